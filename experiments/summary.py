"""Per-study summary tables (CSV and Markdown) from the long results table."""
from __future__ import annotations

from functools import reduce

import numpy as np
import pandas as pd

from methods import result_base

#: the errors against the truth the families' result classes declare (``Column.truth_error``: read through
#: ``methods.result_base.truth_error_columns``)
ERROR_COLUMNS = result_base.truth_error_columns()


def summarise(df: pd.DataFrame, by: list[str]) -> pd.DataFrame:
    """One row per group: runs, share converged, median form error, bias and RMSE of the errors
    against the truth (the columns the result classes declare as ``truth_error``), median iterations and time."""
    by = [c for c in by if c in df.columns]
    declared = result_base.row_columns()
    # the groups hold only the columns read below (the keys group them from outside): splitting the whole frame
    # would copy every column of every row once more
    wanted = ["status", "form_error", "iterations", "time_median_s", *result_base.truth_error_columns(),
              *(p for c in result_base.truth_error_columns() for p in declared[c].components)]
    values = df[[c for c in dict.fromkeys(wanted) if c in df.columns]]
    # a key column with one value everywhere (most data parameters of a study) does not split the rows: its
    # value (as the grouping gives it) joins every key instead of costing one code per row in the grouping
    const = {c: next(iter(df[c].iloc[:1].groupby(df[c].iloc[:1], sort=False, dropna=False).groups))
             for c in by if len(df) and df[c].nunique(dropna=False) == 1}
    split = [c for c in by if c not in const]
    parts = (values.groupby([df[c] for c in split], sort=False, dropna=False) if split or not by
             else [((), values)] if len(values) else [])
    groups = []
    for key, g in parts:
        ok = g[g["status"] == "ok"] if "status" in g else g
        key = iter(key if isinstance(key, tuple) else (key,))
        row = {c: const[c] if c in const else next(key) for c in by}
        row["runs"] = len(g)
        row["ok_share"] = len(ok) / len(g) if len(g) else np.nan
        if "form_error" in g:
            row["form_error_median"] = ok["form_error"].median()
        for col in result_base.truth_error_columns():
            if col in g and ok[col].notna().any():
                v = ok[col].astype(float)
                name = col.replace("_error", "")
                parts = declared[col].components
                if parts:  # the length of an error vector: its bias is the length of the mean vector
                    row[f"{name}_rmse"] = float(np.sqrt(np.mean(v ** 2)))
                    if all(p in ok for p in parts):
                        row[f"{name}_bias"] = float(reduce(np.hypot, [ok[p].mean() for p in parts]))
                else:
                    row[f"{name}_bias"] = float(v.mean())
                    row[f"{name}_rmse"] = float(np.sqrt(np.mean(v ** 2)))
        if "iterations" in g and ok["iterations"].notna().any():
            row["iterations_median"] = float(ok["iterations"].median())
        if "time_median_s" in g and ok["time_median_s"].notna().any():
            row["time_median_s"] = float(ok["time_median_s"].median())
        groups.append(row)
    return pd.DataFrame(groups)


#: the generators' parameters that are lengths (``datasets.synthetic``: lengths in the unit of the data)
DATA_LENGTHS = ("data_center", "data_radius", "data_semi_axes", "data_noise")


def summary_units(summary: pd.DataFrame, cfg: dict | None = None) -> dict[str, str]:
    """{column: unit} of a :func:`summarise` table ('' for counts and shares): each statistic of a row column
    takes that column's declared unit (``experiments.units.column_unit``: the result classes' declarations, s for
    timings, a unit suffix such as ``_deg``); lengths in the study's own length unit where it declares one
    (``experiments.units.data_length_unit``: else mm for the machine-tool data, else the data's own units)."""
    from experiments.units import LENGTH_UNITS, column_unit, data_length_unit
    lengths = data_length_unit(cfg)
    source = {"form_error_median": "form_error", "iterations_median": "iterations", "time_median_s": "time_median_s"}
    for col in result_base.truth_error_columns():
        name = col.replace("_error", "")
        source[f"{name}_rmse"] = source[f"{name}_bias"] = col
    units = {}
    for c in summary.columns:
        if c in ("runs", "ok_share"):
            units[c] = ""
            continue
        unit = column_unit(source.get(c, c))
        if lengths and (unit in LENGTH_UNITS or (c in DATA_LENGTHS and not unit)):
            unit = lengths
        elif c in DATA_LENGTHS and not unit:
            unit = column_unit("form_error")     # a length of the data: the declared length unit
        units[c] = unit
    return units


def share_text(value, digits: int = 4) -> str:
    """A share (0 to 1) in ``digits`` significant digits, with as many more as it takes that a share below 1 never
    reads 1 and one above 0 never reads 0 (1 crashed row of 25,000: 0.99996, not 1); NaN is empty."""
    v = float(value)
    if v != v:
        return ""
    for d in range(digits, 18):
        text = format(v, f".{d}g")
        if (float(text) == 1.0) == (v == 1.0) and (float(text) == 0.0) == (v == 0.0):
            return text
    return repr(v)


#: the summary's columns that are shares (:func:`share_text`)
SHARE_COLUMNS = ("ok_share",)


def with_units(df: pd.DataFrame, units: dict[str, str]) -> pd.DataFrame:
    """``df`` whose columns with a unit name it in brackets ('form_error_median [data units]', as summary.md's
    headers do): the summary as a report table (the fallback table of a study whose analysis gives none)."""
    from experiments.render.text import human_unit
    return df.rename(columns={c: f"{c} [{human_unit(units[c])}]" for c in df.columns if units.get(c)})


def to_markdown(df: pd.DataFrame, floatfmt: str = ".4g", units: dict[str, str] | None = None) -> str:
    """A GitHub Markdown table (``experiments.render.page.markdown_table``) whose headers carry the units
    (``units``: {column: unit}, default :func:`summary_units` of ``df``): 'form error median [mm]'. Numbers in
    ``floatfmt``, shares by :func:`share_text` (never a rounded 1 or 0)."""
    from experiments.render.markdown import markdown_table
    from experiments.render.text import human_unit
    from experiments.units import readable
    units = summary_units(df) if units is None else units
    names = {c: readable(c) + (f" [{human_unit(units[c])}]" if units.get(c) else "") for c in df.columns}
    shown = df.rename(columns=names)
    return markdown_table(shown, floatfmt, escape=False,
                          formats={names[c]: share_text for c in SHARE_COLUMNS if c in names}) + "\n"
