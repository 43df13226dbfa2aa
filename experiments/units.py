"""Units and readable names of a study's row columns: the unit a column carries (declared by the result classes,
``methods.results``, else read from its name's suffix), the unit of a study's lengths (mm for the machine-tool data,
the data's own unit for a generator's), and the words a table header or a figure axis shows for a column."""
from __future__ import annotations

from methods import results

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
    """'RMSE of radius error', 'mean of arc'."""
    return f"{'RMSE' if how == 'rmse' else how} of {readable(column)}"


def unit_problem(column: str, unit: str, how: str) -> str | None:
    """A table unit of another dimension than its values' (a degree column is never labelled mm)."""
    if not unit or how in ("count", "ok_share"):
        return None
    own = column_unit(column)
    for group, what in ((LENGTH_UNITS, "a length"), (ANGLE_UNITS, "an angle")):
        if own in group and unit not in group:
            return f"{column!r} is {what} in {own}, not in {unit!r}"
        if unit in group and own and own not in group:
            return f"{column!r} is in {own}, not {what} ({unit!r})"
    return None


#: data sources whose lengths are in mm (published coordinates, files read into mm, the machine-tool simulators); a
#: generator's lengths are in the unit of its own parameters (a radius of 1 is a unit circle), a plugin's are unknown
MM_SOURCES = frozenset({"published", "file", "circular_test", "positioning", "contouring", "multilateration"})
#: the unit a default table or figure gives a length whose unit the study does not declare (``length_unit``)
DATA_UNITS = "data units"


def data_length_unit(cfg: dict | None) -> str | None:
    """The unit of a study's lengths: its declared ``length_unit`` (:func:`length_unit`), else None (the columns'
    declared mm) when every data set comes from a source whose lengths are mm (:data:`MM_SOURCES`), else
    :data:`DATA_UNITS` (a generator's lengths are those of its own parameters)."""
    declared = length_unit(cfg)
    if declared:
        return declared
    used = {"published" if "published" in d else "file" if "file" in d else d.get("source") or d.get("generator")
            for d in (cfg or {}).get("datasets") or []}
    return None if not used or used <= MM_SOURCES else DATA_UNITS


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
