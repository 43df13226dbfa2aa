"""The unit frame every method works in: shift to the centroid, scale to unit RMS distance from it."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def unit_frame(points: np.ndarray) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """(shift, scale, x, y): the centroid, the RMS distance from it, and the contiguous unit-frame
    coordinates x = (X - shift_x) / scale, y = (Y - shift_y) / scale."""
    x0, y0 = points[:, 0], points[:, 1]
    mx, my = x0.mean(), y0.mean()
    x, y = x0 - mx, y0 - my
    scale = float(np.sqrt((x @ x + y @ y) / len(x)))
    x /= scale
    y /= scale
    return np.array([mx, my]), scale, x, y


@dataclass(frozen=True)
class UnitFrame:
    """The unit frame of a point set; the families add their own parameter conversions."""

    shift: np.ndarray
    scale: float
    x: np.ndarray
    y: np.ndarray

    @classmethod
    def of(cls, points: np.ndarray):
        shift, scale, x, y = unit_frame(points)
        return cls(shift=shift, scale=scale, x=x, y=y)

    def to_unit(self, points: np.ndarray) -> np.ndarray:
        return (points - self.shift) / self.scale
