"""The unit frame every method works in: shift to the centroid, scale to unit RMS distance from it.

Computed without overflow or underflow for any finite float64 data (coordinates up to 1.8e308,
spreads down to the smallest normal number): when the direct sums would leave the normal range, the
data are first scaled by a power of two (exact), so the frame of a circle of radius 3.45e-100 or
1e160 is as accurate as that of the unit circle.

:func:`methods._validation.validate_points` computes the frame of the points it accepts and hands it
to the first :meth:`UnitFrame.of` call on the same array (checked by identity and by the array's
sum), so validation and normalisation are one sweep over the data.

Compiled path (``methods/_compiled.py``): :func:`kernel_frame` computes the shift, the scale and
the unit-frame second moments in ONE sweep (``methods/circle/_ckernels.c`` pass 1) without writing the
unit-frame coordinates; validation offers that :class:`KernelFrame`, the circle fits read the points
through the frame's shift and scale in their own kernel sweeps (each of which returns the data's
``token`` and so proves that the points did not change since validation); :meth:`UnitFrame.of` (the
methods that work on coordinate arrays) computes the NumPy frame, bit for bit the frame those methods had
before the kernels (:meth:`KernelFrame.coordinates` writes them in one sweep, for a family that wants it,
at the cost of last-bit differences in its iterations). Data whose sums leave
(SAFE_LOW, SAFE_HIGH) or are not finite take the NumPy path below, which decides and explains.
"""
from __future__ import annotations

import importlib
import math
import os
import threading
import weakref
from dataclasses import dataclass
from functools import partial
from typing import NamedTuple

import numpy as np

from methods._compiled import kernels

#: squared sums inside (SAFE_LOW, SAFE_HIGH) are computed directly; outside, the data are rescaled first
SAFE_LOW, SAFE_HIGH = 1e-250, 1e250

_handoff = threading.local()


def dot(a: np.ndarray, b: np.ndarray) -> float:
    """sum(a * b) of two 1-D arrays by NumPy's own loops, never BLAS: a BLAS ddot kernel is chosen per CPU
    (OpenBLAS's Haswell and SkylakeX kernels round differently), and a last-bit difference in an objective
    changes the path of a Nelder–Mead simplex, hence its iteration count and status, from one CPU to the next
    (``tests/test_cpu_independence.py``). NumPy's pairwise sum and np.einsum are compiled once for the
    baseline instruction set and give the same bits on every x86-64 CPU; np.einsum needs no temporary array,
    the product-then-sum is cheaper to call for short vectors."""
    if a.size < EINSUM_FROM:
        return float(np.add.reduce(a * b))
    return float(np.einsum("i,i->", a, b))


#: vector length from which :func:`dot` uses np.einsum (no temporary) rather than a product and a pairwise sum
EINSUM_FROM = 8192


def solve3(a, b, rtol: float = 0.0):
    """x of the 3x3 system A x = b (``a``: 9 numbers, row major) by Gaussian elimination with partial pivoting,
    the same operations in the same order as the circle kernel's compiled ``solve3`` (hence the same bits) and as
    LAPACK's dgetf2/dtrsm; None when singular (an exact zero pivot, or with ``rtol`` > 0 one <= rtol max|a_ij|).
    Plain float arithmetic, never BLAS: LAPACK's solve goes through a BLAS kernel chosen per CPU, and a
    last-bit change in a start moves a Nelder–Mead simplex to another iteration count on another CPU."""
    out = solve3_columns(a, [b], rtol)
    return None if out is None else out[0]


def solve3_columns(a, rhs, rtol: float = 0.0):
    """[solve3(a, b, rtol) for b in rhs], or None when singular: the elimination done once for every right-hand
    side (the same operations in the same order on each, hence the same bits as separate solves)."""
    A = [list(a[0:3]), list(a[3:6]), list(a[6:9])]
    B = [list(b) for b in rhs]
    amax = max(abs(v) for v in a)
    for k in range(3):
        piv = k
        for i in range(k + 1, 3):
            if abs(A[i][k]) > abs(A[piv][k]):
                piv = i
        if A[piv][k] == 0.0 or (rtol > 0.0 and not abs(A[piv][k]) > rtol * amax):
            return None
        if piv != k:
            A[k], A[piv] = A[piv], A[k]
            for bb in B:
                bb[k], bb[piv] = bb[piv], bb[k]
        rp = 1.0 / A[k][k]
        for i in range(k + 1, 3):
            lik = A[i][k] * rp
            for j in range(k + 1, 3):
                A[i][j] = A[i][j] - lik * A[k][j]
            for bb in B:
                bb[i] = bb[i] - lik * bb[k]
    out = []
    for bb in B:
        x = bb[:]
        for k in (2, 1, 0):
            x[k] = x[k] / A[k][k]
            for i in range(k):
                x[i] = x[i] - x[k] * A[i][k]
        out.append(x)
    return out


def _pow2_scale(m: float) -> float:
    """A power of two near ``m`` (> 0): dividing by it is exact for normal numbers."""
    return float(np.ldexp(1.0, int(np.frexp(m)[1])))


def unit_frame(points: np.ndarray) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """(shift, scale, x, y): the centroid, the RMS distance from it, and the contiguous unit-frame
    coordinates x = (X - shift_x) / scale, y = (Y - shift_y) / scale.

    ``x`` and ``y`` are the two rows of one (2, N) buffer (``x.base``). ``scale`` is 0 when all
    points are identical (``x``, ``y`` are then zero); it is inf when the spread itself exceeds the
    float64 range."""
    pts = np.asarray(points, dtype=np.float64)
    n = pts.shape[0]
    buf = np.empty((2, n))
    x, y = buf[0], buf[1]
    x[...] = pts[:, 0]  # contiguous copies first: numpy's axis-0 sum of an (N, 2) array is ~50x slower
    y[...] = pts[:, 1]
    with np.errstate(over="ignore", invalid="ignore"):
        total = np.array([x.sum(), y.sum()])
    if np.isfinite(total).all():
        shift = total / n
        x -= shift[0]
        y -= shift[1]
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            ss = dot(x, x) + dot(y, y)
        if SAFE_LOW < ss < SAFE_HIGH:
            scale = float(np.sqrt(ss / n))
            x /= scale
            y /= scale
            return shift, scale, x, y
    # outside the safe range: work on data divided by powers of two (exact), then scale back
    big = float(np.abs(pts).max())
    if big == 0.0:
        buf[:2] = 0.0
        return np.zeros(2), 0.0, x, y
    big = _pow2_scale(big)
    q = pts / big
    qshift = q.sum(axis=0) / n
    np.subtract(q[:, 0], qshift[0], out=x)
    np.subtract(q[:, 1], qshift[1], out=y)
    m = max(float(np.abs(x).max()), float(np.abs(y).max()))
    if m == 0.0:
        return qshift * big, 0.0, x, y
    p2 = _pow2_scale(m)
    x /= p2
    y /= p2
    s = float(np.sqrt((dot(x, x) + dot(y, y)) / n))
    x /= s
    y /= s
    with np.errstate(over="ignore"):
        return qshift * big, s * p2 * big, x, y


#: the compiled module of the point-set sweeps (frame, moments, residuals; used by every family's frame)
KERNEL_MODULE = "methods.circle._ckernels"


_loaded: dict = {}
#: reads FITBENCH_KERNELS for :func:`point_kernels` (chosen at its first call, see :func:`_choice_reader`)
_read_choice = None


def _choice_reader():
    """The compiled kernels' ``env_value`` (C ``getenv``: the environment os.environ writes through, without the
    KeyError os.environ.get raises and catches for an unset variable, which cost more than the kernel sweeps
    of a small fit), or os.environ.get where the kernels are not built."""
    global _read_choice
    try:  # the kernel module by its name, as point_kernels loads it (kernels(KERNEL_MODULE))
        env_value = importlib.import_module(KERNEL_MODULE).env_value
    except (ImportError, AttributeError):
        _read_choice = partial(os.environ.get, "FITBENCH_KERNELS")
    else:
        _read_choice = partial(env_value, b"FITBENCH_KERNELS")
    return _read_choice


def point_kernels():
    """The compiled point-set kernels, or None on the NumPy reference path (``FITBENCH_KERNELS=numpy``);
    the choice is read from the environment at every call (cached per value: a fit calls this thrice)."""
    choice = (_read_choice or _choice_reader())()
    try:
        return _loaded[choice]
    except KeyError:
        _loaded[choice] = ck = kernels(KERNEL_MODULE)
        return ck


def is_point_array(points) -> bool:
    """True for a C-contiguous float64 (N, 2) array, the only input the kernels take."""
    return (isinstance(points, np.ndarray) and points.dtype == np.float64 and points.ndim == 2
            and points.shape[1] == 2 and points.flags.c_contiguous)


class KernelFrame(NamedTuple):
    """The unit frame from the compiled pass 1, without the coordinates: shift (cx, cy), scale, the data's
    token (sum of the raw coordinates in the kernels' order) and the unit-frame means sxx = mean(x^2),
    syy = mean(y^2), sxy = mean(x y) (x, y centred and scaled). Immutable (a named tuple: built in a third
    of a frozen dataclass's time, once per fit)."""

    cx: float
    cy: float
    scale: float
    token: float
    sxx: float
    syy: float
    sxy: float

    @property
    def shift(self) -> np.ndarray:
        return np.array([self.cx, self.cy])

    def coordinates(self, points: np.ndarray, ck):
        """(shift, scale, x, y) as :func:`unit_frame` returns them (the rows of a (2, N) buffer), written in one
        sweep; None when the points changed since this frame was computed (token differs)."""
        buf = np.empty((2, points.shape[0]))
        if ck.unit_coords(points, self.cx, self.cy, self.scale, buf) != self.token:
            return None
        return self.shift, self.scale, buf[0], buf[1]


def kernel_frame(points: np.ndarray, ck) -> KernelFrame | None:
    """Pass 1 (compiled): the frame of ``points`` (a C-contiguous float64 (N, 2) array), or None when the
    data are not finite or their centred sum of squares leaves (SAFE_LOW, SAFE_HIGH) (the NumPy path then
    decides: power-of-two prescaling, or the error message)."""
    token, cx, cy, cxx, cyy, cxy = ck.frame_stats(points)
    ss = cxx + cyy
    if not (math.isfinite(token) and math.isfinite(cx) and math.isfinite(cy) and SAFE_LOW < ss < SAFE_HIGH):
        return None
    return KernelFrame(cx, cy, math.sqrt(ss / points.shape[0]), token, cxx / ss, cyy / ss, cxy / ss)


def offer_frame(points: np.ndarray, frame: tuple, total: float | None = None) -> None:
    """Hand the frame computed during validation to the next :meth:`UnitFrame.of` of ``points``
    (``total`` = points.sum() if the caller has it)."""
    _handoff.value = (weakref.ref(points), float(points.sum()) if total is None else float(total), frame)


def take_frame(points: np.ndarray):
    """The frame offered for this very array (same object and unchanged sum), else None; consumed once."""
    offered = getattr(_handoff, "value", None)
    _handoff.value = None
    if offered is None or offered[0]() is not points:
        return None
    if isinstance(offered[2], KernelFrame):  # its token is checked by the first sweep that reads the points
        return offered[2]
    total = float(points.sum())
    if not (total == offered[1] or (np.isnan(total) and np.isnan(offered[1]))):
        return None
    return offered[2]


@dataclass(frozen=True)
class UnitFrame:
    """The unit frame of a point set; the families add their own parameter conversions."""

    shift: np.ndarray
    scale: float
    x: np.ndarray
    y: np.ndarray

    @classmethod
    def of(cls, points: np.ndarray):
        frame = take_frame(points)
        if isinstance(frame, KernelFrame):
            # the methods that work on coordinate arrays get the NumPy frame, the same bits as before the
            # kernels (their iterations, and so their statuses, do not move by the last bit of the shift)
            frame = None
        shift, scale, x, y = frame if frame is not None else unit_frame(points)
        return cls(shift=shift, scale=scale, x=x, y=y)

    def to_unit(self, points: np.ndarray) -> np.ndarray:
        return (points - self.shift) / self.scale
