"""Which columns of a sniffed file hold what (:func:`resolve` -> :class:`Resolved`), from the header's names
(:data:`ROLES`): x, y, or angle + radial deviation (or radius) as ballbar and roundness software list their data,
and a direction or run column; ``plane`` (:data:`PLANES`) picks two of x, y, z, and a CMM, tracker or 3-D ballbar
export naming all three without a choice is refused with the plane its points lie in (:func:`_which_plane`)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from datasets.io.delimiters import _split
from datasets.io.layout import Layout, skip_rows_hint
from datasets.io.numbers import DataFileError, _field_number
from methods import InvalidInputError


PLANES = {"xy": ("x", "y"), "yz": ("y", "z"), "zx": ("z", "x"), "xz": ("x", "z"), "yx": ("y", "x"), "zy": ("z", "y")}


#: what a column is, by its header key (lower case; spaces, '_', '-' and '.' removed; unit taken off)
ROLES = {"x": "x", "y": "y", "z": "z",
         **dict.fromkeys(("angle", "theta", "phi", "winkel", "sampleangle", "angularposition", "polarangle"), "angle"),
         **dict.fromkeys(("deviation", "radialdeviation", "dr", "deltar", "error", "radialerror", "raddev",
                          "radialdev", "dev", "abweichung", "abw", "radialabweichung", "radiusdeviation", "radialdisplacement"), "deviation"),
         **dict.fromkeys(("radius", "r", "radialposition"), "radius"),
         **dict.fromkeys(("direction", "dir", "run", "pass", "richtung"), "direction")}


@dataclass
class Resolved:
    """Which columns of a file hold what: ``kind`` 'xy' (idx: the two coordinates) or 'polar' (idx: angle,
    then the radial deviation or the radius, ``polar_value``); ``direction``: the run column or None."""

    kind: str
    idx: list
    polar_value: str | None = None
    direction: int | None = None


def resolve(layout: Layout, columns=None, plane: str | None = None) -> Resolved:
    """The instrument layout of a file, decided by its header where it can (:data:`ROLES`, :func:`parse_name`):
    angle + radial deviation (or radius) when the header names both, else x, y (``plane`` picks its named
    pair). ``columns`` names any layout's two columns (header names, case and spaces ignored, or 0-based
    numbers); an angle among them makes the file polar. A header that names an angle is never read as x, y."""
    name = layout.name
    roles = [ROLES.get(k) for k, _ in layout.fields()]
    d_col = roles.index("direction") if "direction" in roles else None
    if columns is not None and tuple(str(c).strip().lower() for c in columns) == ("x", "y") and \
            not ("x" in roles and "y" in roles):
        columns = None  # the default pair, absent from the header: decide by the header
    if plane is not None:
        if plane.lower() not in PLANES:
            raise DataFileError(f"unknown plane {plane!r}; use one of {', '.join(PLANES)}")
        return Resolved("xy", layout.index(PLANES[plane.lower()]), None, d_col)
    if columns is not None:
        idx = layout.index(columns)
        if len(idx) != 2 or idx[0] == idx[1]:
            raise DataFileError(f"{name}: give two different columns, got {tuple(columns)!r}")
        r = [roles[k] for k in idx] if roles else [None, None]
        if "angle" in r:
            if r[1] == "angle":
                idx, r = idx[::-1], r[::-1]
            return Resolved("polar", idx, "radius" if r[1] == "radius" else "deviation", d_col)
        return Resolved("xy", idx, None, d_col)
    if layout.header is None:
        if layout.ncol != 2:
            raise DataFileError(f"{name} line {layout.first_data_line}: {layout.ncol} columns and no header; "
                                "add a header line naming the x and y columns (or --columns 0 1)")
        return Resolved("xy", [0, 1])
    a = roles.index("angle") if "angle" in roles else None
    v = next((roles.index(r) for r in ("deviation", "radius") if r in roles), None)
    if a is not None and v is not None:
        return Resolved("polar", [a, v], roles[v], d_col)
    if "x" in roles and "y" in roles and "z" in roles:
        raise DataFileError(_which_plane(layout, [roles.index(c) for c in "xyz"]))
    if "x" in roles and "y" in roles:
        return Resolved("xy", [roles.index("x"), roles.index("y")], None, d_col)
    if a is not None:
        raise DataFileError(f"{name}: the column {layout.header[a]!r} is an angle but no radial deviation or radius "
                            f"column was found (columns: {', '.join(layout.header)}); name it e.g. 'radial deviation "
                            "(um)' or give --columns ANGLE DEVIATION")
    if len(layout.header) < 2:
        raise DataFileError(f"{name} line {layout.header_line}: header has fewer than two columns"
                            f"{skip_rows_hint(layout)}")
    others = [k for k in range(layout.ncol) if k != d_col]
    if len(others) == 2:
        return Resolved("xy", others, None, d_col)
    raise DataFileError(f"{name}: which two columns? the header has {', '.join(layout.header)}; "
                        f"give --columns NAME NAME or --plane xy|yz|zx{skip_rows_hint(layout)}")


def _which_plane(layout: Layout, idx: list) -> str:
    """The refusal of a file with x, y and z columns and no choice: a CMM, tracker or 3-D ballbar export of a
    circle in any plane. Names the columns, the spread of each in the first data lines (:attr:`Layout.sample`)
    and the ``--plane`` of the two that spread most; reading x, y of a ZX-plane circle gave a 3.77 km radius."""
    names = ", ".join(layout.header[k] for k in idx)
    hint = ""
    rows = [_split(ln.split(layout.comment, 1)[0].strip(), layout.sep) for _, ln in layout.sample]
    try:
        vals = np.array([[_field_number(r[k], layout.decimal_comma) for k in idx] for r in rows if len(r) == layout.ncol],
                        dtype=float)
    except (ValueError, IndexError, InvalidInputError):
        vals = np.empty((0, 3))
    if len(vals) >= 3 and np.isfinite(vals).all():
        spread = np.ptp(vals, axis=0)
        flat = int(np.argmin(spread))
        plane = {0: "yz", 1: "zx", 2: "xy"}[flat]
        hint = (f"; in its first {len(vals)} data lines {', '.join(f'{c} spans {v:.6g}' for c, v in zip('xyz', spread))}"
                f" (the file's unit): the points lie in the {plane.upper()} plane, give --plane {plane}")
    return (f"{layout.name}: the header has three coordinate columns ({names}); which plane is the circle in? give "
            f"--plane xy|yz|zx or --columns A B (fitbench does not guess){hint}")
