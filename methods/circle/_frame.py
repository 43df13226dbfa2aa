"""Internal normalisation shared by the circle methods.

Every fit works on ``(P - shift) / scale`` with ``shift`` the centroid and ``scale`` the RMS
distance from it, so that a 299 mm circle centred at (1200, 650) mm, or 10^6 mm away, is as well
conditioned as the unit circle. Results are mapped back to data units. The unit-frame coordinates
are kept as two contiguous 1-D arrays ``x``, ``y`` (strided (N, 2) columns are several times slower).
"""
from __future__ import annotations

import math

import numpy as np

from methods._frame import (KernelFrame, UnitFrame, dot, is_point_array, kernel_frame, offer_frame, point_kernels,
                            solve3, take_frame)


_EPS = float(np.finfo(float).eps)


class Frame(UnitFrame):
    """The unit frame with the circle parameters' conversions (xc, yc, R)."""

    def circle_to_unit(self, p) -> np.ndarray:
        """(xc, yc, R) in data units -> unit frame."""
        p = np.asarray(p, dtype=np.float64)
        return np.array([(p[0] - self.shift[0]) / self.scale, (p[1] - self.shift[1]) / self.scale, p[2] / self.scale])

    @property
    def ulp(self) -> float:
        """The rounding of the data's coordinates in the unit frame: eps max(1, |shift| / scale)."""
        return _EPS * max(1.0, max(abs(float(self.shift[0])), abs(float(self.shift[1]))) / self.scale)

    def power(self, k: int) -> float:
        """scale**k for converting objective values to data units; inf/0 (no exception) when out of range."""
        try:
            return float(self.scale) ** k
        except OverflowError:
            return math.inf

    def circle_to_data(self, p) -> tuple[np.ndarray, float]:
        """(xc, yc, R) in the unit frame -> (center, radius) in data units."""
        return np.asarray(p[:2]) * self.scale + self.shift, abs(float(p[2])) * self.scale


def geometric_residuals(u: np.ndarray, p) -> np.ndarray:
    """d_i = sqrt((x_i - xc)^2 + (y_i - yc)^2) - R (roundness paper eq. 3; circle/ellipse paper eq. 8)."""
    return np.hypot(u[:, 0] - p[0], u[:, 1] - p[1]) - p[2]


def kasa_xy(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Kåsa's algebraic fit in the unit frame: least squares of the linear system of eq. 7
    (roundness paper) [2x 2y -1][xc yc w]^T = x^2 + y^2, with w = xc^2 + yc^2 - R^2 (eq. 6).

    From its normal equations (:func:`moments`, :func:`kasa_moments`): on centred, scaled data they are as well
    conditioned as the circle's shape allows, and their sums and 3x3 solve use no BLAS, so a start built on
    them is the same on every CPU (a QR factorisation's Householder updates go through BLAS kernels chosen per
    CPU, and a Nelder–Mead simplex started one ulp away ends after another number of iterations)."""
    return kasa_moments(moments(x, y))


def kasa_unit(u: np.ndarray) -> np.ndarray:
    """:func:`kasa_xy` for an (N, 2) unit-frame array."""
    return kasa_xy(np.ascontiguousarray(u[:, 0]), np.ascontiguousarray(u[:, 1]))


def moments(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """M = Z^T Z / N for Z = [z, x, y, 1], z = x^2 + y^2, in one sweep (unit-frame data: centred and
    scaled, so the moments are O(1) and M is as well conditioned as the circle's shape allows).

    One array of N for z; the six second moments are sums of products (:func:`methods._frame.dot`)."""
    n = len(x)
    z = np.multiply(x, x)
    z += y * y
    zz, zx, zy, xx, yy, xy = dot(z, z), dot(z, x), dot(z, y), dot(x, x), dot(y, y), dot(x, y)
    sx, sy, sz = x.sum(), y.sum(), z.sum()
    return np.array([[zz, zx, zy, sz],
                     [zx, xx, xy, sx],
                     [zy, xy, yy, sy],
                     [sz, sx, sy, float(n)]]) / n


def kasa_moments(m: np.ndarray, ck=None) -> np.ndarray:
    """Kåsa's circle (roundness paper eq. 7: least squares of [2x 2y -1][xc yc w]^T = x^2 + y^2,
    w = xc^2 + yc^2 - R^2) from the moment matrix of :func:`moments`: its 3x3 normal equations
    (``ck``: solved by the compiled ``solve3``, Gaussian elimination with partial pivoting as LAPACK's
    dgesv, without NumPy's per-call overhead; else by the same elimination in Python, :func:`solve3`)."""
    (_, m01, m02, m03), (_, m11, m12, m13), (_, _, m22, m23), (_, _, _, m33) = m.tolist()
    return np.array(kasa_sums(m01, m02, m03, m11, m12, m13, m22, m23, m33, ck))


def kasa_sums(m01, m02, m03, m11, m12, m13, m22, m23, m33, ck=None) -> tuple[float, float, float]:
    """:func:`kasa_moments` from the entries (row, column) of the moment matrix M as plain floats (the
    compiled closed-form path has them so, without the matrix): the unit-frame (xc, yc, R), NaNs when the
    system is singular or gives R^2 <= 0."""
    sol = (ck.solve3 if ck is not None else solve3)(
        (4 * m11, 4 * m12, -2 * m13, 4 * m12, 4 * m22, -2 * m23, -2 * m13, -2 * m23, m33), (2 * m01, 2 * m02, -m03))
    if sol is None:
        return math.nan, math.nan, math.nan
    xc, yc, w = sol
    r2 = xc * xc + yc * yc - w
    return xc, yc, math.sqrt(r2) if r2 > 0 else math.nan




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


def compiled_frame(points):
    """(ck, frame) for the compiled path: the circle kernels and the :class:`methods._frame.KernelFrame` that
    validation offered for ``points`` (pass 1), computed here when none was offered; None on the NumPy path
    (``FITBENCH_KERNELS=numpy``, or data the kernels leave to NumPy: not finite, sums out of range)."""
    ck = point_kernels()
    if ck is None:
        return None
    frame = take_frame(points)
    if isinstance(frame, KernelFrame):
        return ck, frame
    if frame is not None:  # a NumPy frame was offered (data the kernel left to NumPy): leave it for Frame.of
        offer_frame(points, frame)
        return None
    frame = kernel_frame(points, ck) if is_point_array(points) else None
    return (ck, frame) if frame is not None else None


def compiled_moment_means(points, ck, frame: KernelFrame) -> tuple[KernelFrame, tuple]:
    """(frame, (zz, zx, zy, xx, yy, xy, sx, sy, sz)): the distinct entries of M = Z^T Z / N (see
    :func:`compiled_moments`) as plain floats, by the compiled pass 2. The pass returns the data's token:
    if the points changed since ``frame`` was computed, the frame is computed again (pass 1) and the
    moments with it."""
    t, zz, zx, zy, xx, yy, xy, sx, sy, sz = ck.moments(points, frame.cx, frame.cy, frame.scale)
    if t != frame.token:
        frame = kernel_frame(points, ck)
        t, zz, zx, zy, xx, yy, xy, sx, sy, sz = ck.moments(points, frame.cx, frame.cy, frame.scale)
    n = float(points.shape[0])
    return frame, (zz / n, zx / n, zy / n, xx / n, yy / n, xy / n, sx / n, sy / n, sz / n)


def compiled_moments(points, ck, frame: KernelFrame) -> tuple[KernelFrame, np.ndarray]:
    """(frame, M = Z^T Z / N) by the compiled pass 2: Z = [z, x, y, 1] of the centred, scaled data (as
    :func:`moments`); see :func:`compiled_moment_means`."""
    frame, (zz, zx, zy, xx, yy, xy, sx, sy, sz) = compiled_moment_means(points, ck, frame)
    return frame, np.array([[zz, zx, zy, sz],
                            [zx, xx, xy, sx],
                            [zy, xy, yy, sy],
                            [sz, sx, sy, 1.0]])


_NO_COORDINATES = np.empty(0)


def compiled_geometric(points, ck, frame: KernelFrame, p, previous=None):
    """:func:`geometric_normal_equations` by one compiled sweep over the data points (unit-frame circle
    ``p``): (F, J^T J, J^T d, None), None when a point is the centre; with ``previous`` (the unit-frame
    circle before the step) also the actual reduction F(previous) - F(p) free of cancellation
    (:func:`methods.circle.levenberg_marquardt._reduction`): then ((F, J^T J, J^T d, None), reduction)."""
    q = (float(p[0]), float(p[1]), float(p[2]))
    if previous is None:
        out = ck.geometric(points, frame.cx, frame.cy, frame.scale, q)
    else:
        out = ck.geometric(points, frame.cx, frame.cy, frame.scale, q,
                           (float(previous[0]), float(previous[1]), float(previous[2])))
    _, cc, cs, ss_, sc, ss, cd, sd_, sd, dd, reduction, zero_r = out
    if zero_r or not all(map(math.isfinite, (cc, cs, ss_, sc, ss))):
        state = None
    else:
        jtj = np.array([[cc, cs, sc], [cs, ss_, ss], [sc, ss, float(points.shape[0])]])
        state = (dd, jtj, -np.array([cd, sd_, sd]), None)
    return state if previous is None else (state, reduction)


def algebraic_start(x, y) -> np.ndarray:
    """Kåsa's circle as the start of an iterative geometric fit (the roundness paper's choice);
    the unit circle about the centroid when Kåsa's system has no real circle."""
    return start_from_moments(moments(x, y))


def start_from_moments(m: np.ndarray, ck=None) -> np.ndarray:
    """:func:`algebraic_start` from the moment matrix M (``ck``: see :func:`kasa_moments`)."""
    p = kasa_moments(m, ck)
    return p if np.isfinite(p).all() else np.array([0.0, 0.0, 1.0])


#: a Gauss–Newton/LM system whose pivot is below this fraction of max|J^T J| is singular to working precision
#: (compiled path; see :func:`solve_linear`)
GN_PIVOT_RTOL = 24 * _EPS


def solve_linear(ck):
    """solve(A, b) for the 3x3 Gauss–Newton/LM systems: :func:`solve3` (NumPy path), or the compiled
    ``solve3`` (Gaussian elimination with partial pivoting as LAPACK's dgetf2/dtrsm, without NumPy's per-call
    overhead). Both raise np.linalg.LinAlgError when J^T J is singular: LAPACK at an exactly zero pivot;
    the compiled path also at a pivot below GN_PIVOT_RTOL max|J^T J|, the rounding of the sums. (When an
    iterate runs off to a huge circle, every c_i, s_i rounds to the same value and J^T J is singular in
    exact arithmetic; whether its pivot then comes out exactly 0 depends on the summation order: LAPACK on
    NumPy's sums said "singular", the compiled sums left 1e-17 and GN walked on. The tolerance makes that
    verdict independent of the order.)"""
    def solve(a, b):
        if ck is None:  # the NumPy path: the same elimination in Python, singular at an exact zero pivot
            x = solve3(a.ravel().tolist(), b.tolist())
        else:
            x = ck.solve3(tuple(a.ravel().tolist()), tuple(b.tolist()), GN_PIVOT_RTOL)
        if x is None:
            raise np.linalg.LinAlgError("Singular matrix")
        return np.array(x)
    return solve


def geometric_setup(points, start):
    """What Gauss–Newton and LM need, on the compiled or the NumPy path: (frame, p0, sweep, coordinates,
    ck) (``ck``: the compiled kernels, None on the NumPy path; see :func:`solve_linear`).

    ``p0`` is ``start`` (data units) in the unit frame, or Kåsa's start (one moments sweep);
    ``sweep(q)`` = :func:`geometric_normal_equations` at unit-frame q (one sweep; compiled: state[3] is None);
    ``coordinates`` = (x, y) on the NumPy path, None on the compiled path (no unit-frame copy)."""
    compiled = compiled_frame(points)
    if compiled is None:
        frame = Frame.of(points)
        x, y = frame.x, frame.y
        p0 = algebraic_start(x, y) if start is None else frame.circle_to_unit(start)
        work = np.empty((4, len(x)))  # one workspace for every sweep (peak memory: frame + 4 N numbers)
        return frame, p0, lambda q: geometric_normal_equations(x, y, q, work), (x, y), None
    ck, kf = compiled
    if start is None:
        kf, m = compiled_moments(points, ck, kf)  # proves the points unchanged since validation (token)
    else:
        kf = kernel_frame(points, ck) or kf  # a fresh pass 1: the frame of the points as they are now
    frame = Frame(shift=kf.shift, scale=kf.scale, x=_NO_COORDINATES, y=_NO_COORDINATES)
    p0 = start_from_moments(m, ck) if start is None else frame.circle_to_unit(start)
    return frame, p0, lambda q, previous=None: compiled_geometric(points, ck, kf, q, previous), None, ck
