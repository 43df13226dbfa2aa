"""Ellipse family: importing this package registers its methods."""
from methods.ellipse import direct, nelder_mead, orthogonal  # noqa: F401
