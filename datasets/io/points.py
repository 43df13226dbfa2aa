"""Points files (:func:`read_points`): an (N, 2) array of x, y in mm from two columns of a text file in any
of the readers' formats (:func:`points_unit`: the unit it is read in); a file holding an angle and a radial
deviation is refused (:func:`datasets.io.runs.read_profile` reads it)."""
from __future__ import annotations

import numpy as np

from datasets.io.columns import read_columns
from datasets.io.headers import length_unit
from datasets.io.layout import Layout, sniff
from datasets.io.numbers import DataFileError
from datasets.io.roles import Resolved, read_offsets, resolve
from methods.units import to_mm


def points_unit(path, columns=None, *, plane: str | None = None, unit: str | None = None,
                skip_rows: int = 0) -> str:
    """The length unit :func:`read_points` reads ``path`` in (the header's, ``unit``, or mm)."""
    layout = sniff(path, skip_rows)
    return length_unit(layout, _xy(layout, columns, plane).idx, unit)


def _xy(layout: Layout, columns, plane) -> Resolved:
    """:func:`resolve` for a reader of x, y: an angle + deviation file is refused in one line."""
    res = resolve(layout, columns, plane)
    if res.kind == "polar":
        raise DataFileError(f"{layout.name}: holds an angle ({layout.header[res.idx[0]] if layout.header else res.idx[0]!r}) "
                            "and a radial deviation, not x, y; this command needs x, y columns")
    return res


def read_points(path, columns=None, *, plane: str | None = None, unit: str | None = None,
                skip_rows: int = 0) -> np.ndarray:
    """Read an (N, 2) float array of x, y (mm) from a text file.

    ``columns``: two header names (case and spaces ignored; units in the header allowed) or 0-based
    indices (default: x, y from the header); ``plane`` ('xy', 'yz', 'zx') picks the named columns of that plane.
    Without a header the file must have exactly two columns (or ``columns`` as indices); with a header lacking
    the names, the first two columns are used only when the file has exactly two, else the error lists the
    columns; a header naming x, y and z needs ``plane`` or ``columns`` (:func:`_which_plane`). A file whose
    header names an angle is refused (it is not x, y; :func:`read_profile` reads it). ``unit``: the file's
    length unit (default: the header's, else mm; a contradiction with the header is an error). A header with
    actual columns besides the nominal ones (``X, Y, X act, Y act``) is read from the actual ones, one with deviation
    columns (``X [mm];Y [mm];dX [µm];dY [µm]``) as nominal + deviation; further numeric columns are refused
    (:func:`datasets.io.roles.resolve`)."""
    layout = sniff(path, skip_rows)
    res = _xy(layout, columns, plane)
    lu = length_unit(layout, res.idx, unit)
    cols = read_columns(layout, res.idx + (res.offsets or []), skip_rows=skip_rows)
    out = np.empty((len(cols[res.idx[0]]), 2), dtype=np.float64)
    out[:, 0], out[:, 1] = cols[res.idx[0]], cols[res.idx[1]]
    if lu != "mm":
        out *= to_mm(1.0, lu)
    if (dev := read_offsets(layout, res, cols)) is not None:
        out += dev
    return out
