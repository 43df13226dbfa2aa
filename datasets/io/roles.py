"""Which columns of a sniffed file hold what (:func:`resolve` -> :class:`Resolved`), from the header's names
(:data:`ROLES`): x, y, or angle + radial deviation (or radius) as ballbar and roundness software list their data,
and a direction or run column; ``plane`` (:data:`PLANES`) picks two of x, y, z, and a CMM, tracker or 3-D ballbar
export naming all three without a choice is refused with the plane its points lie in (:func:`_which_plane`)."""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from datasets.io.delimiters import _split
from datasets.io.headers import ANGLE_UNITS, CONVERT, LENGTH_UNITS, column_unit, parse_name
from datasets.io.layout import Layout, one_column, skip_rows_hint
from datasets.io.numbers import DataFileError, _field_number
from methods import InvalidInputError
from methods.units import to_mm


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
    offsets: list | None = None   # x, y layouts: the columns of the deviations added to idx (dX, dY), else None
    note: str | None = None       # which columns were read, when the header held more than the pair


#: header keys of columns that say nothing more about the points (a point number, a time stamp; an angle column
#: beside x, y is the points' own polar angle): never a coordinate, never refused as an unread column
ANCILLARY = {"point", "pt", "pnt", "no", "nr", "number", "n", "index", "idx", "id", "i", "sample", "samples", "punkt",
             "time", "t", "timestamp", "zeit", "line", "row"}
_AXIS = "(x|y|z)"
_ACT = "(?:act|actual|meas|measured|m|ist|mess|real)"
_NOM = "(?:nom|nominal|n|soll|set|target|cmd|command|ref)"
_DEV = "(?:d|delta|dev|deviation|err|error|abw|abweichung)"
_COMPANION = [(re.compile(f"{_AXIS}{_ACT}|{_ACT}{_AXIS}"), "actual"),
              (re.compile(f"{_AXIS}{_NOM}|{_NOM}{_AXIS}"), "nominal"),
              (re.compile(f"{_DEV}{_AXIS}|{_AXIS}{_DEV}"), "deviation")]


def coordinate_kind(key: str) -> tuple[str, str] | None:
    """(axis, kind) of a header key naming a coordinate: ``x`` -> ('x', 'plain'); ``X act``, ``Xm``, ``Ist X``
    -> 'actual'; ``X nominal``, ``Xsoll`` -> 'nominal'; ``dX``, ``X dev`` -> 'deviation' (the measured point is the
    nominal plus it, as grid-encoder and CMM exports list a circle); None for any other key."""
    if key in ("x", "y", "z"):
        return key, "plain"
    for rx, kind in _COMPANION:
        m = rx.fullmatch(key)
        if m:
            return next(g for g in m.groups() if g), kind
    return None


def is_angle_unit(unit: str | None) -> bool:
    """Whether a header unit is an angle's: one fitbench reads (deg, °, rad) or converts (gon, mrad, arcsec, ...)."""
    return unit is not None and (unit in ANGLE_UNITS.values() or unit in CONVERT["angle"])


def column_roles(layout: Layout) -> list:
    """The role of each header column (:data:`ROLES`, by its name), and ``angle`` for a column whose header unit is an
    angle's (:func:`is_angle_unit`) when it is the only such column and no column is named an angle: exports name the
    angle ``Drehwinkel [°]``, ``C [deg]``, ``Position [deg]``, ``Point angle [deg]``, and such a column is an angle
    whatever its name (read as a length it was refused with advice to rename its unit to mm). [] without a header."""
    fields = layout.fields()
    roles = [ROLES.get(k) for k, _ in fields]
    by_unit = [k for k, (_, u) in enumerate(fields) if is_angle_unit(u)]
    if "angle" not in roles and len(by_unit) == 1:
        roles[by_unit[0]] = "angle"
    return roles


#: words of a header name saying its angles are measured clockwise / counter-clockwise (lower case, whole words;
#: 'clockwise' and 'Uhrzeigersinn' after counter, anti, gegen or entgegen are counter-clockwise)
_CW_WORDS = {"cw", "clockwise", "uhrzeigersinn", "uzs"}
_CCW_WORDS = {"ccw", "acw", "counterclockwise", "anticlockwise", "guzs", "guz", "ccwise"}
_NEGATE = {"counter", "anti", "gegen", "entgegen"}
#: a word of a header name, camel case split ('AngleCW' -> Angle, CW; 'CWAngle' -> CW, Angle)
_WORD = r"[A-ZÄÖÜ]+(?=[A-ZÄÖÜ][a-zäöüß])|[A-ZÄÖÜ]+(?![a-zäöüß])|[A-ZÄÖÜ]?[a-zäöüß]+"


def clockwise_name(name: str) -> bool:
    """Whether a header name says its angles are measured clockwise (``Angle CW (deg)``, ``CW angle [deg]``, ``Angle
    (clockwise) [deg]``, ``Winkel im Uhrzeigersinn [°]``, ``AngleCW [deg]``): by whole words, so ``CCW``, ``counter-clockwise``,
    ``anticlockwise`` and ``gegen den Uhrzeigersinn`` are not."""
    words = [w.lower() for w in re.findall(_WORD, str(name))]
    return any(w in _CW_WORDS and not _NEGATE.intersection(words[:i]) for i, w in enumerate(words))


def _refuse_clockwise(layout: Layout, k: int) -> None:
    """Refuse an angle column whose name says clockwise: fitbench's angles turn counter-clockwise (the mathematical
    sense, ISO 230-4 and ISO 12181-1 polar profiles), and reading clockwise angles so mirrors the profile (the
    roundness centre's y and a circular test's squareness change sign, the runs swap). A name may also mean the
    clockwise RUN's angle, so the convention is the user's to say."""
    if layout.header is None or not clockwise_name(layout.header[k]):
        return
    unit = parse_name(layout.header[k])[1] or "deg"
    raise DataFileError(f"{layout.name}: column {layout.header[k].strip()!r} names a clockwise direction: fitbench "
                        "reads angles counter-clockwise (mathematical sense); if they are measured clockwise, negate "
                        f"them; either way name the column 'Angle [{unit}]'")


def resolve(layout: Layout, columns=None, plane: str | None = None) -> Resolved:
    """The instrument layout of a file (:func:`_resolve`); an angle column named clockwise is refused
    (:func:`_refuse_clockwise`)."""
    res = _resolve(layout, columns, plane)
    if res.kind == "polar":
        _refuse_clockwise(layout, res.idx[0])
    return res


def _resolve(layout: Layout, columns=None, plane: str | None = None) -> Resolved:
    """The instrument layout of a file, decided by its header where it can (:data:`ROLES`, :func:`parse_name`):
    angle + radial deviation (or radius) when the header names both, else x, y (``plane`` picks its named
    pair). ``columns`` names any layout's two columns (header names, case and spaces ignored, or 0-based
    numbers); an angle among them (by its name or its header unit) makes the file polar. A header that names an angle
    (:func:`column_roles`) is never read as x, y."""
    name = layout.name
    roles = column_roles(layout)
    d_col = roles.index("direction") if "direction" in roles else None
    if columns is not None and tuple(str(c).strip().lower() for c in columns) == ("x", "y") and \
            not ("x" in roles and "y" in roles):
        columns = None  # the default pair, absent from the header: decide by the header
    if plane is not None:
        if plane.lower() not in PLANES:
            raise DataFileError(f"unknown plane {plane!r}; use one of {', '.join(PLANES)}")
        if layout.header is not None and (got := _pair(layout, PLANES[plane.lower()], d_col)) is not None:
            return got
        if layout.header is not None and (got := _polar(layout, roles, d_col)) is not None:
            return got   # angle + radial deviation: the plane names the axes the angle turns in (read_runs)
        return Resolved("xy", layout.index(PLANES[plane.lower()]), None, d_col)
    if columns is not None:
        idx = layout.index(columns)
        if len(idx) != 2 or idx[0] == idx[1]:
            raise DataFileError(f"{name}: give two different columns, got {tuple(columns)!r}")
        fields = layout.fields()
        r = [("angle" if is_angle_unit(fields[k][1]) else roles[k]) for k in idx] if roles else [None, None]
        if r == ["angle", "angle"]:
            raise DataFileError(f"{name}: the columns {layout.header[idx[0]]!r}, {layout.header[idx[1]]!r} are both "
                                "angles (by their names or units); give --columns ANGLE DEVIATION, the second a length")
        if "angle" in r:
            if r[1] == "angle":
                idx, r = idx[::-1], r[::-1]
            return Resolved("polar", idx, "radius" if r[1] == "radius" else "deviation", d_col)
        return Resolved("xy", idx, None, d_col)
    if layout.ncol == 1 and all(len(_split(ln, layout.sep)) == 1 for _, ln in layout.sample):
        raise DataFileError(one_column(name, repr(layout.header[0]) if layout.header else None)
                            + skip_rows_hint(layout))
    if layout.header is None:
        if layout.ncol != 2:
            raise DataFileError(f"{name} line {layout.first_data_line}: {layout.ncol} columns and no header; "
                                "add a header line naming the x and y columns (or --columns 0 1)")
        return Resolved("xy", [0, 1])
    if (got := _polar(layout, roles, d_col)) is not None:
        return got
    a = roles.index("angle") if "angle" in roles else None
    if "x" in roles and "y" in roles and "z" in roles:
        raise DataFileError(_which_plane(layout, [roles.index(c) for c in "xyz"]))
    if (got := _pair(layout, ("x", "y"), d_col)) is not None:
        return got
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


def _numeric_column(layout: Layout, k: int) -> bool:
    """Whether column ``k`` holds numbers in the first data lines (:attr:`Layout.sample`)."""
    rows = [_split(ln.split(layout.comment, 1)[0].strip(), layout.sep) for _, ln in layout.sample]
    vals = [r[k] for r in rows if len(r) == layout.ncol and r[k].strip()]
    try:
        return bool(vals) and all(np.isfinite(_field_number(t, layout.decimal_comma)) for t in vals)
    except (ValueError, IndexError, InvalidInputError):
        return False


def _polar(layout: Layout, roles: list, d_col) -> Resolved | None:
    """The angle + radial deviation (or radius) reading of a header naming both, else None."""
    a = roles.index("angle") if "angle" in roles else None
    v = next((roles.index(r) for r in ("deviation", "radius") if r in roles), None)
    if a is None or v is None:
        return None
    _refuse_other_lengths(layout, [a, v], roles, d_col)
    return Resolved("polar", [a, v], roles[v], d_col)


def _pair(layout: Layout, axes: tuple, d_col) -> Resolved | None:
    """The x, y reading of a header naming the coordinates ``axes`` (plain, nominal, actual or deviation columns,
    :func:`coordinate_kind`), or None when it names no such pair. The actual columns are read when the header has
    them (``X, Y, X act, Y act``); deviation columns are added to the nominal ones (``X [mm];Y [mm];dX [µm];dY
    [µm]``, as grid-encoder and CMM exports list a measured circle); a header with further numeric columns that
    fitbench cannot place is refused naming them (reading the nominal path of such a file gave a 0.11 µm
    circular deviation for a 7 µm trace)."""
    name = layout.name
    roles = column_roles(layout)
    kinds = [coordinate_kind(k) for k, _ in layout.fields()]
    found = {}
    for k, c in enumerate(kinds):
        if c is not None and c[0] in axes:
            found.setdefault(c, []).append(k)
    if any(len(v) > 1 for v in found.values()):
        dup = next(v for v in found.values() if len(v) > 1)
        raise DataFileError(f"{name}: the columns {', '.join(layout.header[k] for k in dup)} name the same coordinate; "
                            "give --columns NAME NAME")

    def col(axis, *kinds_):
        return next((found[(axis, kd)][0] for kd in kinds_ if (axis, kd) in found), None)

    base = [col(ax, "plain", "nominal") for ax in axes]
    act = [col(ax, "actual") for ax in axes]
    dev = [col(ax, "deviation") for ax in axes]
    if all(k is None for k in base + act) or (all(k is None for k in act + dev) and None in base):
        return None    # no pair named: decided by the caller (which two columns?)
    h = layout.header
    if all(k is not None for k in act):
        idx, offsets = act, None
        skipped = [k for k in base + dev if k is not None]
        note = (f"read the actual columns {h[act[0]]!r}, {h[act[1]]!r}"
                + (f" (not the nominal {', '.join(repr(h[k]) for k in skipped)})" if skipped else ""))
    elif all(k is not None for k in base) and all(k is not None for k in dev):
        idx, offsets = base, dev
        note = (f"the points are {h[base[0]]!r} + {h[dev[0]]!r}, {h[base[1]]!r} + {h[dev[1]]!r} (nominal plus "
                "deviation)")
        for k in dev:
            if column_unit(layout, k, "length") is None:
                raise DataFileError(f"{name}: the deviation column {h[k]!r} names no unit; write it in the header "
                                    f"({axes[0].upper()} [mm];{axes[1].upper()} [mm];d{axes[0].upper()} [µm];"
                                    f"d{axes[1].upper()} [µm])")
    elif all(k is not None for k in base) and not any(k is not None for k in act + dev):
        idx, offsets, note = base, None, None
    else:
        have = [k for k in base + act + dev if k is not None]
        raise DataFileError(f"{name}: the columns {', '.join(repr(h[k]) for k in have)} do not give both coordinates "
                            f"of one kind (nominal + deviation, or actual); give --columns NAME NAME")
    used = set(idx) | set(offsets or ()) | {k for k in base + act + dev if k is not None}
    extra = [k for k, (key, _) in enumerate(layout.fields())
             if k not in used and k != d_col and key not in ANCILLARY and roles[k] != "angle" and h[k].strip()
             and not (kinds[k] is not None and kinds[k][0] not in axes) and _numeric_column(layout, k)]
    if extra:
        raise DataFileError(f"{name}: besides {h[idx[0]]!r}, {h[idx[1]]!r} the header has the numeric column(s) "
                            f"{', '.join(repr(h[k]) for k in extra)}, and fitbench does not guess what they hold (a "
                            "measured position? a deviation?); give --columns NAME NAME for the two coordinates to "
                            "evaluate, or delete the other columns")
    return Resolved("xy", idx, None, d_col, offsets, note)


def _refuse_other_lengths(layout: Layout, idx: list, roles: list, d_col) -> None:
    """Refuse an angle + deviation file with a further length column (``Deviation filtered (um)``, ``Probe (um)``)
    besides the one chosen and a radius: which one holds the profile is the user's choice (--columns)."""
    extra = [k for k, (key, unit) in enumerate(layout.fields())
             if k not in idx and k != d_col and roles[k] != "radius" and unit in LENGTH_UNITS.values()]
    if extra:
        h = layout.header
        raise DataFileError(f"{layout.name}: besides {h[idx[1]]!r} the header has the length column(s) "
                            f"{', '.join(repr(h[k]) for k in extra)}; give --columns ANGLE DEVIATION naming the "
                            "profile to evaluate")


def read_offsets(layout: Layout, res: Resolved, cols: dict) -> np.ndarray | None:
    """The (N, 2) deviations in mm of an x, y layout with deviation columns (``res.offsets``, each in its header's
    unit, :func:`_pair`) from the columns read ``cols``; None when it has none."""
    if not res.offsets:
        return None
    out = np.empty((len(cols[res.offsets[0]]), 2), dtype=np.float64)
    for j, k in enumerate(res.offsets):
        out[:, j] = cols[k] * to_mm(1.0, column_unit(layout, k, "length"))
    return out


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
