"""Low-level geometry shared by the zone methods (:mod:`methods.circle._zone`) and their global stage
(:mod:`methods.circle._global`): radii about a centre, and whether two small convex hulls of unit contact
directions meet (the alternation / surrounding test of their optimality conditions). Below both modules:
it imports neither, so ``_zone`` -> ``_global`` -> ``_geometry`` runs one way.
"""
from __future__ import annotations

import numpy as np


def radii(x: np.ndarray, y: np.ndarray, c) -> np.ndarray:
    """sqrt((x - cx)^2 + (y - cy)^2), in place: two arrays of N at most (the same operations)."""
    dx = x - c[0]
    dy = y - c[1]
    dx *= dx
    dy *= dy
    dx += dy
    return np.sqrt(dx, out=dx)


def _inside_triangle(p, a, b, c, tol=1e-12) -> bool:
    """p in the closed triangle abc (2-D points)."""
    def cross(o, u, v):
        return (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])
    d1, d2, d3 = cross(a, b, p), cross(b, c, p), cross(c, a, p)
    return not ((min(d1, d2, d3) < -tol) and (max(d1, d2, d3) > tol))


def _segments_cross(a, b, c, d, tol=1e-12) -> bool:
    """Closed segments ab and cd intersect."""
    def cross(o, u, v):
        return (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])
    d1, d2, d3, d4 = cross(c, d, a), cross(c, d, b), cross(a, b, c), cross(a, b, d)
    return d1 * d2 <= tol and d3 * d4 <= tol


def hulls_meet(u: np.ndarray, v: np.ndarray) -> bool:
    """Do conv(u) and conv(v) intersect? u, v: unit direction vectors (rows) of up to 3 points each;
    the cases of the minimum-zone (2+2, 3+1, 1+3) and MIC/MCC (0 against 2 or 3 directions)."""
    if len(u) == 2 and len(v) == 2:
        return _segments_cross(u[0], u[1], v[0], v[1])
    if len(u) == 3 and len(v) == 1:
        return _inside_triangle(v[0], *u)
    if len(u) == 1 and len(v) == 3:
        return _inside_triangle(u[0], *v)
    if len(u) == 2 and len(v) == 1:
        return _segments_cross(u[0], u[1], v[0], v[0])
    if len(u) == 1 and len(v) == 2:
        return _segments_cross(v[0], v[1], u[0], u[0])
    return False
