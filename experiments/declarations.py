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


def validate(cfg: dict, where: str, full: dict | None = None) -> None:
    """Check what the declarative keys (tables, figures, report) say, before any row runs and after the schema
    checked their structure (keys, types, enums: ``experiments.schema``, the typed config): the plot and its
    arguments, the findings template, and -- where the study's columns are known from its config
    (:func:`declared_columns`) -- every column they name and every aggregate against the column's type, and every
    ``where`` value of a column whose values are known (:func:`known_values`). ``full``: the config without its
    ``[quick]`` table when ``cfg`` has it applied (a ``where`` value of the full grid is no typo in a quick run).
    Errors are one line: ``FILE: KEY: PROBLEM``."""
    rep = cfg.get("report", {})
    columns = declared_columns(cfg)
    problem = length_unit_problem(cfg)
    if problem:
        raise ConfigError(f"{where}: length_unit: {problem}")
    values = _values_of(cfg, full) if any(d.get("where") for key in ("tables", "figures", "rankings")
                                           for d in cfg.get(key, [])) else None
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
        _check_where(t.get("where"), columns, f"{here}.where", values)
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
        _check_where(f.get("where"), columns, f"{here}.where", values)
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
        _check_ranking(r, cfg, columns, f"{where}: rankings[{i}]", values)


def _check_ranking(r: dict, cfg: dict, columns: dict | None, here: str, values: dict | None = None) -> None:
    """A ``[[rankings]]`` entry (``experiments.render.rankings``), before any row runs: its metric a numeric column
    of the rows, its problem and where columns too, its methods pattern matching a method of the study, its
    unit against the metric and the study's lengths (``experiments.units.ranking_unit``)."""
    import fnmatch
    _check_where(r.get("where"), columns, f"{here}.where", values)
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


def _check_where(cond, columns, key: str, values: dict | None = None) -> None:
    """A declaration's ``where = {column = value or [values]}``: each column one the rows will have, each value one
    a row will hold where the column's values are known before the run (``values``, :func:`known_values`): a
    method id with a typo selected no row, and the table or figure was empty without a word."""
    if cond is None:
        return
    if not isinstance(cond, dict):
        raise ConfigError(f"{key}: must be a table column = value or [values], got {cond!r}")
    if columns is not None:
        for name in cond:
            _check_column(name, columns, key)
    for name, wanted in cond.items():
        held = (values or {}).get(name)
        if held is None:
            continue
        for v in wanted if isinstance(wanted, list) else [wanted]:
            if not any(_same(v, h) for h in held):
                shown = sorted(map(str, held))
                close = difflib.get_close_matches(str(v), shown, n=1)
                listed = ", ".join(shown[:12]) + (f", ... ({len(shown)} values)" if len(shown) > 12 else "")
                raise ConfigError(f"{key}.{name}: {v!r} matches no row{f' (did you mean {close[0]!r}?)' if close else ''}"
                                  f"; the rows' {name} will be: {listed}")


def _same(a, b) -> bool:
    """Whether ``where``'s value ``a`` selects a row holding ``b`` (``pandas.Series.isin``: 31 selects 31.0, the
    string '31' does not select the number 31, a bool only a bool)."""
    if isinstance(a, bool) or isinstance(b, bool):
        return isinstance(a, bool) and isinstance(b, bool) and a == b
    if isinstance(a, str) or isinstance(b, str):
        return isinstance(a, str) and isinstance(b, str) and a == b
    try:
        return bool(a == b)
    except Exception:
        return False


def known_values(cfg: dict) -> dict[str, set] | None:
    """{column: every value the rows will hold} of the columns whose values a generic grid study's config fixes
    (``study``, ``dataset``, ``method``, ``data_*``, ``param_*``: the tasks of its data sets x the methods their
    ``on`` and ``max_n`` leave them, as ``experiments.rows.base_row`` writes them); None for a kind with rows of its
    own or a config that cannot be expanded (its own check says why)."""
    import json
    import numpy as np
    from experiments import engine
    try:
        if study_of(cfg.get("kind")).own_rows:
            return None
        specs = engine.expand_datasets(cfg, getattr(cfg, "where", "config"))
        runs = engine.expand_methods(cfg, getattr(cfg, "where", "config"))
    except ConfigError:
        return None
    out: dict[str, set] = {"study": {cfg.get("name")}, "dataset": set(), "method": set()}

    def add(prefix, params):
        for k, v in params.items():
            if v is not None:
                out.setdefault(f"{prefix}{k}", set()).add(v if np.isscalar(v) else json.dumps(v))
    pairs_of: dict = {}
    for spec in specs:
        group = (spec["label"], spec.get("params", {}).get("n"))
        if group not in pairs_of:
            pairs_of[group] = engine._pairs(spec, runs)
        pairs = pairs_of[group]
        if not pairs:
            continue
        out["dataset"].add(spec["label"])
        add("data_", spec.get("params", {}))
    for pairs in pairs_of.values():
        for m, params in pairs:
            out["method"].add(m)
            add("param_", params)
    return out


def _values_of(cfg: dict, full: dict | None) -> dict[str, set] | None:
    """:func:`known_values` of ``cfg``, with those of ``full`` (its grid without ``[quick]``) when given."""
    values = known_values(cfg)
    if values is None or full is None:
        return values
    more = known_values(full)
    if more is None:
        return None
    return {k: values.get(k, set()) | more.get(k, set()) for k in {*values, *more}}


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
