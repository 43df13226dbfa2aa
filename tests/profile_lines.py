"""The lines of an x, y roundness profile as an instrument exports it, for the tests that build files around them."""
from __future__ import annotations

import numpy as np


def circle_lines(radius, n=360, phase=0.0):
    """``n`` points of a circle of ``radius`` mm with 1.5 µm of 3-lobing, from ``phase`` degrees, as 'x,y' lines."""
    t = np.radians(np.arange(n) * 360.0 / n + phase)
    r = radius + 0.0015 * np.cos(3 * t)
    return [f"{x:.7f},{y:.7f}" for x, y in zip(r * np.cos(t), r * np.sin(t))]
