"""The unit frame every method works in: shift to the centroid, scale to unit RMS distance from it.

Computed without overflow or underflow for any finite float64 data (coordinates up to 1.8e308,
spreads down to the smallest normal number): when the direct sums would leave the normal range, the
data are first scaled by a power of two (exact), so the frame of a circle of radius 3.45e-100 or
1e160 is as accurate as that of the unit circle.

:func:`methods._validation.validate_points` computes the frame of the points it accepts and hands it
to the first :meth:`UnitFrame.of` call on the same array (checked by identity and by the array's
sum), so validation and normalisation are one sweep over the data.
"""
from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass

import numpy as np

#: squared sums inside (SAFE_LOW, SAFE_HIGH) are computed directly; outside, the data are rescaled first
SAFE_LOW, SAFE_HIGH = 1e-250, 1e250

_handoff = threading.local()


def dot(a: np.ndarray, b: np.ndarray) -> float:
    """sum(a * b) of two 1-D arrays by NumPy's own single-threaded SIMD loop (np.einsum), not BLAS:
    on a loaded machine a threaded BLAS ddot of 10^5 numbers can take 100x longer, and the sum of
    products needs no temporary array. Short vectors go to BLAS, whose call overhead is lower and
    which does not thread them."""
    if a.size < EINSUM_FROM:  # below BLAS's threading threshold its call is cheaper (3 us vs 7 us)
        return float(a @ b)
    return float(np.einsum("i,i->", a, b))


#: vector length from which :func:`dot` uses np.einsum rather than BLAS
EINSUM_FROM = 8192


def _pow2_scale(m: float) -> float:
    """A power of two near ``m`` (> 0): dividing by it is exact for normal numbers."""
    return float(np.ldexp(1.0, int(np.frexp(m)[1])))


def unit_frame(points: np.ndarray) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """(shift, scale, x, y): the centroid, the RMS distance from it, and the contiguous unit-frame
    coordinates x = (X - shift_x) / scale, y = (Y - shift_y) / scale.

    ``x`` and ``y`` are the first two rows of one (3, N) buffer (``x.base``); the third row is free
    for a caller's use (the algebraic circle fits put z = x^2 + y^2 there). ``scale`` is 0 when all
    points are identical (``x``, ``y`` are then zero); it is inf when the spread itself exceeds the
    float64 range."""
    pts = np.asarray(points, dtype=np.float64)
    n = pts.shape[0]
    buf = np.empty((3, n))
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
        shift, scale, x, y = frame if frame is not None else unit_frame(points)
        return cls(shift=shift, scale=scale, x=x, y=y)

    def to_unit(self, points: np.ndarray) -> np.ndarray:
        return (points - self.shift) / self.scale
