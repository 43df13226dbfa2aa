"""Units and readable names of a study's row columns: the unit a column carries (declared by the result classes,
``methods.results``, else read from its name's suffix), the unit of a study's lengths (mm for the machine-tool data,
the data's own unit for a generator's), and the words a table header or a figure axis shows for a column."""
from __future__ import annotations

import math

from methods import results
from methods.units import MM_PER

#: units read from a column name's suffix (data and study columns: ``data_arc_deg``, ``station_error_um``)
SUFFIX_UNITS = {"_deg": "°", "_rad": "rad", "_urad": "µrad", "_um": "µm", "_mm": "mm", "_nm": "nm", "_s": "s"}
LENGTH_UNITS = {"mm", "µm", "um", "nm", "m", "cm"}
ANGLE_UNITS = {"rad", "µrad", "urad", "mrad", "deg", "°", "arcsec"}


def length_unit(cfg: dict | None) -> str | None:
    """The unit a study declares for its lengths: its ``length_unit`` ('R' for data on a unit circle), else the
    ``unit`` of its ``[[rankings]]`` of a length metric when that differs from the metric's declared unit, else
    None (the result classes' declared units)."""
    if (cfg or {}).get("length_unit"):
        return str(cfg["length_unit"])
    for decl in (cfg or {}).get("rankings") or []:
        unit, own = decl.get("unit"), column_unit(str(decl.get("metric", "")))
        if unit and own in LENGTH_UNITS and unit != own:
            return str(unit)
    return None


def column_unit(name: str) -> str:
    """The unit of a row column: declared by the result classes (``methods.results``: lengths in the data's
    unit, mm for the machine-tool data; angles in rad), timing in s, else read from the name's suffix."""
    col = results.row_columns().get(name)
    if col is not None:
        return col.unit
    if name.startswith("time_") and name.endswith("_s"):
        return "s"
    return next((u for suffix, u in SUFFIX_UNITS.items() if name.endswith(suffix)), "")


def readable(name: str) -> str:
    """A row column as a person reads it in a table or on an axis: without the ``data_`` prefix of a data
    parameter and without a unit suffix the unit is shown for, underscores as spaces ('data_arc_deg' -> 'arc',
    'radius_error' -> 'radius error')."""
    shown = name[5:] if name.startswith("data_") and len(name) > 5 else name
    for suffix, unit in SUFFIX_UNITS.items():
        if shown.endswith(suffix) and len(shown) > len(suffix) and column_unit(name) == unit:
            shown = shown[:-len(suffix)]
            break
    return shown.replace("_", " ")


def aggregate_words(how: str, column: str) -> str:
    """'RMSE of radius error', 'mean of arc', 'count of radius error' (its ok rows); 'ok share' (of the rows whose
    status is ok, as summary.md's column: whatever the column)."""
    if how == "ok_share":
        return "ok share"
    return f"{'RMSE' if how == 'rmse' else how} of {readable(column)}"


def unit_problem(column: str, unit: str, how: str, cfg: dict | None = None) -> str | None:
    """Why a declared table cannot show ``column`` in ``unit`` (:func:`table_unit`), None when it can."""
    try:
        table_unit(cfg, column, unit, how)
    except ValueError as exc:
        return str(exc)
    return None


#: the units a table's values may be converted between: base units per unit (lengths in mm, angles in rad, times in
#: s; ``methods.units.MM_PER`` for the lengths fitbench reads)
FACTORS = {"length": {**{u: f for u, f in MM_PER.items() if u in LENGTH_UNITS}, "µm": 1e-3, "cm": 10.0},
           "angle": {"rad": 1.0, "mrad": 1e-3, "µrad": 1e-6, "urad": 1e-6, "deg": math.pi / 180,
                     "°": math.pi / 180, "arcsec": math.pi / 648000},
           "time": {"s": 1.0, "ms": 1e-3, "µs": 1e-6, "us": 1e-6, "ns": 1e-9}}
_WHAT = {"length": "a length", "angle": "an angle", "time": "a time"}


def _dimension(unit: str) -> str | None:
    unit = str(unit).replace("μ", "µ")
    return next((dim for dim, factors in FACTORS.items() if unit in factors), None)


def _factor(unit: str) -> float:
    unit = str(unit).replace("μ", "µ")
    return FACTORS[_dimension(unit)][unit]


def value_unit(cfg: dict | None, column: str) -> str:
    """The unit ``column``'s values are in, in this study: a length in the study's unit of lengths
    (:func:`metric_unit`: its ``length_unit``, mm for the machine-tool data, else :data:`DATA_UNITS`), any other
    column in its declared unit (:func:`column_unit`; '' when unknown)."""
    return metric_unit(cfg or {}, column)[0]


def table_unit(cfg: dict | None, column: str, unit: str, how: str) -> tuple[str, float]:
    """(the unit a declared table shows ``column``'s ``how`` aggregate in, the factor its values are multiplied by).
    Without a declared ``unit``: the values' own unit (:func:`value_unit`), as the default table. A declared unit of the
    same dimension as the values' is a conversion (mm values shown in µm are multiplied by 1000; rad shown in ° by
    180/π); one that names the values' own unit (``um`` for µm, ``deg`` for °) is kept as written. Raises ValueError
    (one line) for a unit of another dimension, and for a length unit of data whose lengths are in no known unit
    (a generator's: :data:`DATA_UNITS`; a ``length_unit`` such as R), which no factor converts, and for any unit on a
    count of rows, a share of ok rows (but ``%``: the share x 100) or a column of :data:`UNITLESS_COLUMNS`
    (iterations), which have none."""
    if how == "ok_share" and unit == "%":
        return "%", 100.0        # the share of ok rows in per cent: 1 (every row ok) is 100 %
    if how in ("count", "ok_share"):
        what = ("a count of rows, which has no unit" if how == "count" else
                "the share of ok rows (0 to 1), which has no unit but % (unit = \"%\" shows it x 100)")
        return ("", 1.0) if not unit else _refuse(f"aggregate = {how!r} gives {what}: drop the unit {unit!r}")
    if unit and column in UNITLESS_COLUMNS:
        return _refuse(f"{column!r} is {UNITLESS_COLUMNS[column]}, which has no unit: drop the unit {unit!r}")
    own, values = column_unit(column), value_unit(cfg, column)
    if not unit or unit == values or (unit == DATA_UNITS and own in LENGTH_UNITS):   # the data's own unit, whatever
        return unit or values, 1.0
    dim = _dimension(unit)
    if dim is not None and dim == _dimension(values):   # the same unit spelt otherwise (um, µm) is a factor of 1
        return unit, _factor(values) / _factor(unit)
    if own in LENGTH_UNITS and values not in LENGTH_UNITS and dim in (None, "length"):
        if values == DATA_UNITS and dim == "length" and _factor(unit) == _factor(own):
            return unit, 1.0   # naming the data's lengths in the unit the columns declare (mm), as length_unit would
        if dim is None and unit not in LENGTH_NAMES:   # no unit of length ('%', 'furlong'): no length_unit names it
            return _refuse(f"{column!r} is a length, and {unit!r} is not a unit of length fitbench knows ({_KNOWN}): "
                           "drop the table's unit")
        if values != DATA_UNITS:
            return _refuse(f"{column!r} is in {values} (the study's length_unit), which cannot be converted to "
                           f"{unit!r}: declare unit = {values!r}, or drop the table's unit")
        name = "\"mm\" if they are in mm, then a table may show them in " + unit if dim else repr(unit).replace("'", '"')
        return _refuse(f"{column!r} is in the unit of the data (a generator's lengths are those of its own radius and "
                       f"noise), which cannot be converted to {unit!r}: name it with the study's length_unit "
                       f"(length_unit = {name}), or drop the table's unit")
    for dimension, group in (("length", LENGTH_UNITS), ("angle", ANGLE_UNITS), ("time", set(FACTORS["time"]))):
        if own in group and unit not in group:
            return _refuse(f"{column!r} is {_WHAT[dimension]} in {own}, not in {unit!r}")
        if unit in group and own and own not in group:
            return _refuse(f"{column!r} is in {own}, not {_WHAT[dimension]} ({unit!r})")
    return unit, 1.0   # a column of unknown unit (a study's own): the declared unit names it


#: the row columns every study writes whose values have no unit (a table or ranking that declares one is refused)
UNITLESS_COLUMNS = {"iterations": "a count (the method's iterations)", "nfev": "a count (function evaluations)",
                    "repetition": "a number (the repetition's)", "seed": "a number (the data's seed)"}


def _refuse(problem: str):
    raise ValueError(problem)


#: data sources whose lengths are in mm (published coordinates, files read into mm, the machine-tool simulators); a
#: generator's lengths are in the unit of its own parameters (a radius of 1 is a unit circle), a plugin's are unknown
MM_SOURCES = frozenset({"published", "file", "circular_test", "positioning", "contouring", "multilateration"})
#: the unit a default table or figure gives a length whose unit the study does not declare (``length_unit``)
DATA_UNITS = "data units"


#: the names a study's lengths may be given: the length units a table or ranking converts between, and R (lengths
#: relative to the radius of data on a unit circle, a generator's: the noise and convergence studies)
LENGTH_NAMES = ("mm", "µm", "um", "nm", "m", "cm", "R")
_KNOWN = "mm, µm (um), nm, m, cm; R for lengths relative to the radius of data on a unit circle"


def _sources(cfg: dict | None) -> dict:
    """{data set as the TOML names it: its source} of a study's ``[[datasets]]``."""
    out = {}
    for d in (cfg or {}).get("datasets") or []:
        source = "published" if "published" in d else "file" if "file" in d else d.get("source") or d.get("generator")
        out[str(d.get("label") or d.get("published") or d.get("file") or source)] = source
    return out


def _in_mm(cfg: dict | None) -> list[str]:
    """The data sets of a study whose lengths are mm (:data:`MM_SOURCES`), as 'trace.csv (file)'."""
    return [f"{name} ({source})" for name, source in _sources(cfg).items() if source in MM_SOURCES]


def length_unit_problem(cfg: dict | None) -> str | None:
    """Why a study's ``length_unit`` cannot name its lengths, None when it can (or none is declared). It names the
    lengths of a generator's data, whose unit is that of its own radius and noise ('R' for unit circles); data read
    in mm (a file, published coordinates, a simulator's) are in mm whatever it says, and a table's or a ranking's
    ``unit`` shows them in another unit (a conversion), so any other unit there is refused, as is a unit fitbench
    does not know."""
    unit = str((cfg or {}).get("length_unit") or "").replace("μ", "µ")
    if not unit:
        return None
    if unit not in LENGTH_NAMES:
        return f"{unit!r} is not a unit of length fitbench knows ({_KNOWN})"
    mm = _in_mm(cfg)
    if mm and (unit == "R" or _factor(unit) != 1.0):
        return (f"{unit!r} would relabel lengths that are in mm: data set {mm[0]} is read in mm; length_unit names "
                f"a generator's lengths; drop it (a [[tables]] or [[rankings]] unit = {unit!r} converts mm"
                f"{'' if unit == 'R' else ' to ' + unit})")
    return None


def ranking_unit(cfg: dict | None, metric: str, unit: str | None) -> tuple[str, float]:
    """(the unit of a ``[[rankings]]``'s costs, the factor the rows' values are multiplied by). Without a ``unit``:
    the values' own (:func:`value_unit`: mm for mm data, the ``length_unit``, else data units; timings in s). A
    length whose unit is known (mm data, a declared ``length_unit``) converts to a length unit (mm to µm: x 1000)
    and refuses any other (R on mm data); a generator's lengths have no unit but the one the study gives: the
    ranking's ``unit`` names them (R for unit circles, as :func:`length_unit` reads it), unless the study also has
    data in mm (it would relabel those) or another ranking names them otherwise. Other metrics as a table's
    (:func:`table_unit`). Raises ValueError (one line)."""
    unit = str(unit or "").replace("μ", "µ")
    if column_unit(metric) not in LENGTH_UNITS:
        return table_unit(cfg, metric, unit, "mean")
    if unit and unit not in LENGTH_NAMES:
        return _refuse(f"{metric!r} is a length, and {unit!r} is not a unit of length fitbench knows ({_KNOWN})")
    sources = set(_sources(cfg).values())
    declared = (cfg or {}).get("length_unit")
    if unit and not declared and not (sources and sources <= MM_SOURCES):   # names a generator's lengths
        mm = _in_mm(cfg)
        if mm and unit != "mm":
            return _refuse(f"unit {unit!r} would name the lengths of every data set of the study, and data set "
                           f"{mm[0]} is read in mm: declare unit = \"mm\" or none")
        named = {str(d["unit"]).replace("μ", "µ") for d in (cfg or {}).get("rankings") or []
                 if d.get("unit") and column_unit(str(d.get("metric", ""))) in LENGTH_UNITS}
        if len(named) > 1:
            return _refuse(f"the study's rankings name its lengths in {' and '.join(sorted(named))}: a generator's "
                           f"lengths have one unit; declare it as length_unit, or the same unit in every ranking")
        return unit, 1.0
    values = value_unit(cfg, metric)
    if not unit or unit == values:
        return unit or values, 1.0
    if values in FACTORS["length"] and unit in FACTORS["length"]:   # mm data shown in µm: x 1000
        return unit, _factor(values) / _factor(unit)
    why = "the study's length_unit" if declared else "data read in mm"
    return _refuse(f"{metric!r} is in {values} ({why}), which cannot be shown in {unit!r}: declare a unit of length "
                   f"({', '.join(u for u in LENGTH_NAMES if u != 'R')}) or none")


def data_length_unit(cfg: dict | None) -> str | None:
    """The unit of a study's lengths: its declared ``length_unit`` (:func:`length_unit`), else None (the columns'
    declared mm) when every data set comes from a source whose lengths are mm (:data:`MM_SOURCES`), else
    :data:`DATA_UNITS` (a generator's lengths are those of its own parameters)."""
    if (cfg or {}).get("length_unit"):
        return str(cfg["length_unit"])
    used = {"published" if "published" in d else "file" if "file" in d else d.get("source") or d.get("generator")
            for d in (cfg or {}).get("datasets") or []}
    if used and used <= MM_SOURCES:
        return None   # data in mm: a ranking's unit does not make them another unit (µm costs of mm rows)
    return length_unit(cfg) or (DATA_UNITS if used else None)


def metric_unit(cfg: dict, metric: str) -> tuple[str, str]:
    """(the unit of ``metric`` in a default table or figure, a sentence for the caption or ''). A length is in the
    study's declared ``length_unit``, else in mm when every data set comes from a source whose lengths are mm
    (:data:`MM_SOURCES`), else in the data's own unit (:data:`DATA_UNITS`), which the caption says how to name."""
    unit = column_unit(metric)
    if unit not in LENGTH_UNITS:
        return unit, ""
    lengths = data_length_unit(cfg)
    if lengths != DATA_UNITS:
        return lengths or unit, ""
    return DATA_UNITS, (" Lengths are in the unit of the data (a generator's are those of its radius and noise); "
                        "length_unit in the study's TOML names it.")
