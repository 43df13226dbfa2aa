"""Shared input validation: every method's points pass through :func:`validate_points`."""
from __future__ import annotations

import numpy as np

from methods._errors import InvalidInputError

#: Singular-value ratio below which a point set counts as collinear (rounding level of float64).
COLLINEAR_RTOL = 1e-12


def validate_points(points, *, min_points: int = 3, method: str = "") -> np.ndarray:
    """Return ``points`` as a C-contiguous float64 (N, 2) array or raise :class:`InvalidInputError`.

    Refuses: wrong shape, NaN/inf, fewer than ``min_points`` points, all points identical,
    all points on one straight line. O(N): the eigenvalues of the 2x2 scatter matrix decide identity and collinearity.
    """
    who = f"{method}: " if method else ""
    try:
        arr = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{who}points are not numeric ({exc}); pass an (N, 2) array of x, y") from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        hint = " (it looks transposed: pass points.T)" if arr.ndim == 2 and arr.shape[0] == 2 else ""
        raise InvalidInputError(f"{who}points must be an (N, 2) array of x, y; got shape {arr.shape}{hint}")
    n = arr.shape[0]
    if n < min_points:
        raise InvalidInputError(f"{who}needs at least {min_points} points, got {n}")
    if not np.isfinite(arr).all():
        bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
        raise InvalidInputError(
            f"{who}{bad.size} point(s) contain NaN or inf (first at index {bad[0]}); remove or repair them")
    x, y = arr[:, 0], arr[:, 1]
    dx, dy = x - x.mean(), y - y.mean()
    sxx, syy, sxy = float(dx @ dx), float(dy @ dy), float(dx @ dy)
    # eigenvalues of the 2x2 scatter matrix in closed form (largest first)
    half_trace, root = 0.5 * (sxx + syy), float(np.hypot(0.5 * (sxx - syy), sxy))
    big, small = half_trace + root, max(sxx * syy - sxy * sxy, 0.0) / max(half_trace + root, np.finfo(float).tiny)
    if big <= 0.0:
        raise InvalidInputError(f"{who}all {n} points are identical; a curve needs points spread along it")
    if small <= (COLLINEAR_RTOL ** 2) * big:
        raise InvalidInputError(f"{who}all {n} points lie on one straight line; no circle or ellipse passes through them")
    return np.ascontiguousarray(arr)


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


def read_text_file(path, *, error=InvalidInputError, missing_hint: str = "") -> str:
    """A text file's content, or ``error`` with one line saying why it cannot be read."""
    try:
        with open(path, encoding="utf-8-sig") as fh:
            return fh.read()
    except FileNotFoundError:
        raise error(f"{path}: no such file{f' ({missing_hint})' if missing_hint else ''}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"{path}: cannot be read as text ({exc})") from None


def read_table(path, *, no_data_hint: str = "", keep_default_na: bool = True, skip_rows: int = 0):
    """A delimited text table (comma, semicolon, tab or whitespace separated; blank and '#' lines skipped;
    ``skip_rows`` preamble lines dropped; a semicolon or tab file may use decimal commas, which are
    turned into points) as a DataFrame of strings, with the file's line number of each data row.
    Errors are one line."""
    import io
    import re

    import pandas as pd

    if skip_rows < 0:
        raise InvalidInputError(f"--skip-rows must be >= 0, got {skip_rows}")
    raw = read_text_file(path)
    kept, lines = [], []
    for k, line in enumerate(raw.splitlines(), start=1):
        if k > skip_rows and line.strip() and not line.lstrip().startswith(("#", "%", "//")):
            kept.append(line)
            lines.append(k)
    if len(kept) < 2:
        raise InvalidInputError(f"{path}: no data lines{f' ({no_data_hint})' if no_data_hint else ''}")
    sep = ";" if ";" in kept[0] else "," if "," in kept[0] else "\t" if "\t" in kept[0] else r"\s+"
    decimal_comma = sep in (";", "\t", r"\s+") and any(re.search(r"\d,\d", ln) for ln in kept[1:51])
    try:
        df = pd.read_csv(io.StringIO("\n".join(kept)), sep=sep, engine="python", dtype=str,
                         keep_default_na=keep_default_na)
    except pd.errors.ParserError as exc:
        raise InvalidInputError(f"{path}: malformed table ({str(exc).splitlines()[0]})") from None
    if decimal_comma:
        df = df.apply(lambda col: col.str.replace(r"^\s*([+-]?\d*),(\d+(?:[eE][+-]?\d+)?)\s*$", r"\1.\2", regex=True)
                      if pd.api.types.is_string_dtype(col) or col.dtype == object else col)
    return df, lines[1:]
