"""Header names and their units.

A name taken apart into key and unit (:func:`parse_name`: ``Radial deviation (um)``, ``angle[deg]``, ``dr/µm``,
``radial_deviation_um``); a units row under the header (``X;Y`` / ``µm;µm``, :func:`_units_row`, folded into the
names as ``NAME [UNIT]``); the length unit of columns from the header or ``--unit``, a contradiction refused
(:func:`column_unit`, :func:`length_unit`); units fitbench does not read are refused by name (:data:`OTHER_UNITS`)."""
from __future__ import annotations

import re

from datasets.io.numbers import DataFileError
from methods.units import canonical


#: units a header may carry, to their canonical names
LENGTH_UNITS = {"nm": "nm", "µm": "µm", "um": "µm", "micron": "µm", "microns": "µm", "mm": "mm", "m": "m",
                "in": "in", "inch": "in"}
ANGLE_UNITS = {"deg": "deg", "degree": "deg", "degrees": "deg", "°": "deg", "rad": "rad", "radian": "rad",
               "radians": "rad"}


def parse_name(name: str) -> tuple[str, str | None]:
    """(key, unit) of a header name: the unit in ``()``, ``[]`` or ``{}``, after ``/`` or a unit word after ``in``
    (DIN 1313's forms; :func:`unit_words`), or as a ``_um``-style suffix (``Radial deviation (um)``, ``angle[deg]``, ``dr/µm``,
    ``Position in mm``, ``radial_deviation_um`` -> ``radialdeviation``,
    ``µm``); the key in lower case without spaces, ``_``, ``-`` or ``.``. The unit is canonical (``µm``,
    ``deg``) when fitbench knows it, else as written."""
    n = str(name).strip().lower().replace("μ", "µ")
    unit = None
    m = re.fullmatch(r"(.*?)\s*[(\[{]\s*([^)\]}]*?)\s*[)\]}]", n) or re.fullmatch(r"(.*?)\s*/\s*([^/\s]+)", n)
    in_unit = re.fullmatch(r"(.*?)\s+in\s+(\S+)", n)   # DIN 1313's 'Position in mm'
    if m and m.group(1):
        n, unit = m.group(1), m.group(2)
    elif in_unit and in_unit.group(1) and in_unit.group(2) in unit_words():   # a unit read or refused by name
        n, unit = in_unit.group(1), in_unit.group(2)
    else:
        m = re.fullmatch(r"(.*?)[\s_\-]+([a-zµ°]+)", n)
        if m and m.group(1) and (m.group(2) in LENGTH_UNITS or m.group(2) in ANGLE_UNITS):
            n, unit = m.group(1), m.group(2)
    key = re.sub(r"[\s_\-.]+", "", n)
    if unit is not None:
        unit = LENGTH_UNITS.get(unit, ANGLE_UNITS.get(unit, unit))
    return key, unit


def column_unit(layout, k: int, kind: str) -> str | None:
    """The unit the header gives column ``k`` ('length' or 'angle'), None when it gives none; a unit of the
    other kind or an unknown one is refused in one line."""
    if not layout.header:
        return None
    key, unit = parse_name(layout.header[k])
    if unit is None:
        if re.search(r"[\[\](){}<>|µμ°]", key):   # a unit fitbench cannot take apart: never read the column as mm
            # the "header" may be a preamble line ('{Probe 3}') above the real header: said, as other refusals do
            raise DataFileError(f"{layout.name}: cannot tell the unit of column {layout.header[k]!r}; write it as "
                                f"'NAME [UNIT]' (x [µm]){layout.preamble_hint()}")
        return None
    known = LENGTH_UNITS if kind == "length" else ANGLE_UNITS
    if unit in known.values():
        return unit
    if kind == "length" and (unit in ANGLE_UNITS.values() or unit in CONVERT["angle"]):
        # an angle read as a length: naming its unit mm (unit_refusal's advice) would read the angles as lengths
        raise DataFileError(f"{layout.name}: column {layout.header[k]!r} is an angle ({unit}) where a length is read; "
                            "give --columns ANGLE DEVIATION (or X Y) naming the angle and a length column")
    # the "header" may be an instrument's preamble line ('Cutoff (UPR);50') above the real one: said
    raise DataFileError(f"{unit_refusal(layout.name, layout.header[k], unit, kind)}{layout.preamble_hint()}")


#: length and angle units a header may give that fitbench does not read: what to multiply the column by, and the
#: unit that gives (said in the refusal, :func:`unit_refusal`, as an exact multiplication or division)
CONVERT = {"length": {"cm": (10.0, "mm"), "dm": (100.0, "mm"), "km": (1e6, "mm"), "mil": (0.0254, "mm"),
                      "mils": (0.0254, "mm"), "thou": (0.0254, "mm"), "ft": (304.8, "mm")},
           "angle": {"mrad": (1e-3, "rad"), "µrad": (1e-6, "rad"), "urad": (1e-6, "rad"), "gon": (0.9, "deg"),
                     "grad": (0.9, "deg"), "arcmin": (1 / 60, "deg"), "arcsec": (1 / 3600, "deg")}}


def _scaling(factor: float, what: str) -> str:
    """'multiply WHAT by 10', or 'divide WHAT by 60' where the factor is the inverse of a short number (arcmin to
    deg is 1/60: 'multiply by 0.0166667' stretched 360° to 360.0007°): the advice is exact, never a rounded factor."""
    if f"{factor:.12g}" == f"{factor:.6g}":
        return f"multiply {what} by {factor:.6g}"
    inverse = 1.0 / factor
    if f"{inverse:.12g}" == f"{inverse:.6g}":
        return f"divide {what} by {inverse:.6g}"
    return f"multiply {what} by {factor:.12g}"


def _bare_name(column) -> str:
    """A header name without its unit (``X [cm]`` -> ``X``, ``dr/µm`` -> ``dr``), as written."""
    name = str(column).strip()
    return re.sub(r"\s*(?:[(\[{].*|/.*)$", "", name) or name


def mixed_units(where, given: dict) -> DataFileError:
    """The one-line refusal of length columns ``given`` ({column: canonical unit}) in different units, naming the
    factor that brings the first column of another unit to the first column's."""
    from methods.units import mm_per
    to = next(iter(given.values()))
    other, unit = next((c, u) for c, u in given.items() if u != to)
    key = _bare_name(other)
    return DataFileError(f"{where}: the columns {', '.join(map(str, given))} are in different units "
                         f"({', '.join(sorted(set(given.values())))}); convert them to one unit, e.g. "
                         f"{_scaling(mm_per(unit) / mm_per(to), f'column {str(other).strip()!r}')} and name it "
                         f"'{key} [{to}]'")


#: units of other quantities a header may give, and what they measure: such a column is never advised to be
#: renamed a length or an angle (a temperature named mm would be read as one)
OTHER_QUANTITIES = {**dict.fromkeys(("°c", "°f", "degc", "degf", "℃", "k"), "a temperature"),
                    **dict.fromkeys(("s", "ms", "min", "sec"), "a time"),
                    **dict.fromkeys(("hz", "khz", "rpm", "1/min"), "a frequency"),
                    **dict.fromkeys(("mm/min", "m/min", "mm/s", "in/min"), "a feed rate"),
                    **dict.fromkeys(("ppm", "µm/m", "um/m"), "a ratio"),
                    "upr": "undulations per revolution (a filter cutoff)"}


def unit_refusal(where, column, unit: str, kind: str = "length") -> DataFileError:
    """The one-line refusal of a ``kind`` ('length' or 'angle') column whose header gives a unit fitbench does not
    read: the factor that converts it to one it reads when the unit is known (cm: x 10 to mm), else the units it
    reads and how to name one in the header."""
    name, key = str(column).strip(), _bare_name(column)
    reads = "nm, µm, mm, m, in" if kind == "length" else "deg, rad"
    if unit in CONVERT[kind]:
        factor, to = CONVERT[kind][unit]
        return DataFileError(f"{where}: column {name!r} carries the unit {unit!r}, which fitbench does not read (it "
                             f"reads {reads}): {_scaling(factor, 'the column')} and name its unit {to} "
                             f"('{key} [{to}]')")
    what, example = ("a length", "mm") if kind == "length" else ("an angle", "deg")
    if unit in OTHER_QUANTITIES:
        return DataFileError(f"{where}: column {name!r} carries the unit {unit!r}, {OTHER_QUANTITIES[unit]}, not "
                             f"{what}: fitbench does not evaluate such a column (it reads {reads} here); name the "
                             "columns to read (--columns) or delete this one")
    return DataFileError(f"{where}: column {name!r} carries the unit {unit!r}, not {what} unit: name the column's "
                         f"unit in the header ({reads}; e.g. '{key} [{example}]')")


def length_unit(layout, idx, unit: str | None) -> str:
    """The length unit of the columns ``idx``: the header's, the declared ``unit`` (--unit), or mm. A header
    unit that contradicts ``unit``, or two columns in different units, is an error."""
    found = {layout.header[k]: column_unit(layout, k, "length") for k in idx} if layout.header else {}
    given = {c: u for c, u in found.items() if u is not None}
    if len(set(given.values())) > 1:
        raise mixed_units(layout.name, given)
    header = next(iter(given.values()), None)
    if unit is not None and header is not None and canonical(unit) != header:
        col = next(iter(given))
        raise DataFileError(f"{layout.name}: the header says column {col!r} is in {header} but --unit says "
                            f"{canonical(unit)}; drop --unit or correct the header")
    return header or (canonical(unit) if unit is not None else "mm")


def _names_above(skip_rows: int) -> str:
    """The advice for a header of units read after ``skip_rows`` skipped lines: skip one line fewer."""
    if not skip_rows:
        return ""
    return ("; if the names are on the line above, drop --skip-rows" if skip_rows == 1 else
            f"; if the names are on the line above, give --skip-rows {skip_rows - 1}")


#: units a units row or a header may name that fitbench does not read: refused by name, never taken as a column
OTHER_UNITS = {"cm", "dm", "km", "mil", "mils", "thou", "ft", "gon", "grad", "mrad", "µrad", "urad", "arcsec", "arcmin",
               "ms", "min", "%", "ppm", "µm/m", "um/m", "mm/min", "°c", "hz"}


def unit_words() -> frozenset:
    """Every unit word a header may name, in lower case: those fitbench reads and those it refuses by name
    (:data:`OTHER_UNITS`, :data:`CONVERT`): after ``in`` (``Run 1 + in µm``) only such a word is a unit, so that
    ``in cm`` is refused as ``[cm]`` is and ``Zoom in x`` stays a name."""
    return frozenset(LENGTH_UNITS) | frozenset(ANGLE_UNITS) | OTHER_UNITS | frozenset(CONVERT["length"]) | \
        frozenset(CONVERT["angle"])


def _unit_word(token: str) -> str | None:
    """The unit a field of a units row names (``µm``, ``[mm]``, ``(deg)``), canonical when fitbench reads it,
    else as written when it is a unit it does not read (:data:`OTHER_UNITS`); '' for the placeholder of a column
    without a unit (``-``, ``[-]``, ``[1]``, ``1``, ``[]``: a point number, a direction, a run); None when it is no
    unit."""
    t = str(token).strip().lower().replace("μ", "µ")
    t = re.sub(r"^[\[({]\s*(.*?)\s*[\])}]$", r"\1", t)
    if t in ("", "-", "\u2013", "\u2014", "1"):
        return ""
    return LENGTH_UNITS.get(t, ANGLE_UNITS.get(t, t if t in OTHER_UNITS else None))


def _units_row(tokens) -> list | None:
    """The units of a units row (``µm;µm``, ``;deg;µm``, ``[-];[µm];[µm]``: one per field, None for an empty field
    or a unitless column's placeholder, :func:`_unit_word`), or None when ``tokens`` is not one (every non-empty
    field a unit or a placeholder, at least one a unit)."""
    words = [_unit_word(t) if t.strip() else "" for t in tokens]
    if any(w is None for w in words) or not any(words):
        return None
    return [w or None for w in words]


def _with_units(name, header: list, units: list, lineno: int) -> list:
    """The header names with the units of the units row under them (line ``lineno``) as ``NAME [UNIT]``; a name
    that carries another unit already is refused."""
    if len(units) > len(header):
        raise DataFileError(f"{name} line {lineno}: a units row of {len(units)} fields under a header of "
                            f"{len(header)}; give one unit per column")
    out = list(header)
    for k, u in enumerate(units):
        if u is None:
            continue
        had = parse_name(header[k])[1]
        if had is not None and had != u:
            raise DataFileError(f"{name} line {lineno}: the units row says {u} for column {header[k]!r}, whose name "
                                f"says {had}; correct one of them")
        if had is None:
            out[k] = f"{header[k]} [{u}]"
    return out
