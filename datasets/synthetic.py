"""Synthetic data with known truth."""
from __future__ import annotations

import numpy as np


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
