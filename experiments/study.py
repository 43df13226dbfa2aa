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

    [[figures]]                          # a registered plot (register_plot: lines, bars, a plugin's) ...
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

A study module's rows are keyed on its code and the libraries it imports (``experiments.codehash``): it builds rows
with ``experiments.rows``, expands its config through ``cfg`` (``cfg.grid_tasks()``, ``cfg.expand_methods()``) rather
than by importing the engine, and draws with ``experiments.render.style.plotting()`` (output code, which no row's key
enters: ``experiments.codehash.OUTPUT_PACKAGES``), so that the run's and the figures' libraries are in no row's key
(docs/studies.md). This module
follows the same rules.

The run's analysis step adds the TOML's declared tables and figures (``experiments.analysis``; checked before any row
runs: ``experiments.declarations``) and writes ``report.json`` (the manifest: sections, numbered later by the
report) and one CSV per table under ``target/tables/``, everything atomically (``experiments.outputs``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from pydantic import BaseModel, ConfigDict

from experiments import studies
from experiments.rows import fit_row, task_data
from methods import InvalidInputError, results
from methods.plugins import add_entry

if TYPE_CHECKING:  # pandas is imported where a table is checked: a row's process (a worker) needs none of it
    import pandas as pd


class ConfigError(InvalidInputError):
    """A study config that cannot run; the message names the file, the key and the problem."""


class ConfigTable(BaseModel):
    """A TOML table: no key beyond its fields (optional fields default to None: absent). A study kind's own keys
    are such a model (its :attr:`Study.config_schema`); the config's schema (``experiments.schema``) is made of them."""
    model_config = ConfigDict(extra="forbid")


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
        import pandas as pd
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

    * :attr:`config_schema` -- the config keys only this kind uses: a model (:class:`ConfigTable`)
      or {key: JSON Schema}, merged into the schema;
    * :meth:`validate` -- the rules the schema cannot express; :meth:`count_rows` -- the rows from the config alone;
    * :meth:`tasks` -- the tasks (default: data sets x repetitions x methods); :meth:`execute` -- one task's row
      (default: the generic fit, in a worker);
    * :meth:`row_columns` -- the columns of its rows, known before the run (declarations are checked against them);
      :meth:`data_sets` -- the data sets its rows read (their files' SHA-256 go into ``meta.json``);
    * :meth:`analyse` -- tables, figures, named values and findings (default: none of its own; the TOML's
      ``[[tables]]``/``[[figures]]`` are added to what it returns, or chosen from the metrics when undeclared);
    * :attr:`values` -- the names of the values its analysis adds (its findings template may use them; None:
      known only after the run); :attr:`tolerances` -- verify's tolerances of the columns its own rows add.
    """

    #: the study kind (the module's name), set by :func:`study_of`
    kind: str = "grid"

    #: the config keys only this kind uses: a model of them (:class:`ConfigTable`) or {key: JSON Schema}
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
        Default: data sets x repetitions x methods (x their grids). ``cfg`` (``experiments.config.StudyConfig``)
        expands itself: ``cfg.grid_tasks()``, ``cfg.expand_datasets()``, ``cfg.expand_methods()``."""
        return cfg.grid_tasks()

    def prepared_tasks(self, cfg: dict):
        """The tasks with their index and cache key, lazily (what the engine runs)."""
        if not self.own_tasks:  # the generic grid keys its tasks as it expands them (one identity per pair)
            return cfg.grid_tasks(keyed=True)
        return cfg.prepare(self.tasks(cfg))

    def execute(self, task: dict) -> dict:
        """One task's row (in a worker). Default: the generic fit of the task's method on its data set."""
        points, truth = task_data(task)  # load_data, made once for the methods that follow on the same data
        return fit_row(task, points, truth)

    def data_sets(self, cfg: dict) -> list[dict] | None:
        """The data set specs its rows read (``meta.json`` records the SHA-256 of each file they read,
        ``experiments.compare.inputs``); None (the default): the config's ``[[datasets]]``. A kind whose own tasks
        read other data sets names them."""
        return None

    def row_columns(self, cfg: dict) -> dict[str, str] | None:
        """{column: "number" | "bool" | "text"} its rows will have besides the identity and status columns,
        from the config alone; None when known only after the run. Default: the generic fit's columns (a kind
        with its own rows declares its own or None)."""
        return None if self.own_rows else _generic_columns(cfg)

    # -- analysis

    def analyse(self, rows: pd.DataFrame, cfg: dict, target: Path, log) -> Analysis:
        """Tables, figures (files it saved under ``target``), named values and findings built from them. Default:
        nothing of its own (the run's analysis, ``experiments.analysis.analyse``, then adds the table and the figure
        it chooses from the metrics for what the TOML does not declare)."""
        return Analysis()

    @property
    def own_analysis(self) -> bool:
        """Whether this kind defines its own :meth:`analyse` (else the run adds a default table and figure)."""
        return type(self).analyse is not Study.analyse


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


def _kind(values) -> str:
    vals = [v for v in values if v is not None]
    if vals and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
        return "number"
    if vals and all(isinstance(v, bool) for v in vals):
        return "bool"
    return "text"


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
