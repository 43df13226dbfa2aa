"""Internal normalisation shared by the circle methods.

Every fit works on ``(P - shift) / scale`` with ``shift`` the centroid and ``scale`` the RMS
distance from it, so that a 299 mm circle centred at (1200, 650) mm, or 10^6 mm away, is as well
conditioned as the unit circle. Results are mapped back to data units. The unit-frame coordinates
are kept as two contiguous 1-D arrays ``x``, ``y`` (strided (N, 2) columns are several times slower).
"""
from __future__ import annotations

import numpy as np

from methods._frame import UnitFrame


class Frame(UnitFrame):
    """The unit frame with the circle parameters' conversions (xc, yc, R)."""

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


def kasa_xy(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Kåsa's algebraic fit in the unit frame: least squares of the linear system of eq. 7
    (roundness paper) [2x 2y -1][xc yc w]^T = x^2 + y^2, with w = xc^2 + yc^2 - R^2 (eq. 6).

    Solved through the R factor of the QR decomposition of [K | L] (as accurate as lstsq on K)."""
    aug = np.empty((len(x), 4))
    aug[:, 0] = 2.0 * x
    aug[:, 1] = 2.0 * y
    aug[:, 2] = -1.0
    aug[:, 3] = x * x + y * y
    r = np.linalg.qr(aug, mode="r")
    if r.shape[0] < 4:  # N = 3: pad with zero rows (R^T R = A^T A still holds)
        r = np.vstack([r, np.zeros((4 - r.shape[0], 4))])
    try:
        xc, yc, w = np.linalg.solve(r[:3, :3], r[:3, 3])
    except np.linalg.LinAlgError:
        return np.full(3, np.nan)
    r2 = xc * xc + yc * yc - w
    return np.array([xc, yc, np.sqrt(r2) if r2 > 0 else np.nan])


def kasa_unit(u: np.ndarray) -> np.ndarray:
    """:func:`kasa_xy` for an (N, 2) unit-frame array."""
    return kasa_xy(np.ascontiguousarray(u[:, 0]), np.ascontiguousarray(u[:, 1]))


def geometric_normal_equations(x, y, p):
    """Residuals and normal equations at p: (F, J^T J, J^T d, (dx, dy, r, d)) for d_i = r_i - R,
    J rows [-(x_i - xc)/r_i, -(y_i - yc)/r_i, -1] (roundness paper eq. 10); None if a point is the centre."""
    dx, dy = x - p[0], y - p[1]
    r = np.sqrt(dx * dx + dy * dy)
    if not r.all():
        return None
    d = r - p[2]
    inv_r = 1.0 / r
    c, s = dx * inv_r, dy * inv_r
    sc, ss = c.sum(), s.sum()
    jtj = np.array([[c @ c, c @ s, sc], [c @ s, s @ s, ss], [sc, ss, float(len(x))]])
    jtd = -np.array([c @ d, s @ d, d.sum()])
    return float(d @ d), jtj, jtd, (dx, dy, r, d)


def algebraic_start(x, y) -> np.ndarray:
    """Kåsa's circle as the start of an iterative geometric fit (the roundness paper's choice);
    the unit circle about the centroid when Kåsa's system has no real circle."""
    p = kasa_xy(x, y)
    return p if np.isfinite(p).all() else np.array([0.0, 0.0, 1.0])
