"""The study contract: what a study declares, and the one interface through which its analysis reaches
the report. The report (``experiments.report``) renders only this; it knows no study by name.

A study is one TOML file (``experiments/configs/NAME.toml``, or any path)::

    name = "my_study"                    # = the file name
    title = "Kasa against Gauss-Newton on a short arc"
    kind = "grid"                        # the generic engine; or a module experiments/studies/KIND.py
    seed = 7
    repetitions = 20
    summary_by = ["dataset", "data_arc_deg", "method", "params"]   # never data_stream / repetition

    [report]
    section = "My comparisons"           # the report section (heading) this study belongs to
    order = 100                          # place in the report (default 1000; ties: by name); a section
                                         # sits where its first study does
    findings = "{best_method} has the smallest radius RMSE ({best_value:.3g} mm)."  # optional, from values

    [[datasets]]
    source = "circle"                    # any registered data source (datasets.sources), or:
    params = { radius = 5.0, noise = 0.01, n = 30 }
    grid = { arc_deg = [360.0, 90.0] }
    [[datasets]]
    file = "trace.csv"                   # relative to this TOML; any format datasets.read_points reads

    [[methods]]
    id = "circle.*"

    [[tables]]                           # a pivot of the rows
    caption = "Radius RMSE by arc; synthetic circles of radius 5 mm, noise 0.01 mm, 20 repetitions"
    rows = ["method"]                    # index columns
    columns = "data_arc_deg"             # optional: one column whose values become table columns
    values = "radius_error"
    aggregate = "rmse"                   # mean | median | max | min | std | rmse | count | ok_share
    unit = "mm"                          # shown in the caption and the header
    digits = 4                           # significant digits (default 4)

    [[figures]]                          # a registered plot (experiments.study.PLOTS) ...
    plot = "lines"
    x = "data_arc_deg"
    y = "radius_error"
    by = "method"
    aggregate = "rmse"
    logy = true
    caption = "Radius RMSE against the arc length [mm]; what to look for: ..."
    [[figures]]                          # ... or a file the study's Python analysis wrote
    file = "noise_kcr.png"
    caption = "..."

Python is needed only for analysis a config cannot express: the study module defines
``analyse(df, cfg, target, log) -> Analysis`` (tables, figures it saved under ``target``, named values
and a findings text built from those values); the values also land in ``meta.json['findings']``. A study
whose numbers need more computation than its rows declares it as tasks (``tasks(cfg)`` + ``execute(task)``),
so that the engine caches, resumes and parallelises it; ``analyse`` only aggregates rows.

``run.py`` writes ``report.json`` (the manifest: sections, numbered later by the report) and one CSV
per table under ``target/tables/``; everything atomically.
"""
from __future__ import annotations

import io
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from experiments.engine import ConfigError
from experiments.provenance import write_atomic
from methods.files import atomic_path  # noqa: F401  (the one atomic writer, for writers that take a file name)

DEFAULT_SECTION = "Other studies"
AGGREGATES = {
    "mean": "mean", "median": "median", "max": "max", "min": "min", "std": "std", "count": "count",
    "rmse": lambda s: float(np.sqrt(np.mean(np.square(s.astype(float))))) if len(s) else np.nan,
}


@dataclass
class Table:
    """A table for the report: caption (what, on what data), unit of its numbers, the data."""

    caption: str
    data: pd.DataFrame = field(repr=False)
    unit: str = ""
    digits: int = 7
    colour: str = ""   #: "lower_is_better": a method comparison, coloured per row in the HTML report


@dataclass
class Figure:
    """A figure the study saved (a PNG, path relative to the study folder) with its caption."""

    caption: str
    file: str


@dataclass
class Analysis:
    """What a study's analysis returns: its tables, figures, named values and a findings text built
    from the values (never hand-written numbers)."""

    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    values: dict = field(default_factory=dict)
    findings: str = ""


# ---------------------------------------------------------------- plot registry

PLOTS: dict[str, Callable] = {}


def register_plot(name: str):
    """Register ``func(df, ax, **arguments)`` (draws on a matplotlib axis) as plot ``name``."""
    def deco(func):
        PLOTS[name] = func
        return func
    return deco


def _aggregate(df, by, y, how):
    agg = AGGREGATES[how]
    return df.groupby(by, sort=False, dropna=False)[y].agg(agg)


@register_plot("lines")
def lines(df, ax, *, x, y, by=None, aggregate="mean", logx=False, logy=False, xlabel=None, ylabel=None):
    """One line per value of ``by``: ``aggregate`` of ``y`` against ``x``."""
    groups = df.groupby(by, sort=False) if by else [(y, df)]
    for label, g in groups:
        s = _aggregate(g, x, y, aggregate).sort_index()
        ax.plot(s.index, s.values, marker="o", ms=3, label=str(label))
    ax.set_xscale("log" if logx else "linear")
    ax.set_yscale("log" if logy else "linear")
    ax.set_xlabel(xlabel or x)
    ax.set_ylabel(ylabel or f"{aggregate} of {y}")
    if by:
        ax.legend(fontsize=8, loc="best")


@register_plot("bars")
def bars(df, ax, *, x, y, aggregate="mean", logy=False, xlabel=None, ylabel=None):
    """One bar per value of ``x``: ``aggregate`` of ``y``."""
    s = _aggregate(df, x, y, aggregate)
    ax.bar(range(len(s)), s.values)
    ax.set_xticks(range(len(s)), [str(v) for v in s.index], rotation=30, ha="right", fontsize=8)
    ax.set_yscale("log" if logy else "linear")
    ax.set_xlabel(xlabel or x)
    ax.set_ylabel(ylabel or f"{aggregate} of {y}")


# ---------------------------------------------------------------- declarations

TABLE_KEYS = {"caption", "rows", "columns", "values", "aggregate", "unit", "digits", "where", "colour"}
FIGURE_KEYS = {"caption", "plot", "file", "args", "x", "y", "by", "aggregate", "logx", "logy", "xlabel", "ylabel",
               "width", "height", "where"}
REPORT_KEYS = {"section", "order", "findings"}


def validate(cfg: dict, where: str) -> None:
    """Check the declarative keys (tables, figures, report) before any row runs."""
    rep = cfg.get("report", {})
    if not isinstance(rep, dict) or set(rep) - REPORT_KEYS:
        raise ConfigError(f"{where}: [report] must be a table with keys {', '.join(sorted(REPORT_KEYS))}")
    if "order" in rep and not isinstance(rep["order"], int):
        raise ConfigError(f"{where}: report.order must be an integer, got {rep['order']!r}")
    for i, t in enumerate(cfg.get("tables", [])):
        here = f"{where} tables[{i}]"
        if not isinstance(t, dict):
            raise ConfigError(f"{here}: each table is a TOML table")
        bad = set(t) - TABLE_KEYS
        if bad:
            raise ConfigError(f"{here}: unknown key(s) {', '.join(sorted(bad))} (known: {', '.join(sorted(TABLE_KEYS))})")
        for k in ("caption", "rows", "values"):
            if k not in t:
                raise ConfigError(f"{here}: missing key {k!r}")
        if t.get("colour", "lower_is_better") != "lower_is_better":
            raise ConfigError(f"{here}: colour must be 'lower_is_better' (cells coloured by their ratio to the row's "
                              f"lowest value), got {t['colour']!r}")
        if t.get("aggregate", "mean") not in AGGREGATES and t.get("aggregate") != "ok_share":
            raise ConfigError(f"{here}: aggregate must be one of {', '.join(AGGREGATES)}, ok_share")
    for i, f in enumerate(cfg.get("figures", [])):
        here = f"{where} figures[{i}]"
        if not isinstance(f, dict):
            raise ConfigError(f"{here}: each figure is a TOML table")
        bad = set(f) - FIGURE_KEYS
        if bad:
            raise ConfigError(f"{here}: unknown key(s) {', '.join(sorted(bad))} (known: {', '.join(sorted(FIGURE_KEYS))})")
        if "caption" not in f or ("plot" in f) == ("file" in f):
            raise ConfigError(f"{here}: needs a caption and exactly one of plot (a registered plot: "
                              f"{', '.join(PLOTS)}) and file (a PNG the study's analysis writes)")
        if "plot" in f and f["plot"] not in PLOTS:
            raise ConfigError(f"{here}: unknown plot {f['plot']!r}; known: {', '.join(PLOTS)}")
        if "file" in f and (Path(f["file"]).is_absolute() or ".." in Path(f["file"]).parts):
            raise ConfigError(f"{here}: file must be a path inside the study's folder, got {f['file']!r}")


def _where(df, cond):
    for k, v in (cond or {}).items():
        df = df[df[k].isin(v if isinstance(v, list) else [v])]
    return df


def declared_table(df: pd.DataFrame, t: dict) -> Table:
    """A pivot (or a grouped aggregate) of the rows, as declared."""
    rows = [t["rows"]] if isinstance(t["rows"], str) else list(t["rows"])
    how = t.get("aggregate", "mean")
    data = _where(df, t.get("where"))
    value = t["values"]
    if how == "ok_share":
        data = data.assign(_ok=(data["status"] == "ok").astype(float))
        value, how = "_ok", "mean"
    else:
        data = data[data["status"] == "ok"]
    for c in rows + ([t["columns"]] if t.get("columns") else []) + [value]:
        if c not in data.columns:
            raise ConfigError(f"table {t['caption'][:40]!r}: no column {c!r} in the rows "
                              f"(columns: {', '.join(df.columns)})")
    if t.get("columns"):
        out = data.pivot_table(index=rows, columns=t["columns"], values=value, aggfunc=AGGREGATES[how], sort=False)
        out.columns = [f"{t['columns']}={c}" for c in out.columns]
        out = out.reset_index()
    else:
        out = data.groupby(rows, sort=False, dropna=False)[value].agg(AGGREGATES[how]).reset_index()
        out = out.rename(columns={value: f"{how} of {t['values']}"})
    return Table(caption=t["caption"], data=out, unit=t.get("unit", ""), digits=t.get("digits", 4),  # significant digits
                 colour=t.get("colour", ""))  # significant digits


def declared_figure(df: pd.DataFrame, f: dict, target: Path, number: int) -> Figure:
    if "file" in f:
        return Figure(caption=f["caption"], file=f["file"])
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    args = {k: f[k] for k in ("x", "y", "by", "aggregate", "logx", "logy", "xlabel", "ylabel") if k in f}
    args.update(f.get("args", {}))
    fig, ax = plt.subplots(figsize=(f.get("width", 6.4), f.get("height", 4.2)))
    PLOTS[f["plot"]](_where(df[df["status"] == "ok"], f.get("where")), ax, **args)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    name = f"figure_{number}_{f['plot']}.png"
    save_figure(fig, target / name)
    plt.close(fig)
    return Figure(caption=f["caption"], file=name)


def save_figure(fig, path: Path, dpi: float = 110) -> None:
    """Save a matplotlib figure atomically (:func:`fitbench.plots.save_atomic`: a kill never leaves a
    half-written PNG)."""
    from fitbench.plots import save_atomic
    save_atomic(fig, path, dpi=dpi)


def save_csv(df: pd.DataFrame, path: Path, **kwargs) -> None:
    """``df.to_csv(path, **kwargs)``, written atomically."""
    buf = io.StringIO()
    df.to_csv(buf, **kwargs)
    write_atomic(path, buf.getvalue())


def remove_leftover_tmp(folder: Path) -> None:
    """Remove ``*.tmp`` files an interrupted atomic write left behind."""
    if folder.is_dir():
        for pattern in (".*.tmp", ".*.tmp.*"):
            for p in folder.rglob(pattern):
                p.unlink(missing_ok=True)


def write_manifest(target: Path, cfg: dict, analysis: Analysis, summary: pd.DataFrame) -> None:
    """``report.json`` and ``tables/*.csv``: everything the report renders for this study."""
    tables_dir = target / "tables"
    if tables_dir.is_dir():  # never mix the tables of two runs
        for p in tables_dir.glob("*.csv"):
            p.unlink()
    tables = analysis.tables or [Table(caption=f"Summary of {cfg['name']}: one row per data set and method "
                                               "(runs, share ok, medians, bias and RMSE against the truth)",
                                       data=summary)]
    entries = []
    for k, t in enumerate(tables):
        buf = io.StringIO()
        t.data.to_csv(buf, index=False, float_format="%.10g")
        name = f"tables/table_{k + 1}.csv"
        write_atomic(target / name, buf.getvalue())
        entries.append({"caption": t.caption, "file": name, "unit": t.unit, "digits": t.digits,
                        **({"colour": t.colour} if t.colour else {})})
    rep = cfg.get("report", {})
    findings = analysis.findings
    if not findings and rep.get("findings"):
        try:
            findings = rep["findings"].format(**analysis.values)
        except (KeyError, ValueError, IndexError) as exc:
            findings = f"(findings template not filled: {exc})"
    manifest = {"title": cfg["title"], "section": rep.get("section", DEFAULT_SECTION), "order": rep.get("order", 1000),
                "quick": bool(cfg.get("_quick")), "tables": entries,
                "figures": [{"caption": f.caption, "file": f.file} for f in analysis.figures],
                "values": analysis.values, "findings": findings}
    write_atomic(target / "report.json", json.dumps(manifest, indent=1, default=_plain) + "\n")


def _plain(v):
    if isinstance(v, np.generic):
        return v.item()
    return str(v)


def analyse(study, df: pd.DataFrame, cfg: dict, target: Path, log) -> tuple[dict, Analysis]:
    """Run a study's analysis (its module's ``analyse``, if any) and the TOML's declared tables and figures;
    return (the named values for meta.json, Analysis)."""
    analysis = study.analyse(df, cfg, target, log) if hasattr(study, "analyse") else Analysis()
    analysis.values = {"n_rows": len(df), "n_ok": int((df["status"] == "ok").sum()), **analysis.values}
    findings = json.loads(json.dumps(analysis.values, default=_plain))  # what meta.json holds
    analysis.tables += [declared_table(df, t) for t in cfg.get("tables", [])]
    for f in cfg.get("figures", []):
        analysis.figures.append(declared_figure(df, f, target, len(analysis.figures) + 1))
    return findings, analysis
