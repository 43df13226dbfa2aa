"""Shared input validation: every method's points pass through :func:`validate_points`."""
from __future__ import annotations

import math

import numpy as np

from methods._errors import InvalidInputError
from methods._frame import dot, kernel_frame, offer_frame, point_kernels, unit_frame

#: Singular-value ratio (smaller / larger principal spread) below which a point set counts as
#: collinear; raised to the rounding of the coordinates themselves (8 eps max|X| / spread) when that
#: is larger, so the test is scale-free: it depends on the shape of the data, not on their unit.
COLLINEAR_RTOL = 1e-12
EPS = float(np.finfo(float).eps)
_FLOAT64 = np.dtype(np.float64)


def _as_array(points, who: str) -> np.ndarray:
    """The points as a float64 array, honouring masks and column names; complex input refused.

    * a NumPy masked array: rows with a masked coordinate are dropped (the fit sees only unmasked
      points; residuals follow the kept points in their order);
    * a pandas DataFrame (or anything with ``columns``) with columns named x and y (any case): used
      by name, whatever their order (refused when it also has a z column that varies: the points are then not
      in the x, y plane, and which two coordinates hold the curve is the caller's choice); otherwise its columns
      by position;
    * complex numbers are refused (their imaginary part would be silently lost)."""
    if hasattr(points, "columns") and hasattr(points, "to_numpy"):
        names = [str(c).strip().lower() for c in points.columns]
        if "x" in names and "y" in names:
            if "z" in names:
                _refuse_varying_z(points, names, who)
            points = points.iloc[:, [names.index("x"), names.index("y")]]
        points = points.to_numpy()
    if isinstance(points, np.ma.MaskedArray):
        mask = np.ma.getmaskarray(points)
        data = np.asarray(points.data)
        if mask.any():
            if data.ndim != 2 or data.shape[1] != 2:
                raise InvalidInputError(f"{who}points must be an (N, 2) array of x, y; got shape {data.shape}")
            data = data[~mask.any(axis=1)]
        points = data
    try:
        raw = np.asarray(points) if not isinstance(points, np.ndarray) else points
    except ValueError:  # NumPy refuses a ragged nested list ("inhomogeneous shape")
        raise InvalidInputError(f"{who}points are ragged (rows of different lengths); pass an (N, 2) array of x, y, "
                                "one row per point") from None
    if np.iscomplexobj(raw) or (raw.dtype == object and any(isinstance(v, complex) for v in raw.ravel()[:1000])):
        raise InvalidInputError(f"{who}points are complex numbers; pass real x, y columns "
                                "(e.g. numpy.column_stack([z.real, z.imag]))")
    try:
        return np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{who}points are not numeric ({exc}); pass an (N, 2) array of x, y") from None


def _refuse_varying_z(frame, names: list[str], who: str) -> None:
    """Refuse x, y, z columns whose z varies by more than 1e-9 of the x, y extent (a curve in another plane, or
    tilted: its x, y projection is not the curve); a constant z (a circle measured at one height) is ignored."""
    try:
        xyz = frame.iloc[:, [names.index("x"), names.index("y"), names.index("z")]].to_numpy(dtype=np.float64)
    except (TypeError, ValueError):
        return  # not numbers: the conversion below says so
    with np.errstate(invalid="ignore", over="ignore"):
        spread = np.nanmax(xyz, axis=0) - np.nanmin(xyz, axis=0) if len(xyz) else np.zeros(3)
    if np.isfinite(spread).all() and spread[2] > 1e-9 * max(spread[0], spread[1]):
        raise InvalidInputError(f"{who}the points have x, y and z columns and z varies ({spread[2]:.6g} against "
                                f"{spread[0]:.6g} in x and {spread[1]:.6g} in y): they are not in the x, y plane; "
                                "pass the two coordinates of the curve's plane, e.g. points[['x', 'z']]")


def validate_points(points, *, min_points: int = 3, method: str = "") -> np.ndarray:
    """Return ``points`` as a C-contiguous float64 (N, 2) array or raise :class:`InvalidInputError`.

    Refuses: wrong shape, complex numbers, NaN/inf, fewer than ``min_points`` points, all points
    identical, all points on one straight line. Masked arrays lose their masked rows, DataFrame
    columns named x, y are taken by name (see :func:`_as_array`).

    Scale-free at any float64 magnitude: identity and collinearity are decided on the unit frame
    (:func:`methods._frame.unit_frame`, computed without overflow or underflow), which is then handed
    to the method's own :meth:`UnitFrame.of` so that the data are normalised once."""
    if (type(points) is np.ndarray and points.dtype == _FLOAT64 and points.ndim == 2 and points.shape[1] == 2
            and points.shape[0] >= min_points and points.flags.c_contiguous):
        arr = points  # what the conversions and shape checks below return for such an array: itself
    else:
        arr = _checked_array(points, min_points, method)
    ck = point_kernels()
    if ck is not None and _clearly_valid(arr, ck):
        return arr
    who = f"{method}: " if method else ""
    n = arr.shape[0]
    with np.errstate(over="ignore", invalid="ignore"):
        total = arr.sum()
    if not np.isfinite(total):  # one cheap sweep; the elementwise test only when it fails
        bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
        if bad.size:
            raise InvalidInputError(
                f"{who}{bad.size} point(s) contain NaN or inf (first at index {bad[0]}); remove or repair them")
    shift, scale, x, y = unit_frame(arr)
    if not np.isfinite(scale):
        raise InvalidInputError(f"{who}the points' spread exceeds the float64 range (~1.8e308); rescale the data")
    coord = float(np.max(np.abs(shift)))
    if scale <= 64 * EPS * coord or scale == 0.0:
        if scale == 0.0 or bool((arr == arr[0]).all()):
            raise InvalidInputError(f"{who}all {n} points are identical; a curve needs points spread along it")
    # principal spreads of the unit-frame data (trace = N): all O(1) numbers, no under/overflow
    sxx, syy, sxy = dot(x, x) / n, dot(y, y) / n, dot(x, y) / n
    big = 0.5 * (sxx + syy) + float(np.hypot(0.5 * (sxx - syy), sxy))
    small = max(sxx * syy - sxy * sxy, 0.0) / big
    rtol = max(COLLINEAR_RTOL, 8 * EPS * coord / scale)
    if small <= 1e-8 * big:  # det suffers cancellation: measure the spread across the principal axis
        theta = 0.5 * np.arctan2(2 * sxy, sxx - syy)
        across = np.cos(theta) * y - np.sin(theta) * x
        small = dot(across, across) / n
    if small <= rtol * rtol * big:
        raise InvalidInputError(f"{who}all {n} points lie on one straight line (to {rtol:.0e} of their spread); "
                                "no circle or ellipse passes through them")
    offer_frame(arr, (shift, scale, x, y), total)
    return arr


def _checked_array(points, min_points: int, method: str) -> np.ndarray:
    """The points as a C-contiguous float64 (N, 2) array of at least ``min_points`` rows (:func:`_as_array`),
    or the error saying what is wrong with their shape or number."""
    who = f"{method}: " if method else ""
    arr = _as_array(points, who)
    if arr.ndim != 2 or arr.shape[1] != 2:
        hint = " (it looks transposed: pass points.T)" if arr.ndim == 2 and arr.shape[0] == 2 else ""
        raise InvalidInputError(f"{who}points must be an (N, 2) array of x, y; got shape {arr.shape}{hint}")
    n = arr.shape[0]
    masked = " after dropping masked points" if isinstance(points, np.ma.MaskedArray) else ""
    if n < min_points:
        raise InvalidInputError(f"{who}needs at least {min_points} points, got {n}{masked}")
    return np.ascontiguousarray(arr)


def _clearly_valid(arr: np.ndarray, ck) -> bool:
    """The compiled path of :func:`validate_points` (one sweep, ``methods/circle/_ckernels.c`` pass 1): True,
    and the frame offered to the method, when the points are finite, in the kernels' range, clearly not
    identical and clearly not collinear by the same rules as below; anything else (a refusal, a borderline
    case, sums out of range) returns False and the NumPy path decides and explains."""
    frame = kernel_frame(arr, ck)
    if frame is None:
        return False
    coord = max(abs(frame.cx), abs(frame.cy))
    if frame.scale <= 64 * EPS * coord:
        return False
    sxx, syy, sxy = frame.sxx, frame.syy, frame.sxy
    big = 0.5 * (sxx + syy) + math.hypot(0.5 * (sxx - syy), sxy)
    small = max(sxx * syy - sxy * sxy, 0.0) / big
    rtol = max(COLLINEAR_RTOL, 8 * EPS * coord / frame.scale)
    if small <= 1e-8 * big or small <= rtol * rtol * big:
        return False
    offer_frame(arr, frame, frame.token)
    return True


def check_choice(name: str, value, choices, method: str = ""):
    """Refuse a parameter value outside ``choices`` with a message listing them."""
    if value not in choices:
        raise InvalidInputError(f"{method}: parameter {name}={value!r} is not one of {', '.join(map(repr, choices))}")
    return value


def check_positive(name: str, value, method: str = "", allow_zero: bool = False):
    """Refuse a non-numeric, non-finite or non-positive tolerance/count parameter."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{method}: parameter {name}={value!r} is not a number") from None
    if not np.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise InvalidInputError(f"{method}: parameter {name}={value!r} must be a positive number")
    return value


def check_vector(name: str, value, length: int, method: str = "") -> np.ndarray | None:
    """Parse an optional parameter vector (start point, simplex steps) of a given length."""
    if value is None:
        return None
    try:
        vec = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{method}: parameter {name}={value!r} is not a list of {length} numbers") from None
    if vec.size != length or not np.isfinite(vec).all():
        raise InvalidInputError(f"{method}: parameter {name} needs {length} finite numbers, got {value!r}")
    return vec
