"""The tables a study declares (``[[tables]]`` in its TOML, and the default table of a study that declares none):
pivots and grouped aggregates of its ok rows, with their caption, unit and digits. The rows of a data set without
the parameter a table is keyed on stay, under :data:`NO_VALUE`, and the caption names those data sets."""
from __future__ import annotations

import numpy as np
import pandas as pd

from experiments.study import ConfigError, Table
from experiments.units import DATA_UNITS, aggregate_words, column_unit, metric_unit, readable, table_unit

#: the aggregates a ``[[tables]]`` or ``[[figures]]`` entry may name (``aggregate = "rmse"``)
AGGREGATES = {
    "mean": "mean", "median": "median", "max": "max", "min": "min", "std": "std", "count": "count",
    "rmse": lambda s: float(np.sqrt(np.mean(np.square(s.astype(float))))) if len(s) else np.nan,
}
#: the key of the rows of the data sets that lack a table's key parameter ('share = none'), the legend of their line
NO_VALUE = "none"


def rows_where(df: pd.DataFrame, cond: dict | None) -> pd.DataFrame:
    """The rows whose columns hold the values a declaration's ``where = {column = value or [values]}`` names."""
    for k, v in (cond or {}).items():
        df = df[df[k].isin(v if isinstance(v, list) else [v])]
    return df


def _no_result(df: pd.DataFrame) -> str:
    """Why the rows lack a column the config's check expected (a metric): none of them has a result; their
    statuses and most frequent message (empty when some row has a result)."""
    if "status" not in df.columns or df["status"].isin(("ok", "not converged")).any() or not len(df):
        return ""
    counts = ", ".join(f"{n:,} {s}" for s, n in df["status"].value_counts().items())
    message = str(df["message"].mode().iloc[0])[:200] if "message" in df.columns and df["message"].notna().any() else ""
    return f": no row has a result ({counts}{f'; most often: {message}' if message else ''})"


def declared_table(df: pd.DataFrame, t: dict, cfg: dict | None = None) -> Table:
    """A pivot (or a grouped aggregate) of the rows, as declared, in the declared unit: values converted from their
    own (a length in the study's unit of lengths, ``cfg``; :func:`experiments.units.table_unit`), labelled with their
    own unit when the table declares none."""
    rows = [t["rows"]] if isinstance(t["rows"], str) else list(t["rows"])
    how = t.get("aggregate", "mean")
    value = t["values"]
    try:
        unit, factor = table_unit(cfg, value, t.get("unit", ""), how)
    except ValueError as exc:   # the config's check refuses it before any row runs
        raise ConfigError(f"table {t['caption'][:40]!r}: {exc}") from None
    # only the columns read below (selecting the rows of the whole frame would copy every column)
    used = [*rows, *([t["columns"]] if t.get("columns") else []), value, "status", *(t.get("where") or {})]
    data = rows_where(df[[c for c in dict.fromkeys(used) if c in df.columns]], t.get("where"))
    if how == "ok_share":
        data = data.assign(_ok=(data["status"] == "ok").astype(float))
        value, how = "_ok", "mean"
    else:
        data = data[data["status"] == "ok"]
    for c in rows + ([t["columns"]] if t.get("columns") else []) + [value]:
        if c not in data.columns:
            raise ConfigError(f"table {t['caption'][:40]!r}: no column {c!r} in the rows{_no_result(df)} "
                              f"(columns: {', '.join(df.columns)})")
    if factor != 1.0:   # shown in another unit of the same dimension (mm rows in µm): every aggregate scales with it
        data = data.assign(**{value: pd.to_numeric(data[value], errors="coerce") * factor})
    # a key some rows lack (a data parameter of one data set, not of another) keeps those rows under NO_VALUE: the
    # groupby keeps NaN keys (pivot_table drops them, and every group whose value is NaN: rows nobody would see)
    lacking = [c for c in rows + ([t["columns"]] if t.get("columns") else []) if data[c].isna().any()]
    numeric_keys = {c for c in rows if pd.api.types.is_numeric_dtype(data[c])}
    if t.get("columns"):
        col = t["columns"]
        out = data.groupby([*rows, col], sort=False, dropna=False)[value].agg(AGGREGATES[how]).unstack(col)
        key_unit = column_unit(col)  # a pivot column names its key with the key's own unit: 'data_arc_deg = 90 °'
        key = readable(col)
        out.columns = [f"{key} = {NO_VALUE}" if c is None or c != c else
                       f"{key} = {c:g}{' ' + key_unit if key_unit else ''}" if isinstance(c, (int, float))
                       else f"{key} = {c}" for c in out.columns]
        out = out.reset_index()
    else:
        out = data.groupby(rows, sort=False, dropna=False)[value].agg(AGGREGATES[how]).reset_index()
        out = out.rename(columns={value: aggregate_words(t.get("aggregate", "mean"), t["values"])})
    for c in rows:
        if c in lacking:
            out[c] = out[c].astype(object).where(out[c].notna(), NO_VALUE)
    # a numeric key column carries its own unit in its name, so the table's unit never labels it
    out = out.rename(columns={c: f"{readable(c)} [{column_unit(c)}]" for c in rows
                              if column_unit(c) and c in numeric_keys})
    caption = t["caption"] + lacking_note(df, lacking)
    if t.get("columns") and t.get("aggregate") in ("ok_share", "count"):
        # a pivot's headers are the column key's values: the caption says what the cells count
        caption = caption.rstrip() + ("" if caption.rstrip().endswith((".", "!", "?")) else ".")
        caption += (" Values: the share of rows whose status is ok" + ("." if unit == "%" else " (0 to 1).")
                    if t["aggregate"] == "ok_share" else f" Values: the count of ok rows with {readable(t['values'])}.")
    if unit == DATA_UNITS and not t.get("unit"):   # how to name the data's unit, as the default table says
        caption = caption.rstrip() + ("" if caption.rstrip().endswith((".", "!", "?")) else ".")
        caption += metric_unit(cfg or {}, t["values"])[1]
    return Table(caption=caption, data=out, unit=unit, digits=t.get("digits", 4),  # significant digits
                 colour=t.get("colour", ""))


def lacking_note(df: pd.DataFrame, lacking: list[str], drawn: bool = True) -> str:
    """A caption's sentence naming the data sets that lack a key parameter of a table (their rows are under
    :data:`NO_VALUE`), or of a figure's x axis (``drawn=False``: their rows cannot be placed), '' for none."""
    notes = []
    for c in lacking:
        sets = list(dict.fromkeys(df.loc[df[c].isna(), "dataset"].astype(str))) if "dataset" in df else []
        named = f" ({', '.join(sets[:5])}{', ...' if len(sets) > 5 else ''})" if sets else ""
        notes.append(f" The data sets without {readable(c)}{named} are under '{NO_VALUE}'." if drawn else
                     f" Not drawn: the {int(df[c].isna().sum()):,} of {len(df):,} ok rows of the data sets without "
                     f"{readable(c)}{named}.")
    return "".join(notes)
