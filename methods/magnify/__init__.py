"""Magnified contouring-error plots (Ibaraki & Matsubara, Precision Engineering 33 (2009) 322-326):
the conventional nearest-point magnification and the contour-parallel-offset algorithm. Importing this
package registers the family ``magnify``."""
from methods.magnify import algorithms  # noqa: F401
from methods.magnify.data import MagnifyInput, continuity, self_intersections

__all__ = ["MagnifyInput", "continuity", "self_intersections"]
