"""Internal normalisation shared by the circle methods.

Every fit works on ``(P - shift) / scale`` with ``shift`` the centroid and ``scale`` the RMS
distance from it, so that a 299 mm circle centred at (1200, 650) mm, or 10^6 mm away, is as well
conditioned as the unit circle. Results are mapped back to data units.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Frame:
    shift: np.ndarray
    scale: float

    @classmethod
    def of(cls, points: np.ndarray) -> "Frame":
        shift = points.mean(axis=0)
        centred = points - shift
        scale = float(np.sqrt(np.mean(np.einsum("ij,ij->i", centred, centred))))
        return cls(shift=shift, scale=scale)

    def to_unit(self, points: np.ndarray) -> np.ndarray:
        return (points - self.shift) / self.scale

    def circle_to_unit(self, p) -> np.ndarray:
        """(xc, yc, R) in data units -> unit frame."""
        p = np.asarray(p, dtype=np.float64)
        return np.array([(p[0] - self.shift[0]) / self.scale, (p[1] - self.shift[1]) / self.scale, p[2] / self.scale])

    def circle_to_data(self, p) -> tuple[np.ndarray, float]:
        """(xc, yc, R) in the unit frame -> (center, radius) in data units."""
        return np.asarray(p[:2]) * self.scale + self.shift, abs(float(p[2])) * self.scale


def geometric_residuals(u: np.ndarray, p) -> np.ndarray:
    """d_i = sqrt((x_i - xc)^2 + (y_i - yc)^2) - R (roundness paper eq. 3; circle/ellipse paper eq. 8)."""
    return np.hypot(u[:, 0] - p[0], u[:, 1] - p[1]) - p[2]


def kasa_unit(u: np.ndarray) -> np.ndarray:
    """Kåsa's algebraic fit in the unit frame: least squares of the linear system of eq. 7
    (roundness paper) [2x 2y -1][xc yc w]^T = x^2 + y^2, with w = xc^2 + yc^2 - R^2 (eq. 6)."""
    k = np.empty((u.shape[0], 3))
    k[:, :2] = 2.0 * u
    k[:, 2] = -1.0
    l = np.einsum("ij,ij->i", u, u)
    (xc, yc, w), *_ = np.linalg.lstsq(k, l, rcond=None)
    r2 = xc * xc + yc * yc - w
    return np.array([xc, yc, np.sqrt(r2) if r2 > 0 else np.nan])
