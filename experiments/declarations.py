"""What a study declares, checked before any row runs (``experiments.config.load`` calls :func:`validate` after the
schema checked the structure): every column its ``[[tables]]``, ``[[figures]]`` and ``[[rankings]]`` name against the
columns its rows will have (:func:`declared_columns`, from its config alone), each aggregate against its column's
type, plot arguments against the plot's signature, a table's unit against its values' dimension, the findings
template. An error is one line: ``FILE: KEY: PROBLEM``."""
from __future__ import annotations

import difflib
import inspect
from pathlib import Path

from experiments.figures import plot_arguments
from experiments.findings import BASE_VALUES, findings_problem
from experiments.study import PLOT_COLUMNS, PLOTS, ConfigError, study_of
from experiments.tables import AGGREGATES
from experiments.units import length_unit_problem, ranking_unit, unit_problem


def validate(cfg: dict, where: str) -> None:
    """Check what the declarative keys (tables, figures, report) say, before any row runs and after the schema
    checked their structure (keys, types, enums: ``experiments.schema``, the typed config): the plot and its
    arguments, the findings template, and -- where the study's columns are known from its config
    (:func:`declared_columns`) -- every column they name and every aggregate against the column's type.
    Errors are one line: ``FILE: KEY: PROBLEM``."""
    rep = cfg.get("report", {})
    columns = declared_columns(cfg)
    problem = length_unit_problem(cfg)
    if problem:
        raise ConfigError(f"{where}: length_unit: {problem}")
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
        problem = unit_problem(t["values"], t.get("unit", ""), how, cfg)
        if problem:
            raise ConfigError(f"{here}.unit: {problem}")
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
        args = plot_arguments(f)
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
    of the rows, its problem and where columns too, its methods pattern matching a method of the study, its
    unit against the metric and the study's lengths (``experiments.units.ranking_unit``)."""
    import fnmatch
    _check_where(r.get("where"), columns, f"{here}.where")
    try:
        ranking_unit(cfg, r["metric"], r.get("unit"))
    except ValueError as exc:
        raise ConfigError(f"{here}.unit: {exc}") from None
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


def declared_columns(cfg: dict) -> dict[str, str] | None:
    """{column: "number" | "bool" | "text"} of the rows a study will write, from its config alone (nothing is
    expanded): the identity and status columns every row has and the columns of its kind
    (:meth:`experiments.study.Study.row_columns`); None when its kind knows its columns only after the run."""
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


def _values_known(cfg: dict) -> set[str] | None:
    """The named values a findings template may use, when known before the run: the counts every study has and
    those its kind declares (:attr:`experiments.study.Study.values`); None when its analysis adds values known only after the run."""
    try:
        study = study_of(cfg.get("kind"))
    except ConfigError:
        return None
    return None if study.values is None else {*BASE_VALUES, *study.values}
