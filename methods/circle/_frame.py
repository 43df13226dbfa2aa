"""Internal normalisation shared by the circle methods.

Every fit works on ``(P - shift) / scale`` with ``shift`` the centroid and ``scale`` the RMS
distance from it, so that a 299 mm circle centred at (1200, 650) mm, or 10^6 mm away, is as well
conditioned as the unit circle. Results are mapped back to data units. The unit-frame coordinates
are kept as two contiguous 1-D arrays ``x``, ``y`` (strided (N, 2) columns are several times slower).
"""
from __future__ import annotations

import numpy as np

from methods._frame import UnitFrame, dot


class Frame(UnitFrame):
    """The unit frame with the circle parameters' conversions (xc, yc, R)."""

    def circle_to_unit(self, p) -> np.ndarray:
        """(xc, yc, R) in data units -> unit frame."""
        p = np.asarray(p, dtype=np.float64)
        return np.array([(p[0] - self.shift[0]) / self.scale, (p[1] - self.shift[1]) / self.scale, p[2] / self.scale])

    @property
    def ulp(self) -> float:
        """The rounding of the data's coordinates in the unit frame: eps max(1, |shift| / scale)."""
        return float(np.finfo(float).eps) * max(1.0, float(np.abs(self.shift).max()) / self.scale)

    def power(self, k: int) -> float:
        """scale**k for converting objective values to data units; inf/0 (no exception) when out of range."""
        with np.errstate(over="ignore", under="ignore"):
            return float(np.float64(self.scale) ** k)

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


def _buffer(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The (3, N) buffer whose rows 0, 1 are x, y (the unit frame's layout), or a new one."""
    base = x.base
    if (isinstance(base, np.ndarray) and base.shape == (3, len(x)) and base.flags.c_contiguous
            and np.shares_memory(base[0], x) and x.ctypes.data == base[0].ctypes.data
            and y.ctypes.data == base[1].ctypes.data):
        return base
    buf = np.empty((3, len(x)))
    buf[0], buf[1] = x, y
    return buf


def moments(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """M = Z^T Z / N for Z = [z, x, y, 1], z = x^2 + y^2, in one sweep (unit-frame data: centred and
    scaled, so the moments are O(1) and M is as well conditioned as the circle's shape allows).

    z is written into the free third row of the frame's buffer; the six second moments are sums of
    products (:func:`methods._frame.dot`, no temporaries)."""
    n = len(x)
    buf = _buffer(x, y)
    z = buf[2]
    np.multiply(x, x, out=z)
    z += y * y
    zz, zx, zy, xx, yy, xy = dot(z, z), dot(z, x), dot(z, y), dot(x, x), dot(y, y), dot(x, y)
    sx, sy, sz = buf.sum(axis=1)
    return np.array([[zz, zx, zy, sz],
                     [zx, xx, xy, sx],
                     [zy, xy, yy, sy],
                     [sz, sx, sy, float(n)]]) / n


def kasa_moments(m: np.ndarray) -> np.ndarray:
    """Kåsa's circle (roundness paper eq. 7: least squares of [2x 2y -1][xc yc w]^T = x^2 + y^2,
    w = xc^2 + yc^2 - R^2) from the moment matrix of :func:`moments`: its 3x3 normal equations."""
    ata = np.array([[4 * m[1, 1], 4 * m[1, 2], -2 * m[1, 3]],
                    [4 * m[1, 2], 4 * m[2, 2], -2 * m[2, 3]],
                    [-2 * m[1, 3], -2 * m[2, 3], m[3, 3]]])
    atl = np.array([2 * m[0, 1], 2 * m[0, 2], -m[0, 3]])
    try:
        xc, yc, w = np.linalg.solve(ata, atl)
    except np.linalg.LinAlgError:
        return np.full(3, np.nan)
    r2 = xc * xc + yc * yc - w
    return np.array([xc, yc, np.sqrt(r2) if r2 > 0 else np.nan])


def geometric_normal_equations(x, y, p, work: np.ndarray | None = None):
    """Residuals and normal equations at p in one sweep: (F, J^T J, J^T d, (c, s, r, d)) for
    d_i = r_i - R, J rows [-c_i, -s_i, -1], c_i = (x_i - xc)/r_i, s_i = (y_i - yc)/r_i
    (roundness paper eq. 10); None if a point is the centre. ``work``: an optional (4, N) array the
    rows c, s, d, r are written into (an iteration reuses it: no allocation per sweep); six sums of
    products and three sums."""
    n = len(x)
    if work is None:
        work = np.empty((4, n))
    c, s, d, r = work
    np.subtract(x, p[0], out=c)
    np.subtract(y, p[1], out=s)
    np.multiply(c, c, out=r)
    np.multiply(s, s, out=d)
    r += d
    np.sqrt(r, out=r)
    with np.errstate(divide="ignore", invalid="ignore"):
        c /= r
        s /= r
    np.subtract(r, p[2], out=d)
    cc, cs, ss_, cd, sd_, dd = dot(c, c), dot(c, s), dot(s, s), dot(c, d), dot(s, d), dot(d, d)
    sc, ss, sd = work[:3].sum(axis=1)
    if not np.isfinite([cc, cs, ss_, sc, ss]).all():
        return None
    jtj = np.array([[cc, cs, sc], [cs, ss_, ss], [sc, ss, float(n)]])
    jtd = -np.array([cd, sd_, sd])
    return dd, jtj, jtd, (c, s, r, d)


def algebraic_start(x, y) -> np.ndarray:
    """Kåsa's circle as the start of an iterative geometric fit (the roundness paper's choice);
    the unit circle about the centroid when Kåsa's system has no real circle."""
    p = kasa_moments(moments(x, y))
    return p if np.isfinite(p).all() else np.array([0.0, 0.0, 1.0])
