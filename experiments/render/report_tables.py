"""A declared table of the report in LaTeX and HTML: the bridge between a study's table CSV (caption, unit,
significant digits, optional ``colour``, the columns' declared ``decimals`` and ``exact``) and the renderers ``latex.latex_table`` / ``html_tables.coloured_table``.

``latex_fragments`` never returns an overflowing table: a table too wide for the page (``TableTooWide``) is
split into parts that keep the key (text) columns and share out the number columns; a table that cannot fit
even with one number column becomes a note pointing to its CSV.
"""
from __future__ import annotations

import re

import numpy as np
import pandas as pd

from experiments.render.html_tables import coloured_table, plain_table
from experiments.render.numbers import (declared_format, header_unit, human_header, human_unit_text, is_count,
                                        table_formats)
from experiments.render.latex import Column, TableTooWide, latex_table
from experiments.render.text import human_unit, tex

MAX_DIGITS = 4   #: significant digits shown in the paper (the CSV keeps all)


def _numeric(s: pd.Series) -> bool:
    return pd.api.types.is_numeric_dtype(s) and not pd.api.types.is_bool_dtype(s)


def split_columns(df: pd.DataFrame) -> tuple[list[str], list[str]]:
    """(key columns = text, value columns = numbers) in table order."""
    keys = [c for c in df.columns if not _numeric(df[c])]
    return keys, [c for c in df.columns if c not in keys]


def _integral(s: pd.Series) -> bool:
    """A count column: integer dtype, or floats that are all whole numbers (a CSV column with a gap)."""
    if pd.api.types.is_integer_dtype(s):
        return True
    v = s.dropna().to_numpy(float)
    return pd.api.types.is_float_dtype(s) and len(v) > 0 and bool(np.all(np.isfinite(v) & (v == np.round(v)))) \
        and bool(np.all(np.abs(v) < 2 ** 53))


def column_unit(name, s: pd.Series, unit: str) -> str:
    """The table's unit for this column's header: none for a column whose name already carries one
    ("error [mm]") or that counts something (runs, iterations, ...: ``numbers.is_count``); every other number
    column carries it, whole-numbered or not (a share of 100 % is a percentage like 87.5 %)."""
    if "[" in str(name) or is_count(name):
        return ""
    return header_unit(name) or unit or ""


#: a column of published values (``published``, ``published [µm]``): each number as the source printed it
PUBLISHED = re.compile(r"^\s*published\s*(\[[^\]]*\])?\s*$", re.I)


def _formats(df: pd.DataFrame, values, unit: str, digits: int, decimals: dict | None = None, exact=()) -> dict:
    """One format per number column (``numbers.table_formats``): the declared ones (``decimals``: {column: n}
    fixed decimals; ``exact``: as given) as declared; of the others, columns with the same unit, from their header
    or the table's, share one; counts are formatted alone."""
    # a table with a unit column gives each row's numbers in that row's unit: its columns share one format
    # (an estimate and the injected value it is compared with, at one resolution)
    per_row = "the row's unit" if any(str(c).strip().lower() in ("unit", "units") for c in df.columns) else None
    units = {c: (None if is_count(c) else (header_unit(c) or unit or per_row)) for c in values}
    # published values are printed as published (27, not 27.00), unless declared otherwise
    published = [c for c in values if c not in (decimals or {}) and PUBLISHED.match(str(c))]
    return table_formats(df, values, units, max(1, min(int(digits or 3), MAX_DIGITS)),
                         declared=declared_format(decimals, tuple(exact or ()) + tuple(published)))


def _humanised(df: pd.DataFrame) -> pd.DataFrame:
    """Unit columns (named unit/units) with µm, µrad, µm/m for um, urad, um/m."""
    cols = [c for c in df.columns if str(c).strip().lower() in ("unit", "units") and not _numeric(df[c])]
    if not cols:
        return df
    df = df.copy()
    for c in cols:
        df[c] = df[c].map(human_unit_text)
    return df


def _header(c) -> str | None:
    """The LaTeX header of column ``c`` when it differs from the name (µ units; underscores outside maths as
    spaces), else None (the renderer's default)."""
    shown = human_header(c)
    if shown == str(c):
        return None
    import re
    return "".join(p if p.startswith("$") else p.replace("_", " ") for p in re.split(r"(\$[^$]+\$)", shown))


def _columns(df: pd.DataFrame, keys, values, unit: str, digits: int, decimals: dict | None = None,
             exact=()) -> list[Column]:
    cols = []
    for i, c in enumerate(keys):
        repeated = len(df) > 1 and df[c].duplicated().any() and len(keys) > 1 and i == 0
        cols.append(Column(str(c), header=_header(c), kind="text", group=bool(repeated)))
    formats = _formats(df, values, unit, digits, decimals, exact)
    for c in values:
        fmt = formats[c]
        header = _header(c)
        u = column_unit(c, df[c], unit) or None
        if fmt.kind == "exact":
            cols.append(Column(str(c), header=header, unit=u, kind="number", exact=True))
        elif fmt.kind == "integer":
            cols.append(Column(str(c), header=header, unit=u, kind="integer"))
        elif fmt.kind == "fixed":
            cols.append(Column(str(c), header=header, unit=u, kind="number", decimals=fmt.decimals, exponent=False))
        else:   # exponent: every cell 4.07e8; significant: plain between 1e-3 and 1e5, as NumberFormat.text
            cols.append(Column(str(c), header=header, unit=u, kind="number", digits=fmt.decimals + 1,
                               exponent=True if fmt.kind == "exponent" else None))
    return cols


def latex_fragments(df: pd.DataFrame, *, caption: str, label: str, unit: str = "", digits: int = 4,
                    decimals: dict | None = None, exact=()) -> list[str]:
    """One or more LaTeX fragments for the table (more than one when it had to be split). ``decimals`` ({column:
    n}) and ``exact`` (columns) are the table's declared formats (``study.Table``), the same in every rendering."""
    df = _humanised(df)
    keys, values = split_columns(df)
    # a table of methods: a value may not apply there (a station error with known stations) or the method did
    # not run or failed; a table of other rows (an error source the test does not estimate) blames no method
    methods_rows = any(str(c).strip().lower() in ("method", "methods") for c in keys) or \
        any(str(c).startswith(("circle.", "ellipse.")) for c in values)
    notes = ([f"-- : no value{' (it does not apply there, or the method did not run or failed)' if methods_rows else ''}"]
             if (df.isna() | df.isin([np.inf, -np.inf])).any().any() else None)   # inf: failed (a ranking's median)

    def attempt(vals, cap, lab):
        return latex_table(df[keys + vals], _columns(df, keys, vals, unit, digits, decimals, exact), caption=cap,
                           label=lab, notes=notes)

    try:
        return [attempt(values, caption, label)]
    except TableTooWide:
        pass
    parts = [values]
    while True:
        widest = max(parts, key=len)
        if len(widest) <= 1:
            break
        i = parts.index(widest)
        half = (len(widest) + 1) // 2
        parts[i:i + 1] = [widest[:half], widest[half:]]
        try:
            return [attempt(p, f"{caption} (part {k + 1} of {len(parts)})", f"{label}-{k + 1}")
                    for k, p in enumerate(parts)]
        except TableTooWide:
            continue
    return [f"\\begin{{table}}[htbp]\\centering\\small\\caption{{{tex(caption)}}}\\label{{tab:{label}}}\n"
            f"\\parbox{{0.9\\linewidth}}{{Too wide for the page even with one number column per part; the data are in "
            f"the report's \\texttt{{tables/{label}.csv}}.}}\n\\end{{table}}\n"]


def html_table(df: pd.DataFrame, *, caption: str, unit: str = "", digits: int = 4, colour: str = "",
               table_id: str = "table", decimals: dict | None = None, exact=()) -> str:
    """The table as self-contained HTML with ``<caption>`` (``html_tables``, pandas' Styler);
    ``colour='lower_is_better'``: the number columns are methods (or other competitors), each cell coloured by
    its ratio to the row's lowest value."""
    df = _humanised(df)
    keys, values = split_columns(df)
    if colour == "lower_is_better" and values and keys:
        t = df.set_index(keys)[values]
        t.index = [" | ".join(map(str, k)) if isinstance(k, tuple) else str(k) for k in t.index]
        t.index.name = " | ".join(keys)
        numbers = t.to_numpy(float)
        if np.all(np.isnan(numbers) | (numbers >= 0)):
            formats = _formats(t, list(t.columns), unit, digits, decimals, exact)
            return coloured_table(t, unit=human_unit(unit), caption=caption, table_id=table_id,
                                  formats=[formats[c] for c in t.columns])
    headers = {c: human_header(c) + (f" [{human_unit(u)}]" if c in values and (u := column_unit(c, df[c], unit)) else "")
               for c in df.columns}
    return plain_table(df, caption=caption, headers=headers, formats=_formats(df, values, unit, digits, decimals, exact),
                       table_id=table_id)


def text_frame(df: pd.DataFrame, *, unit: str = "", digits: int = 4, decimals: dict | None = None,
               exact=()) -> pd.DataFrame:
    """The table as the HTML shows it, every cell text: number columns in their one format per column
    (``_formats``), headers with their unit; for the Markdown rendering, which must not choose its own."""
    df = _humanised(df)
    keys, values = split_columns(df)
    formats = _formats(df, values, unit, digits, decimals, exact)
    out = pd.DataFrame({c: (df[c].map(lambda v, f=formats[c]: f.text(float(v)) if v == v else "–") if c in values
                            else df[c].map(lambda v: "" if v != v else str(v)))
                        for c in df.columns})
    out.columns = [human_header(c) + (f" [{human_unit(u)}]" if c in values and (u := column_unit(c, df[c], unit))
                                      else "") for c in df.columns]
    return out
