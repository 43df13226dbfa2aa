"""The analysis step of a run, after its rows: the study's own analysis (:meth:`experiments.study.Study.analyse`),
the default table and figure of a study that has none and declares none (chosen from its metrics), the tables and
figures its TOML declares, and the one line of a study none of whose rows has a result."""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from experiments.figures import declared_figure
from experiments.jsontext import json_text, json_value
from experiments.study import Analysis, Study
from experiments.tables import declared_table
from experiments.units import aggregate_words, metric_unit, readable
from methods import results


def analyse(study: Study, df: pd.DataFrame, cfg: dict, target: Path, log) -> tuple[dict, Analysis]:
    """Run a study's analysis (:meth:`Study.analyse`; for a study without its own, the table and the figure
    :func:`default_declarations` chooses for what the TOML does not declare) and add the TOML's declared tables and
    figures; return (the named values for meta.json, Analysis). Without rows (a study refused before its run has
    none) there is nothing to analyse: no table, no figure."""
    if not len(df):
        return {"n_rows": 0, "n_ok": 0}, Analysis(values={"n_rows": 0, "n_ok": 0})
    analysis = study.analyse(df, cfg, target, log)
    if not study.own_analysis and not (cfg.get("tables") and cfg.get("figures")):
        table, figure = default_declarations(cfg, df)
        if table and not cfg.get("tables"):
            analysis.tables.append(declared_table(df, table, cfg))
        if figure and not cfg.get("figures"):
            analysis.figures.append(declared_figure(df, figure, target, 1, cfg))
    analysis.values = {"n_rows": len(df), "n_ok": int((df["status"] == "ok").sum()), **analysis.values}
    findings = json_value(json_text(analysis.values))  # what meta.json holds: plain values, as read back from it
    analysis.tables += [declared_table(df, t, cfg) for t in cfg.get("tables", [])]
    for f in cfg.get("figures", []):
        analysis.figures.append(declared_figure(df, f, target, len(analysis.figures) + 1, cfg))
    return findings, analysis


#: the statuses of a row that has a result: the method returned one and the gate accepted it (``docs/results.md``)
RESULT_STATUSES = ("ok", "not converged")


def failed_rows(cfg: dict, rows) -> str | None:
    """The one line of a study none of whose rows has a result (every row ``error``, ``invalid``, ``skipped``,
    ``timeout``, ...: ``python -m experiments.run`` then exits 1), naming the most frequent reason; None when a row
    has a result. ``rows``: the rows (``status`` and ``message``), or the study's ``results.csv``."""
    if not isinstance(rows, pd.DataFrame):
        try:   # meta.json's counts: a study with a result is not read again
            counts = json_value((Path(rows).parent / "meta.json").read_text(encoding="utf-8")).get("status_counts")
            if any(counts.get(s) for s in RESULT_STATUSES):
                return None
        except (OSError, ValueError, AttributeError):
            pass
        try:
            rows = pd.read_csv(rows, usecols=["status", "message"], keep_default_na=False, dtype=str)
        except (OSError, ValueError):
            return None
    if not len(rows) or rows["status"].isin(RESULT_STATUSES).any():
        return None
    counts = ", ".join(f"{n:,} {status}" for status, n in rows["status"].value_counts().items())
    reasons = rows.groupby(["status", "message"], sort=False, dropna=False).size().sort_values(ascending=False,
                                                                                                kind="stable")
    (status, message), n = reasons.index[0], int(reasons.iloc[0])
    message = " ".join(str(message).split())
    message = message if len(message) <= 200 else message[:199] + "…"
    return (f"{cfg.where}: {len(rows):,} of {len(rows):,} rows failed ({counts}), none has a result; most often "
            f"{status}: {message} ({n:,} row{'s' if n > 1 else ''}); the rows and their messages are in results.csv")


def _varying(df: pd.DataFrame) -> tuple[list[str], list[str]]:
    """(the numeric data parameters that vary, in the rows' order; every other varying grouping key: a text data
    parameter, the method's params, the data set)."""
    numeric, other = [], []
    for c in df.columns:
        if c.startswith("data_") and c != "data_stream" and df[c].nunique() > 1:
            (numeric if pd.api.types.is_numeric_dtype(df[c]) else other).append(c)
    other += [c for c in ("params", "dataset") if c in df and df[c].nunique() > 1]
    return numeric, other


def _and(words: list[str]) -> str:
    """'a', 'a and b', 'a, b and c'."""
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} and {words[-1]}"


def default_declarations(cfg: dict, df: pd.DataFrame) -> tuple[dict | None, dict | None]:
    """The table and figure of a study that declares none, chosen from its metrics: the first error against the
    truth its rows have (RMSE), else the form error (median); per method, against the first data parameter that
    varies (else per data set), and per value of every other parameter that varies (nothing pooled silently: a
    table row and a figure line each). Units come from the metric declarations (``methods.results``); a length is in
    the study's ``length_unit``, else mm for the machine-tool data, else the data's own unit (:func:`experiments.units.metric_unit`)."""
    ok = (df["status"] == "ok").to_numpy() if "status" in df else slice(None)  # a mask: no copy of the rows
    errors = results.truth_error_columns()
    metric = next((c for c in (*errors, "form_error")
                   if c in df and pd.to_numeric(df[c].iloc[ok], errors="coerce").notna().any()),
                  None)
    if metric is None:
        return None, None
    how = "rmse" if metric in errors else "median"
    unit, unit_note = metric_unit(cfg, metric)
    numeric, other = _varying(df)
    across = numeric[0] if numeric else ("dataset" if "dataset" in other else None)
    keys = [c for c in (*numeric[1:], *other) if c != across]   # every other varying parameter: its own rows
    rows = ["method"] + keys
    what = aggregate_words(how, metric)
    shown = f"{what} [{unit}]" if unit else what
    n_ok = len(df) if isinstance(ok, slice) else int(ok.sum())
    over = f"{len(df)} rows" if n_ok == len(df) else f"the {n_ok} ok rows of {len(df)}"  # the others are not in it
    per = _and([readable(c) for c in (*rows, *([across] if across else []))])
    table = {"caption": f"{what} per {per} over {over} of {cfg['name']} (the default table of a study that declares "
                        f"none).{unit_note}",
             "rows": rows, "values": metric, "aggregate": how, "unit": unit, "digits": 4, "colour": "lower_is_better",
             **({"columns": across} if across else {})}
    by = ["method", *keys] if keys else "method"
    lines_of = "one line per " + _and([readable(c) for c in ("method", *keys)])
    if numeric:
        figure = {"plot": "lines", "x": numeric[0], "y": metric, "by": by, "aggregate": how, "ylabel": shown,
                  "caption": f"{shown} against {readable(numeric[0])}, {lines_of}.{unit_note}"}
    else:
        figure = {"plot": "bars", "x": by, "y": metric, "aggregate": how, "ylabel": shown,
                  **({} if isinstance(by, str) else {"xlabel": ", ".join(readable(c) for c in by)}),
                  "caption": f"{shown} per {_and([readable(c) for c in rows])}.{unit_note}"}
    return table, figure
