"""The 21 geometric errors of a 3-axis machine identified by multilateration, as CSV with ISO 230-1 names.

One row per identified coefficient: ``iso230_1_name`` (EXX, EYX, ..., C0Y, B0Z, A0Z; the rigid-body
terms TX..RZ of the measured volume are listed with the name ``rigid``), ``description``, ``order`` (the
power j of (position / travel)), ``value``, ``u`` (standard uncertainty) and ``unit`` (mm for
translational, rad for angular errors: the JSON's units). Names as in ISO 230-1:2012 table (as in the
multilateration paper's table 3): E<direction><axis> for component errors, A0Z/B0Z/C0Y squareness.
"""
from __future__ import annotations

import io

from methods._lazy import lazy_module

pd = lazy_module("pandas")


DIRECTION = {"X": "positioning/straightness along x", "Y": "straightness/positioning along y",
             "Z": "straightness/positioning along z", "A": "roll/pitch/yaw about x", "B": "roll/pitch/yaw about y",
             "C": "roll/pitch/yaw about z"}
SQUARENESS = {"C0Y": "squareness of Y to X (in the XY plane)", "B0Z": "squareness of Z to X (in the ZX plane)",
              "A0Z": "squareness of Z to Y (in the YZ plane)"}
RIGID = {"TX": "rigid shift x", "TY": "rigid shift y", "TZ": "rigid shift z", "RX": "rigid rotation about x",
         "RY": "rigid rotation about y", "RZ": "rigid rotation about z"}


def describe(name: str) -> tuple[str, str, int | None, str]:
    """(ISO 230-1 name, description, order, unit) of a parameter name such as 'EXX^2', 'C0Y', 'TX'."""
    base, _, order = name.partition("^")
    if base in SQUARENESS:
        return base, SQUARENESS[base], None, "rad"
    if base in RIGID:
        return "rigid", RIGID[base], None, "mm" if base[0] == "T" else "rad"
    d, axis = base[1], base[2]
    what = {"X": "error along x", "Y": "error along y", "Z": "error along z", "A": "angular error about x",
            "B": "angular error about y", "C": "angular error about z"}[d]
    if d == axis:
        what = f"positioning error of {axis}"
    elif d in "XYZ":
        what = f"straightness of {axis} along {d.lower()}"
    else:
        what = f"{'roll' if 'XYZABC'.index(d) - 3 == 'XYZ'.index(axis) else 'tilt'} of {axis} ({what})"
    return base, what, int(order) if order else None, "mm" if d in "XYZ" else "rad"


def errors_frame(ident) -> pd.DataFrame:
    rows = []
    for row in ident.as_table():
        iso, desc, order, unit = describe(row["parameter"])
        rows.append({"parameter": row["parameter"], "iso230_1_name": iso, "description": desc, "order": order,
                     "value": row["value"], "u": row["u"], "unit": unit})
    return pd.DataFrame(rows)


def errors_csv(ident) -> str:
    buf = io.StringIO()
    buf.write(f"# 21 geometric errors (ISO 230-1 names) identified by multilateration; value = coefficient of "
              f"(axis position / travel)^order, travels {', '.join(f'{t:g}' for t in ident.model.travel)} mm; "
              f"units per row (mm, rad)\n")
    errors_frame(ident).to_csv(buf, index=False, float_format="%.9g", lineterminator="\n")
    return buf.getvalue()
