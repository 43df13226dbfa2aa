"""Synthetic data with known truth."""
from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import Field

#: The generators' parameter types (their annotations are what a study's values are checked against before any
#: row runs, ``datasets.sources.DataSource.parameter_types``). Lengths in the unit of the data, angles in degrees.
Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]
Count = Annotated[int, Field(ge=1)]
Degrees = float
ArcDegrees = Annotated[float, Field(gt=0, le=360)]
Point = tuple[float, float]


def circle_points(center=(0.0, 0.0), radius=1.0, n=100, *, arc=(0.0, 2 * np.pi), noise=0.0,
                  rng: np.random.Generator | None = None, endpoint=False) -> np.ndarray:
    """``n`` points on the circle (optionally an arc ``(start, end)`` in radians), with radial
    Gaussian noise of standard deviation ``noise`` (data units) drawn from ``rng``."""
    t = np.linspace(arc[0], arc[1], n, endpoint=endpoint)
    r = np.full(n, float(radius))
    if noise:
        if rng is None:
            raise ValueError("noise needs an explicit numpy Generator (rng) for reproducibility")
        r = r + rng.normal(0.0, noise, n)
    return np.column_stack([center[0] + r * np.cos(t), center[1] + r * np.sin(t)])


def ellipse_points(center=(0.0, 0.0), semi_axes=(2.0, 1.0), angle=0.0, n=100, *, arc=(0.0, 2 * np.pi),
                   noise=0.0, rng: np.random.Generator | None = None, endpoint=False) -> np.ndarray:
    """``n`` points x = c + R(angle) (a cos t, b sin t) for t evenly spaced on ``arc``, with Gaussian
    noise of standard deviation ``noise`` added to both coordinates (drawn from ``rng``)."""
    t = np.linspace(arc[0], arc[1], n, endpoint=endpoint)
    a, b = semi_axes
    u, v = a * np.cos(t), b * np.sin(t)
    c, s = np.cos(angle), np.sin(angle)
    pts = np.column_stack([center[0] + c * u - s * v, center[1] + s * u + c * v])
    if noise:
        if rng is None:
            raise ValueError("noise needs an explicit numpy Generator (rng) for reproducibility")
        pts = pts + rng.normal(0.0, noise, pts.shape)
    return pts


def _exact_key(*values):
    """A dict key equal only for values that give the same bits (None for a value that is not a finite int
    or float, or a list/tuple of them): ints and floats apart, -0.0 apart from 0.0."""
    key = []
    for v in values:
        if type(v) in (list, tuple):
            sub = _exact_key(*v)
            if sub is None:
                return None
            key.append(sub)
        elif type(v) is float and math.isfinite(v):
            key.append(v.hex())
        elif type(v) is int:
            key.append(v)
        else:
            return None
    return tuple(key)


#: noise-free arcs of :func:`_circle` by their exact parameters (read-only arrays; a study draws thousands of
#: repetitions of one data set: the angles, cosines and sines are computed once)
_ARCS: dict = {}


def _noise_free_circle(center, radius, n, arc_deg, arc_start_deg) -> np.ndarray:
    """The points of :func:`_circle` before noise (a read-only array, shared: add to it, never write into it)."""
    key = _exact_key(center, radius, n, arc_deg, arc_start_deg)
    pts = _ARCS.get(key) if key is not None else None
    if pts is None:
        start = np.radians(arc_start_deg)
        span = np.radians(arc_deg)
        pts = circle_points(center, radius, n, arc=(start, start + span), endpoint=not arc_deg >= 360.0)
        pts.flags.writeable = False
        if key is not None:
            if len(_ARCS) >= 64:
                _ARCS.clear()
            _ARCS[key] = pts
    return pts


def _circle(rng, *, center: Point = (0.0, 0.0), radius: Positive = 1.0, n: Count = 100, arc_deg: ArcDegrees = 360.0,
            arc_start_deg: Degrees = 0.0, noise: NonNegative = 0.0,
            noise_model: Literal["isotropic", "radial"] = "isotropic"):
    """Points on a circle (or arc of ``arc_deg`` degrees); Gaussian noise of s.d. ``noise`` per
    coordinate ('isotropic') or along the radius ('radial')."""
    if noise_model == "radial":
        start = np.radians(arc_start_deg)
        span = np.radians(arc_deg)
        pts = circle_points(center, radius, n, arc=(start, start + span), noise=noise, rng=rng,
                            endpoint=not arc_deg >= 360.0)
    elif noise_model == "isotropic":
        pts = _noise_free_circle(center, radius, n, arc_deg, arc_start_deg)
        pts = pts + rng.normal(0.0, noise, pts.shape) if noise else pts.copy()
    else:
        raise ValueError(f"noise_model must be 'isotropic' or 'radial', got {noise_model!r}")
    return pts, {"family": "circle", "center": tuple(map(float, center)), "radius": float(radius)}


def _ellipse(rng, *, center: Point = (0.0, 0.0), semi_axes: tuple[Positive, Positive] = (2.0, 1.0),
             angle_deg: Degrees = 0.0, n: Count = 100, arc_deg: ArcDegrees = 360.0, arc_start_deg: Degrees = 0.0,
             noise: NonNegative = 0.0):
    """Points on an ellipse (or arc), Gaussian noise of s.d. ``noise`` per coordinate."""
    start = np.radians(arc_start_deg)
    full = arc_deg >= 360.0
    pts = ellipse_points(center, semi_axes, np.radians(angle_deg), n, arc=(start, start + np.radians(arc_deg)),
                         noise=noise, rng=rng if noise else None, endpoint=not full)
    a, b = float(max(semi_axes)), float(min(semi_axes))
    angle = np.radians(angle_deg) + (0.0 if semi_axes[0] >= semi_axes[1] else np.pi / 2)
    return pts, {"family": "ellipse", "center": tuple(map(float, center)), "semi_axes": (a, b),
                 "angle": float(np.mod(angle, np.pi))}


#: synthetic generators by name: f(rng, **params) -> (points, truth)
GENERATORS = {"circle": _circle, "ellipse": _ellipse}


def generate(name: str, rng: np.random.Generator, **params):
    """Points and truth from a registered generator (``GENERATORS``)."""
    try:
        gen = GENERATORS[name]
    except KeyError:
        raise ValueError(f"unknown generator {name!r}; known: {', '.join(GENERATORS)}") from None
    return gen(rng, **params)
