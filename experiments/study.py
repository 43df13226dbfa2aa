"""The study contract: what a study declares, and the one interface through which its analysis reaches
the report. The report (``experiments.report``) renders only this; it knows no study by name.

A study is one TOML file (``experiments/configs/NAME.toml``, or any path)::

    name = "my_study"                    # = the file name
    title = "Kasa against Gauss-Newton on a short arc"
    kind = "grid"                        # the generic engine (also without kind); or experiments/studies/KIND.py
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

Python is needed only for what a config cannot express: the module ``experiments/studies/KIND.py`` defines
one subclass of :class:`Study`, overriding only what differs from the generic benchmark, e.g.::

    class MyStudy(Study):
        values = ("best_method",)                      # the values its findings may name

        def analyse(self, rows, cfg, target, log):    # tables, figures it saved under target, values, findings
            best = rows.groupby("method")["radius_error"].apply(lambda s: (s ** 2).mean()).idxmin()
            return Analysis(values={"best_method": best}, findings=f"{best} has the smallest radius RMSE.")

The values also land in ``meta.json['findings']``. A study whose numbers need more computation than its rows
declares it as tasks (``tasks(cfg)`` + ``execute(task)``), so that the engine caches, resumes and
parallelises it; ``analyse`` only aggregates rows.

``run.py`` writes ``report.json`` (the manifest: sections, numbered later by the report) and one CSV
per table under ``target/tables/``; everything atomically.
"""
from __future__ import annotations

import difflib
import inspect
import io
import json
import math
import re
import string
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from experiments import engine, studies
from experiments.engine import ConfigError
from experiments.provenance import write_atomic
from methods.files import atomic_path  # noqa: F401  (the one atomic writer, for writers that take a file name)
from methods import results
from methods.plugins import add_entry

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
    #: {column: n}: fixed, n decimals, where a comparison needs a resolution the chosen digits would round away
    #: (radii of 299.0132 mm compared at 0.1 µm: 4); ``exact``: columns printed as given (published values)
    decimals: dict = field(default_factory=dict)
    exact: tuple = ()

    def __post_init__(self):
        declared = [*self.decimals, *self.exact]
        bad = [c for c in declared if c not in self.data.columns or not pd.api.types.is_numeric_dtype(self.data[c])]
        if bad or not all(isinstance(n, int) and 0 <= n <= 15 for n in self.decimals.values()):
            raise ValueError(f"table {self.caption[:40]!r}: decimals/exact must name number columns of its data "
                             f"(decimals 0..15); got {', '.join(map(repr, bad)) or self.decimals}")


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


def _grid_size(entry) -> int:
    size = 1
    for values in (entry.get("grid", {}) if isinstance(entry, dict) else {}).values():
        size *= len(values)
    return size


def count_rows(cfg: dict) -> int:
    """An upper bound of the rows of the generic grid, from the config alone (nothing expanded):
    data-set grid points x repetitions x method grid points. A study that multiplies its rows further
    (its own ``tasks``) is checked again on the expanded task list."""
    import methods
    reps = cfg.get("repetitions", 1)
    n_data = 0
    for entry in cfg.get("datasets", []):
        n_data += _grid_size(entry) * (1 if "published" in entry else reps)
    if not cfg.get("datasets"):
        n_data = max(len(cfg.get("scenarios", [])), 1) * reps
    n_methods = 0
    for entry in cfg.get("methods", []):
        mid = entry if isinstance(entry, str) else entry["id"]
        ids = len(methods.list_methods(mid[:-2])) if mid.endswith(".*") else 1
        n_methods += ids * _grid_size(entry)
    return n_data * max(n_methods, 1)


# ---------------------------------------------------------------- the study class

class Study:
    """A kind of study (benchopt's ``Benchmark``/``Objective`` split): what its rows are, how one row is computed,
    and what the report shows of them. Each module ``experiments/studies/KIND.py`` defines one subclass; a TOML
    with ``kind = "KIND"`` runs it (no kind, or ``kind = "grid"``: this class as it is, the generic benchmark).
    Every method has a default, so a subclass overrides only what its study does differently:

    * :attr:`config_schema` -- the config keys only this kind uses: a model (``experiments.schema.ConfigTable``)
      or {key: JSON Schema}, merged into the schema;
    * :meth:`validate` -- the rules the schema cannot express; :meth:`count_rows` -- the rows from the config alone;
    * :meth:`tasks` -- the tasks (default: data sets x repetitions x methods); :meth:`execute` -- one task's row
      (default: the generic fit, in a worker);
    * :meth:`row_columns` -- the columns of its rows, known before the run (declarations are checked against them);
    * :meth:`analyse` -- tables, figures, named values and findings (default: none of its own; the TOML's
      ``[[tables]]``/``[[figures]]`` are added to what it returns, or chosen from the metrics when undeclared);
    * :attr:`values` -- the names of the values its analysis adds (its findings template may use them; None:
      known only after the run); :attr:`tolerances` -- verify's tolerances of the columns its own rows add.
    """

    #: the study kind (the module's name), set by :func:`study_of`
    kind: str = "grid"

    #: the config keys only this kind uses: a model of them (``experiments.schema.ConfigTable``) or {key: JSON Schema}
    config_schema: dict | type = {}
    #: the names of the named values :meth:`analyse` adds (besides ``n_rows``, ``n_ok``); None: not known before
    values: tuple[str, ...] | None = ()
    #: ``python -m experiments.verify``'s tolerances of the columns its own rows add ({column: Tolerance, or None:
    #: not compared}); the generic columns' are declared with the families' results and the metrics
    tolerances: dict = {}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        studies.CLASSES.add(cls)  # the registry study_of finds a module's class in

    # -- config

    def validate(self, cfg: dict, where: str) -> None:
        """Raise ConfigError (``FILE: KEY: PROBLEM``) for what the schema cannot check. Default: the generic grid
        needs data sets and methods."""
        if not self.own_tasks:
            for key in ("datasets", "methods"):
                if not cfg.get(key):
                    raise ConfigError(f"{where}: {key}: missing; the study kind {cfg['kind']!r} needs at least one "
                                      f"[[{key}]] table")

    def count_rows(self, cfg: dict) -> int:
        """An upper bound of the rows from the config alone (nothing expanded). Default: the generic grid's."""
        return count_rows(cfg)

    # -- rows

    @property
    def own_tasks(self) -> bool:
        """Whether this kind defines its own :meth:`tasks`."""
        return type(self).tasks is not Study.tasks

    @property
    def own_rows(self) -> bool:
        """Whether this kind builds its own rows (its own :meth:`tasks` or :meth:`execute`)."""
        return self.own_tasks or type(self).execute is not Study.execute

    @property
    def generic_rows(self) -> bool:
        """Whether its rows are the generic fit's (it does not define its own :meth:`execute`): the engine then runs
        a chunk's rows in batches, each step of them one loop (``experiments.rows``)."""
        return type(self).execute is Study.execute

    def tasks(self, cfg: dict):
        """The tasks (plain picklable dicts, one row each; see ``experiments.engine``), an iterable read lazily.
        Default: data sets x repetitions x methods (x their grids)."""
        return engine.iter_grid_tasks(cfg, cfg.where)

    def prepared_tasks(self, cfg: dict):
        """The tasks with their index and cache key, lazily (what the engine runs)."""
        if not self.own_tasks:  # the generic grid keys its tasks as it expands them (one identity per pair)
            return engine.iter_grid_tasks(cfg, cfg.where, keyed=True)
        return engine.iter_prepared(self.tasks(cfg))

    def execute(self, task: dict) -> dict:
        """One task's row (in a worker). Default: the generic fit of the task's method on its data set."""
        points, truth = engine.task_data(task)  # load_data, made once for the methods that follow on the same data
        return engine.fit_row(task, points, truth)

    def row_columns(self, cfg: dict) -> dict[str, str] | None:
        """{column: "number" | "bool" | "text"} its rows will have besides the identity and status columns,
        from the config alone; None when known only after the run. Default: the generic fit's columns (a kind
        with its own rows declares its own or None)."""
        return None if self.own_rows else _generic_columns(cfg)

    # -- analysis

    def analyse(self, rows: pd.DataFrame, cfg: dict, target: Path, log) -> Analysis:
        """Tables, figures (files it saved under ``target``), named values and findings built from them. Default:
        the table and the figure chosen from the metrics for what the TOML does not declare."""
        table, figure = default_declarations(cfg, rows) if not (cfg.get("tables") and cfg.get("figures")) else (None, None)
        out = Analysis()
        if table and not cfg.get("tables"):
            out.tables.append(declared_table(rows, table))
        if figure and not cfg.get("figures"):
            out.figures.append(declared_figure(rows, figure, target, 1))
        return out


def study_of(kind: str) -> Study:
    """The study of ``kind``: the :class:`Study` subclass its module ``experiments.studies.KIND`` defines (found
    by importing the module; the framework knows no study by name). ConfigError for an unknown kind or a module
    without exactly one subclass."""
    try:
        return studies.study_of(kind)
    except studies.StudyKindError as exc:
        raise ConfigError(str(exc)) from None


# ---------------------------------------------------------------- plot registry

PLOTS: dict[str, Callable] = {}
#: plot name -> (arguments that name a column of the rows, of which those aggregated as numbers)
PLOT_COLUMNS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {}


def register_plot(name: str, *, columns=("x", "y", "by"), numeric=("y",)):
    """Register ``func(df, ax, **arguments)`` (draws on a matplotlib axis) as plot ``name``; ``columns``: the
    arguments that name a column of the rows, ``numeric``: those of them aggregated as numbers (both checked
    against the study's columns before any row runs)."""
    def deco(func):
        add_entry(PLOTS, name, func)  # journaled: a plugin that fails to load leaves no plot behind
        add_entry(PLOT_COLUMNS, name, (tuple(columns), tuple(numeric)))
        return func
    return deco


def _aggregate(df, by, y, how):
    agg = AGGREGATES[how]
    return df.groupby(by, sort=False, dropna=False)[y].agg(agg)


@register_plot("lines")
def lines(df, ax, *, x, y, by=None, aggregate="mean", logx=False, logy=False, xlabel=None, ylabel=None):
    """One line per value of ``by``: ``aggregate`` of ``y`` against ``x``."""
    groups = df.groupby(by, sort=False, dropna=False) if by else [(y, df)]  # a data set without a by key: 'none'
    for label, g in groups:
        s = _aggregate(g, x, y, aggregate).sort_index()
        ax.plot(s.index, s.values, marker="o", ms=3, label=_legend(by, label))
    ax.set_xscale("log" if logx else "linear")
    ax.set_yscale("log" if logy else "linear")
    ax.set_xlabel(xlabel or x)
    ax.set_ylabel(ylabel or f"{aggregate} of {y}")
    if by:
        ax.legend(fontsize=8, loc="best")


def _legend(by, label) -> str:
    """A line's label: its value of ``by``; of several columns 'circle.kasa, n = 20' (the first column's value, then
    each other as name = value)."""
    def text(v):
        return NO_VALUE if v is None or v != v else str(v)  # the data sets without that parameter
    if isinstance(by, str) or not isinstance(label, tuple):
        return text(label)
    return ", ".join(text(v) if i == 0 else f"{readable(c)} = {text(v)}" for i, (c, v) in enumerate(zip(by, label)))


@register_plot("bars")
def bars(df, ax, *, x, y, aggregate="mean", logy=False, xlabel=None, ylabel=None):
    """One bar per value of ``x``: ``aggregate`` of ``y``."""
    s = _aggregate(df, x, y, aggregate)
    ax.bar(range(len(s)), s.values)
    ax.set_xticks(range(len(s)), [_legend(x, v) for v in s.index], rotation=30, ha="right", fontsize=8)
    ax.set_yscale("log" if logy else "linear")
    ax.set_xlabel(xlabel or x)
    ax.set_ylabel(ylabel or f"{aggregate} of {y}")


# ---------------------------------------------------------------- declarations


def validate(cfg: dict, where: str) -> None:
    """Check what the declarative keys (tables, figures, report) say, before any row runs and after the schema
    checked their structure (keys, types, enums: ``experiments.schema``, the typed config): the plot and its
    arguments, the findings template, and -- where the study's columns are known from its config
    (:func:`declared_columns`) -- every column they name and every aggregate against the column's type.
    Errors are one line: ``FILE: KEY: PROBLEM``."""
    rep = cfg.get("report", {})
    columns = declared_columns(cfg)
    if rep.get("findings") is not None:
        fixed = _values_known(cfg)
        problem = findings_problem(rep["findings"], fixed)
        if problem:
            raise ConfigError(f"{where}: report.findings: {problem}")
    for i, t in enumerate(cfg.get("tables", [])):
        here = f"{where}: tables[{i}]"
        how = t.get("aggregate", "mean")
        if not isinstance(t["values"], str):
            raise ConfigError(f"{here}.values: must be one column name, got {t['values']!r}")
        rows = [t["rows"]] if isinstance(t["rows"], str) else t["rows"]
        if not isinstance(rows, list) or not rows or not all(isinstance(r, str) for r in rows):
            raise ConfigError(f"{here}.rows: must be a column name or a list of them, got {t['rows']!r}")
        _check_where(t.get("where"), columns, f"{here}.where")
        if columns is not None:
            for key, names in (("rows", rows), ("columns", [t.get("columns")] if t.get("columns") else []),
                               ("values", [t["values"]])):
                for c in names:
                    _check_column(c, columns, f"{here}.{key}")
            if how not in ("count", "ok_share", "max", "min") and columns[t["values"]] == "text":
                raise ConfigError(f"{here}.aggregate: the {how} of {t['values']!r} (a text column) is not defined; "
                                  "use count, or a numeric column")
        unit_problem = _unit_problem(t["values"], t.get("unit", ""), how)
        if unit_problem:
            raise ConfigError(f"{here}.unit: {unit_problem}")
    for i, f in enumerate(cfg.get("figures", [])):
        here = f"{where}: figures[{i}]"
        if ("plot" in f) == ("file" in f):
            raise ConfigError(f"{here}: needs a caption and exactly one of plot (a registered plot: "
                              f"{', '.join(PLOTS)}) and file (a PNG the study's analysis writes)")
        if "plot" in f and f["plot"] not in PLOTS:
            raise ConfigError(f"{here}.plot: unknown plot {f['plot']!r}; known: {', '.join(PLOTS)}")
        if "file" in f:
            if Path(f["file"]).is_absolute() or ".." in Path(f["file"]).parts:
                raise ConfigError(f"{here}.file: must be a path inside the study's folder, got {f['file']!r}")
            continue
        args = _plot_arguments(f)
        try:
            inspect.signature(PLOTS[f["plot"]]).bind(None, None, **args)
        except TypeError as exc:
            known = [p for p in inspect.signature(PLOTS[f["plot"]]).parameters if p not in ("df", "ax")]
            raise ConfigError(f"{here}: plot {f['plot']!r}: {exc} (its arguments: {', '.join(known)})") from None
        how = args.get("aggregate", "mean")
        if "aggregate" in args and how not in AGGREGATES:
            raise ConfigError(f"{here}.aggregate: must be one of {', '.join(AGGREGATES)}; got {how!r}")
        _check_where(f.get("where"), columns, f"{here}.where")
        names, numeric = PLOT_COLUMNS.get(f["plot"], ((), ()))
        for a in names:
            if a in args and not isinstance(args[a], str):
                raise ConfigError(f"{here}.{a}: must be one column name, got {args[a]!r}")
            if a in args and columns is not None:
                _check_column(args[a], columns, f"{here}.{a}")
                if a in numeric and how not in ("count", "max", "min") and columns[args[a]] == "text":
                    raise ConfigError(f"{here}.aggregate: the {how} of {args[a]!r} (a text column) is not defined; "
                                      "use count, or a numeric column")
    for i, r in enumerate(cfg.get("rankings", [])):
        _check_ranking(r, cfg, columns, f"{where}: rankings[{i}]")


def _check_ranking(r: dict, cfg: dict, columns: dict | None, here: str) -> None:
    """A ``[[rankings]]`` entry (``experiments.render.rankings``), before any row runs: its metric a numeric column
    of the rows, its problem and where columns too, its methods pattern matching a method of the study (its unit is
    checked by the report, ``ranking_unit``)."""
    import fnmatch
    _check_where(r.get("where"), columns, f"{here}.where")
    if columns is not None:
        _check_column(r["metric"], columns, f"{here}.metric")
        if columns[r["metric"]] != "number":
            raise ConfigError(f"{here}.metric: {r['metric']!r} is not a number (a ranking's metric is a cost, lower "
                              "is better)")
        for c in r.get("problem", []):
            _check_column(c, columns, f"{here}.problem")
        ids = _method_ids(cfg)
        if ids and "methods" in r and not any(fnmatch.fnmatchcase(m, r["methods"]) for m in ids):
            raise ConfigError(f"{here}.methods: {r['methods']!r} matches none of the study's methods "
                              f"({', '.join(ids)})")


def _method_ids(cfg: dict) -> list[str]:
    """The registered method ids of a study's ``[[methods]]`` (wildcards expanded)."""
    import methods
    ids = []
    for entry in cfg.get("methods", []):
        mid = entry if isinstance(entry, str) else entry["id"]
        if mid.endswith(".*"):
            ids += [s.id for s in methods.list_methods(mid[:-2])]
        elif "." in mid:
            ids.append(mid)
    return list(dict.fromkeys(ids))


def _plot_arguments(f: dict) -> dict:
    args = {k: f[k] for k in ("x", "y", "by", "aggregate", "logx", "logy", "xlabel", "ylabel") if k in f}
    args.update(f.get("args", {}))
    return args


def _check_column(name, columns: dict, key: str) -> None:
    if name not in columns:
        close = difflib.get_close_matches(str(name), list(columns), n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ConfigError(f"{key}: no row will have the column {name!r}{hint} (the rows have: "
                          f"{', '.join(sorted(columns))})")


def _check_where(cond, columns, key: str) -> None:
    if cond is None:
        return
    if not isinstance(cond, dict):
        raise ConfigError(f"{key}: must be a table column = value or [values], got {cond!r}")
    if columns is not None:
        for name in cond:
            _check_column(name, columns, key)


# ---------------------------------------------------------------- the columns a study's rows will have

#: units read from a column name's suffix (data and study columns: ``data_arc_deg``, ``station_error_um``)
SUFFIX_UNITS = {"_deg": "°", "_rad": "rad", "_urad": "µrad", "_um": "µm", "_mm": "mm", "_nm": "nm", "_s": "s"}
LENGTH_UNITS = {"mm", "µm", "um", "nm", "m", "cm"}
_ANGLE_UNITS = {"rad", "µrad", "urad", "mrad", "deg", "°", "arcsec"}


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


def _aggregate_words(how: str, column: str) -> str:
    """'RMSE of radius error', 'mean of arc'."""
    return f"{'RMSE' if how == 'rmse' else how} of {readable(column)}"


def _unit_problem(column: str, unit: str, how: str) -> str | None:
    """A table unit of another dimension than its values' (a degree column is never labelled mm)."""
    if not unit or how in ("count", "ok_share"):
        return None
    own = column_unit(column)
    for group, what in ((LENGTH_UNITS, "a length"), (_ANGLE_UNITS, "an angle")):
        if own in group and unit not in group:
            return f"{column!r} is {what} in {own}, not in {unit!r}"
        if unit in group and own and own not in group:
            return f"{column!r} is in {own}, not {what} ({unit!r})"
    return None


def _kind(values) -> str:
    vals = [v for v in values if v is not None]
    if vals and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
        return "number"
    if vals and all(isinstance(v, bool) for v in vals):
        return "bool"
    return "text"


def declared_columns(cfg: dict) -> dict[str, str] | None:
    """{column: "number" | "bool" | "text"} of the rows a study will write, from its config alone (nothing is
    expanded): the identity and status columns every row has and the columns of its kind
    (:meth:`Study.row_columns`); None when its kind knows its columns only after the run."""
    try:
        study = study_of(cfg.get("kind"))
    except ConfigError:
        return None
    own = study.row_columns(cfg)
    if own is None:
        return None
    out = {c: "text" for c in ("study", "dataset", "data_stream", "method", "params", "status", "message")}
    out.update(repetition="number", seed="number", converged="bool", iterations="number", nfev="number")
    out.update(own)
    return out


def _generic_columns(cfg: dict) -> dict[str, str]:
    """The columns of the generic fit's rows: the data and method parameters, the columns the result classes of
    its methods declare and the timing columns."""
    import methods
    out: dict[str, str] = {}
    values: dict[str, list] = {}
    for entry in cfg.get("datasets", []):
        for k, v in {**entry.get("params", {}), **{k: vs for k, vs in entry.get("grid", {}).items()}}.items():
            values.setdefault(f"data_{k}", []).extend(v if k in entry.get("grid", {}) else [v])
    families = set()
    for entry in cfg.get("methods", []):
        entry = {"id": entry} if isinstance(entry, str) else entry
        families.add(entry["id"].partition(".")[0])
        for k, v in {**entry.get("params", {}), **entry.get("grid", {})}.items():
            values.setdefault(f"param_{k}", []).extend(v if k in entry.get("grid", {}) else [v])
    out.update({name: _kind(vs) for name, vs in values.items()})
    methods.load_plugins()
    for family in families:
        for col in _family_columns(family):
            out[col] = "number"
    if cfg.get("timing"):
        out.update(time_median_s="number", time_iqr_s="number", time_rounds="number", time_calls_per_round="number")
    return out


def _family_columns(family: str) -> list[str]:
    base = results.contract(family)
    classes = [c for c in results.result_classes() if base is not None and issubclass(c, base)] \
        or results.result_classes()
    return [col.name for cls in classes for col in cls.COLUMNS]


def _values_known(cfg: dict) -> set[str] | None:
    """The named values a findings template may use, when known before the run: the counts every study has and
    those its kind declares (:attr:`Study.values`); None when its analysis adds values known only after the run."""
    try:
        study = study_of(cfg.get("kind"))
    except ConfigError:
        return None
    return None if study.values is None else {*BASE_VALUES, *study.values}


# ---------------------------------------------------------------- findings: a sandboxed template

#: the named values every study's findings may use
BASE_VALUES = ("n_rows", "n_ok")
#: a format spec of a findings field: [[fill]align][sign][#][0][width][,|_][.precision][type], width <= 99
_SPEC = re.compile(r"^(?:[^{}]?[<>=^])?[+\- ]?#?0?(?P<width>\d{1,2})?[,_]?(?:\.(?P<precision>\d{1,2}))?[bcdeEfFgGnosxX%]?$")
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
#: the longest findings text (characters): a paragraph, not a document
MAX_FINDINGS = 4000


def _fields(template: str):
    """(literal, name, spec) of a ``str.format``-style template, or raise ValueError with the problem: a
    field is a plain name (no attribute or item access, no conversion) with a bounded format spec."""
    if not isinstance(template, str):
        raise ValueError(f"must be a string, got {template!r}")
    out = []
    for literal, name, spec, conversion in string.Formatter().parse(template):
        if name is None:
            out.append((literal, None, ""))
            continue
        if not _NAME.match(name):
            raise ValueError(f"{{{name}}}: a field is a plain value name (no attribute, item or positional access)")
        if conversion is not None:
            raise ValueError(f"{{{name}!{conversion}}}: conversions are not allowed")
        if not _SPEC.match(spec or ""):
            raise ValueError(f"{{{name}:{spec}}}: the format spec must be [[fill]align][sign][#][0][width <= 99]"
                             "[,][.precision <= 99][type]")
        out.append((literal, name, spec or ""))
    return out


def findings_problem(template, names: set[str] | None = None) -> str | None:
    """The problem with a findings template (None: fine); ``names``: the values it may use, when known."""
    try:
        fields_ = _fields(template)
    except ValueError as exc:
        return str(exc)
    if names is not None:
        unknown = sorted({n for _, n, _ in fields_ if n is not None} - names)
        if unknown:
            return f"unknown value(s) {', '.join(unknown)} (the values: {', '.join(sorted(names))})"
    return None


def render_findings(template: str, values: dict) -> str:
    """Fill ``template`` from ``values`` (numbers and text only), sandboxed: no attribute or item access, no
    conversions, widths and precisions below 100, the result one paragraph of at most MAX_FINDINGS characters
    (line breaks become spaces). Raises ValueError with the problem."""
    parts = []
    for literal, name, spec in _fields(template):
        parts.append(literal)
        if name is None:
            continue
        if name not in values:
            raise ValueError(f"unknown value {name!r} (the values: {', '.join(sorted(values))})")
        v = values[name]
        if isinstance(v, np.generic):
            v = v.item()
        if not isinstance(v, (int, float, str)) or isinstance(v, bool):
            v = str(v)
        try:
            parts.append(format(v, spec))
        except (ValueError, TypeError) as exc:
            raise ValueError(f"{{{name}:{spec}}}: {exc}") from None
    text = " ".join("".join(parts).split())
    return text if len(text) <= MAX_FINDINGS else text[:MAX_FINDINGS - 1] + "…"


#: the statuses of a row that has a result: the method returned one and the gate accepted it (``docs/results.md``)
RESULT_STATUSES = ("ok", "not converged")


def failed_rows(cfg: dict, rows) -> str | None:
    """The one line of a study none of whose rows has a result (every row ``error``, ``invalid``, ``skipped``,
    ``timeout``, ...: ``python -m experiments.run`` then exits 1), naming the most frequent reason; None when a row
    has a result. ``rows``: the rows (``status`` and ``message``), or the study's ``results.csv``."""
    if not isinstance(rows, pd.DataFrame):
        try:   # meta.json's counts: a study with a result is not read again
            counts = json.loads((Path(rows).parent / "meta.json").read_text(encoding="utf-8")).get("status_counts")
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


def _where(df, cond):
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


def declared_table(df: pd.DataFrame, t: dict) -> Table:
    """A pivot (or a grouped aggregate) of the rows, as declared."""
    rows = [t["rows"]] if isinstance(t["rows"], str) else list(t["rows"])
    how = t.get("aggregate", "mean")
    value = t["values"]
    # only the columns read below (selecting the rows of the whole frame would copy every column)
    used = [*rows, *([t["columns"]] if t.get("columns") else []), value, "status", *(t.get("where") or {})]
    data = _where(df[[c for c in dict.fromkeys(used) if c in df.columns]], t.get("where"))
    if how == "ok_share":
        data = data.assign(_ok=(data["status"] == "ok").astype(float))
        value, how = "_ok", "mean"
    else:
        data = data[data["status"] == "ok"]
    for c in rows + ([t["columns"]] if t.get("columns") else []) + [value]:
        if c not in data.columns:
            raise ConfigError(f"table {t['caption'][:40]!r}: no column {c!r} in the rows{_no_result(df)} "
                              f"(columns: {', '.join(df.columns)})")
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
        out = out.rename(columns={value: _aggregate_words(how, t["values"])})
    for c in rows:
        if c in lacking:
            out[c] = out[c].astype(object).where(out[c].notna(), NO_VALUE)
    # a numeric key column carries its own unit in its name, so the table's unit never labels it
    out = out.rename(columns={c: f"{readable(c)} [{column_unit(c)}]" for c in rows
                              if column_unit(c) and c in numeric_keys})
    caption = t["caption"] + _lacking_note(df, lacking)
    return Table(caption=caption, data=out, unit=t.get("unit", ""), digits=t.get("digits", 4),  # significant digits
                 colour=t.get("colour", ""))


#: the key of the rows of the data sets that lack a table's key parameter ('share = none'), the legend of their line
NO_VALUE = "none"


def _lacking_note(df: pd.DataFrame, lacking: list[str], drawn: bool = True) -> str:
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


def load_plotting_in_background() -> None:
    """Import matplotlib (Agg), pyplot and the PNG and PDF backends in a daemon thread: a run whose rows run in worker processes waits for them
    meanwhile, and its figures need the import after the rows (0.5-0.7 s here). An import that fails here fails
    again, with its message, where the figures are drawn."""
    import threading

    def load():
        try:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot  # noqa: F401
            import matplotlib.backends.backend_agg  # noqa: F401  (the PNG of each figure)
            import matplotlib.backends.backend_pdf  # noqa: F401  (its PDF, for the report's LaTeX: 0.15 s more)
        except Exception:  # reported where the figures import it
            pass
    threading.Thread(target=load, daemon=True, name="fitbench-load-plotting").start()


def declared_figure(df: pd.DataFrame, f: dict, target: Path, number: int) -> Figure:
    if "file" in f:
        return Figure(caption=f["caption"], file=f["file"])
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    args = _plot_arguments(f)
    accepted = inspect.signature(PLOTS[f["plot"]]).parameters
    for axis, label in (("x", "xlabel"), ("y", "ylabel")):  # axes name their column and its unit
        if isinstance(args.get(axis), str) and label in accepted and label not in args:
            unit = column_unit(args[axis])
            what = readable(args[axis]) if axis == "x" else _aggregate_words(args.get("aggregate", "mean"), args[axis])
            args[label] = f"{what} [{unit}]" if unit else what
    fig, ax = plt.subplots(figsize=(f.get("width", 6.4), f.get("height", 4.2)))
    plot = PLOTS[f["plot"]]
    if plot in (lines, bars):  # these read only the columns their arguments name: select the rows of those alone
        named = [c for a in PLOT_COLUMNS[f["plot"]][0] for c in
                 ([args[a]] if isinstance(args.get(a), str) else list(args.get(a) or ()))]
        df = df[[c for c in dict.fromkeys([*named, "status", "dataset", *(f.get("where") or {})]) if c in df.columns]]
    shown = _where(df[df["status"] == "ok"], f.get("where"))
    note = ""
    if plot is lines and isinstance(args.get("x"), str) and args["x"] in shown and shown[args["x"]].isna().any():
        # rows of data sets without the x parameter have no place on the axis: left out, and the caption says so
        note = _lacking_note(shown, [args["x"]], drawn=False)
        shown = shown[shown[args["x"]].notna()]
    plot(shown, ax, **args)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    name = f"figure_{number}_{f['plot']}.png"
    save_figure(fig, target / name)
    plt.close(fig)
    return Figure(caption=f["caption"] + note, file=name)


def save_figure(fig, path: Path, dpi: float = 110) -> None:
    """Save a matplotlib figure atomically (:func:`fitbench.plots.save_atomic`: a kill never leaves a
    half-written PNG)."""
    from fitbench.plots import save_atomic
    save_atomic(fig, path, dpi=dpi)
    save_atomic(fig, Path(path).with_suffix(".pdf"))   # the vector form the report's LaTeX includes


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
                        **({"colour": t.colour} if t.colour else {}),
                        **({"decimals": dict(t.decimals)} if t.decimals else {}),
                        **({"exact": list(t.exact)} if t.exact else {})})
    rep = cfg.get("report", {})
    findings = analysis.findings
    if not findings and rep.get("findings"):
        try:
            findings = render_findings(rep["findings"], analysis.values)
        except ValueError as exc:
            findings = f"(findings template not filled: {cfg.where}: report.findings: {exc})"
    manifest = {"title": cfg["title"], "section": rep.get("section", DEFAULT_SECTION), "order": rep.get("order", 1000),
                "quick": cfg.quick, "tables": entries,
                "figures": [{"caption": f.caption, "file": f.file} for f in analysis.figures],
                "values": analysis.values, "findings": findings}
    write_atomic(target / "report.json", json_text(manifest, indent=1) + "\n")


def _plain(v):
    if isinstance(v, np.generic):
        return v.item()
    return str(v)


#: how a value that is not a finite number is written in JSON: a text that Python's ``float()`` and JavaScript's
#: ``Number()`` read back (JSON has no such number; the bare ``Infinity`` Python writes is refused by jq and JSON.parse)
NON_FINITE = {math.inf: "Infinity", -math.inf: "-Infinity"}


def _finite(v):
    """``v`` with every float that is infinite or NaN (NumPy's too, in lists, tuples and dicts) as its text."""
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float):
        return v if math.isfinite(v) else NON_FINITE.get(v, "NaN")
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_finite(x) for x in v]
    return v


def json_text(value, **kwargs) -> str:
    """``value`` as strict JSON (RFC 8259): a study's values, named by its analysis, may be infinite or NaN."""
    return json.dumps(_finite(value), default=_plain, allow_nan=False, **kwargs)


_FROM_TEXT = {"Infinity": math.inf, "-Infinity": -math.inf, "NaN": math.nan}


def _numbers(v):
    if isinstance(v, str):
        return _FROM_TEXT.get(v, v)
    if isinstance(v, dict):
        return {k: _numbers(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_numbers(x) for x in v]
    return v


def json_value(text: str):
    """The value :func:`json_text` wrote, its "Infinity", "-Infinity" and "NaN" texts the floats again (a study's
    findings hold numbers: a condition number of a degenerate layout is infinite)."""
    return _numbers(json.loads(text))


def analyse(study: Study, df: pd.DataFrame, cfg: dict, target: Path, log) -> tuple[dict, Analysis]:
    """Run a study's analysis (:meth:`Study.analyse`) and add the TOML's declared tables and figures; return
    (the named values for meta.json, Analysis)."""
    analysis = study.analyse(df, cfg, target, log)
    analysis.values = {"n_rows": len(df), "n_ok": int((df["status"] == "ok").sum()), **analysis.values}
    findings = json.loads(json_text(analysis.values))  # what meta.json holds
    analysis.tables += [declared_table(df, t) for t in cfg.get("tables", [])]
    for f in cfg.get("figures", []):
        analysis.figures.append(declared_figure(df, f, target, len(analysis.figures) + 1))
    return findings, analysis


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


def _length_unit(cfg: dict, metric: str) -> tuple[str, str]:
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
    the study's ``length_unit``, else mm for the machine-tool data, else the data's own unit (:func:`_length_unit`)."""
    ok = (df["status"] == "ok").to_numpy() if "status" in df else slice(None)  # a mask: no copy of the rows
    errors = results.truth_error_columns()
    metric = next((c for c in (*errors, "form_error")
                   if c in df and pd.to_numeric(df[c].iloc[ok], errors="coerce").notna().any()),
                  None)
    if metric is None:
        return None, None
    how = "rmse" if metric in errors else "median"
    unit, unit_note = _length_unit(cfg, metric)
    numeric, other = _varying(df)
    across = numeric[0] if numeric else ("dataset" if "dataset" in other else None)
    keys = [c for c in (*numeric[1:], *other) if c != across]   # every other varying parameter: its own rows
    rows = ["method"] + keys
    what = _aggregate_words(how, metric)
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
