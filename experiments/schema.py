"""The schema of a study config (JSON Schema, checked with ``jsonschema``) and the checks it cannot express.

ONE PLACE TO EXTEND:
* a new top-level key of every study (e.g. ``report``, ``tables``, ``figures``): add it to
  :data:`TOP_LEVEL`;
* a key only one kind of study uses (``rounding``, ``scenarios``, ...) is declared by that study's module as
  ``Study.config_schema`` = {key: JSON Schema}, merged here when a config of that kind is checked: adding a study
  needs no edit of this file (its ``validate`` checks the values the schema cannot express);
* a new kind of data source in ``[[datasets]]`` (e.g. ``file = "trace.csv"``, a plugin source): add its
  key to :data:`DATASET_SOURCES` with the schema of the entry's own keys, and register the check of its
  parameter values with :func:`register_source_check` (the source validates its parameters, not this
  schema).
Structure errors come from the schema; value errors of generator and method parameters from the
generators' ``check_params`` and the method registry's ``MethodSpec.check_params``. Every error is one
line: ``FILE: KEY: PROBLEM``.
"""
from __future__ import annotations

import math
from typing import Callable

import jsonschema

_POSITIVE_INT = {"type": "integer", "minimum": 1}
_GRID = {"type": "object", "additionalProperties": {"type": "array", "minItems": 1},
         "description": "parameter -> non-empty list of values (the cartesian product is taken)"}
_PARAMS = {"type": "object", "description": "parameter -> value"}

#: The keys of one ``[[datasets]]`` entry, per data source (the source key names the source).
DATASET_SOURCES: dict[str, dict] = {
    "generator": {"generator": {"type": "string"}, "params": _PARAMS, "grid": _GRID, "label": {"type": "string"}},
    "published": {"published": {"type": "string"},
                  "variant": {"enum": ["drop_repeated_closing_point"]}, "label": {"type": "string"}},
    "source": {"source": {"type": "string"}, "params": _PARAMS, "grid": _GRID, "label": {"type": "string"}},
    "file": {"file": {"type": "string", "minLength": 1, "description": "a points file, relative to the TOML"},
             "truth": {"type": "object"}, "label": {"type": "string"}},
}

_METHOD_ENTRY = {
    "anyOf": [
        {"type": "string", "minLength": 1},
        {"type": "object", "required": ["id"], "additionalProperties": False,
         "properties": {"id": {"type": "string", "minLength": 1}, "params": _PARAMS, "grid": _GRID,
                        "max_n": _POSITIVE_INT, "on": {"type": "array", "items": {"type": "string"}}}},
    ],
    "description": "a method id, or a table with id, params, grid, max_n, on",
}

#: Every top-level key a study config may have. Keys overridable by ``[quick]`` are all but
#: :data:`NOT_IN_QUICK`.
TOP_LEVEL: dict[str, dict] = {
    "name": {"type": "string", "pattern": r"^[A-Za-z0-9_][A-Za-z0-9_-]*$",
             "description": "the file name without .toml (letters, digits, _ and -)"},
    "title": {"type": "string", "minLength": 1},
    "kind": {"type": "string", "pattern": r"^[A-Za-z_][A-Za-z0-9_]*$"},
    "default": {"type": "boolean"},
    "seed": {"type": "integer", "minimum": 0},
    "repetitions": _POSITIVE_INT,
    "max_jobs": _POSITIVE_INT,
    "row_timeout": {"type": "number", "exclusiveMinimum": 0, "description": "seconds a row may run (engine)"},
    "chunk_rows": _POSITIVE_INT,  # rows sent to a worker at a time (default: from the measured cost of a row)
    "summary_by": {"type": "array", "items": {"type": "string"}, "minItems": 1},
    "datasets": {"type": "array", "minItems": 1, "items": {"type": "object"}},  # entries: _dataset_schema()
    "methods": {"type": "array", "minItems": 1, "items": _METHOD_ENTRY},
    "timing": {"type": "object", "additionalProperties": False,
               "properties": {"min_time_s": {"type": "number", "exclusiveMinimum": 0},
                              "rounds": _POSITIVE_INT}},
    "quick": {"type": "object"},  # checked as overrides: see config_schema()
    # the report contract (experiments/study.py): the section, the declared tables and figures
    "report": {"type": "object", "additionalProperties": False,
               "properties": {"section": {"type": "string", "minLength": 1}, "order": {"type": "integer"},
                              "findings": {"type": "string"}}},
    "tables": {"type": "array", "items": {
        "type": "object", "required": ["caption", "rows", "values"], "additionalProperties": False,
        "properties": {"caption": {"type": "string", "minLength": 1},
                       "rows": {"anyOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}}],
                                "description": "a column name or a list of them"},
                       "values": {"anyOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}}],
                                  "description": "a column name or a list of them"},
                       "columns": {"type": "string"},
                       "aggregate": {"enum": ["mean", "median", "max", "min", "std", "count", "rmse", "ok_share"]},
                       "unit": {"type": "string"}, "digits": {"type": "integer", "minimum": 0},
                       "where": {"type": "object"},
                       "colour": {"enum": ["lower_is_better"],
                                  "description": "a method comparison: HTML cells coloured by their ratio to "
                                                 "the row's best (lowest) value"}}}},
    # cross-study rankings (experiments/report.py): Dolan-More performance profiles pooled over every study
    # that declares the same profile name
    "rankings": {"type": "array", "items": {
        "type": "object", "required": ["profile", "metric"], "additionalProperties": False,
        "properties": {"profile": {"type": "string", "minLength": 1}, "metric": {"type": "string", "minLength": 1},
                       "unit": {"type": "string"}, "methods": {"type": "string", "minLength": 1},
                       "problem": {"type": "array", "items": {"type": "string"}, "minItems": 1},
                       "floor": {"type": "number", "minimum": 0}, "where": {"type": "object"}}}},
    "figures": {"type": "array", "items": {
        "type": "object", "required": ["caption"], "additionalProperties": False,
        "properties": {"caption": {"type": "string", "minLength": 1}, "plot": {"type": "string"},
                       "file": {"type": "string"}, "x": {"type": "string"}, "y": {"type": "string"},
                       "by": {"type": "string"}, "aggregate": {"type": "string"}, "logx": {"type": "boolean"},
                       "logy": {"type": "boolean"}, "xlabel": {"type": "string"}, "ylabel": {"type": "string"},
                       "args": {"type": "object"}, "width": {"type": "number", "exclusiveMinimum": 0},
                       "height": {"type": "number", "exclusiveMinimum": 0}, "where": {"type": "object"}}}},
}
REQUIRED = ("name", "title")
NOT_IN_QUICK = ("name", "kind", "default", "quick")


def _dataset_schema() -> dict:
    alternatives = []
    for source, keys in DATASET_SOURCES.items():
        alternatives.append({"type": "object", "required": [source], "properties": keys, "additionalProperties": False})
    return {"oneOf": alternatives}


def config_schema(study_keys: dict | None = None) -> dict:
    """The JSON Schema of a whole config file (its ``[quick]`` table: the same keys, none required), with the
    keys its study kind declares (``study_keys``: its ``Study.config_schema``)."""
    clash = set(study_keys or {}) & set(TOP_LEVEL)
    if clash:
        raise ValueError(f"config_schema redefines the common key(s) {', '.join(sorted(clash))}")
    props = {k: dict(v) for k, v in {**TOP_LEVEL, **(study_keys or {})}.items()}
    props["datasets"] = {**props["datasets"], "items": _dataset_schema()}
    quick = {k: v for k, v in props.items() if k not in NOT_IN_QUICK}
    props["quick"] = {"type": "object", "properties": quick, "additionalProperties": False}
    return {"type": "object", "required": list(REQUIRED), "properties": props, "additionalProperties": False}


def _path(error) -> str:
    parts = []
    for p in error.absolute_path:
        if isinstance(p, int):
            parts[-1:] = [f"{parts[-1]}[{p}]"] if parts else [f"[{p}]"]
        else:
            parts.append(str(p))
    return ".".join(parts) or "(top level)"


def _message(error) -> str:
    """A one-line reading of a jsonschema error (the most specific one for oneOf/anyOf)."""
    v = error.validator
    if v == "additionalProperties":
        extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
        known = ", ".join(sorted(error.schema.get("properties", {})))
        return f"unknown key(s) {', '.join(extra)} (known: {known})"
    if v == "required":
        return f"missing required key {error.message.split(' ')[0]}"
    if v == "type":
        want = error.validator_value
        want = " or ".join(want) if isinstance(want, list) else want
        return f"must be {'an' if want[0] in 'aeiou' else 'a'} {want}, got {error.instance!r}"
    if v in ("minimum", "exclusiveMinimum"):
        return f"must be {'>=' if v == 'minimum' else '>'} {error.validator_value}, got {error.instance!r}"
    if v == "minItems":
        return "must not be empty" if error.validator_value == 1 else error.message
    if v == "pattern":
        return f"{error.instance!r} is not allowed ({error.schema.get('description', error.validator_value)})"
    if v == "enum":
        return f"must be one of {', '.join(map(repr, error.validator_value))}, got {error.instance!r}"
    if v == "oneOf" and isinstance(error.instance, dict):
        present = [s for s in DATASET_SOURCES if s in error.instance]
        if len(present) != 1:
            return (f"give exactly one data source ({', '.join(DATASET_SOURCES)}), "
                    f"got {', '.join(present) or 'none'}")
        alternative = list(DATASET_SOURCES).index(present[0])
        sub = [e for e in error.context if e.relative_schema_path and e.relative_schema_path[0] == alternative]
        if sub:
            best = jsonschema.exceptions.best_match(sub)
            where = ".".join(str(p) for p in best.relative_path)
            return (where + ": " if where else "") + _message(best)
    if v == "anyOf" and "description" in error.schema:
        return f"must be {error.schema['description']}, got {error.instance!r}"
    return error.message


# TOML keeps integers and floats apart: an "integer" is an int (JSON Schema would accept 1e9 as one)
_Validator = jsonschema.validators.extend(
    jsonschema.Draft202012Validator,
    type_checker=jsonschema.Draft202012Validator.TYPE_CHECKER.redefine(
        "integer", lambda checker, v: isinstance(v, int) and not isinstance(v, bool)))


def check_structure(cfg: dict, where: str, study_keys: dict | None = None) -> None:
    """Raise ConfigError for the first structural problem (unknown key, wrong type, missing table);
    ``study_keys``: the keys the config's study kind declares (its ``Study.config_schema``)."""
    from experiments.engine import ConfigError
    validator = _Validator(config_schema(study_keys))
    errors = sorted(validator.iter_errors(cfg), key=lambda e: (list(map(str, e.absolute_path)), e.validator))
    if errors:
        err = errors[0]
        raise ConfigError(f"{where}: {_path(err)}: {_message(err)}")
    _check_finite(cfg, where, "")


def _check_finite(value, where: str, path: str) -> None:
    """TOML accepts inf and nan: no config value may be one."""
    from experiments.engine import ConfigError
    if isinstance(value, float) and not math.isfinite(value):
        raise ConfigError(f"{where}: {path or '(top level)'}: must be a finite number, got {value!r}")
    if isinstance(value, dict):
        for k, v in value.items():
            _check_finite(v, where, f"{path}.{k}" if path else str(k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            _check_finite(v, where, f"{path}[{i}]")


# ---------------------------------------------------------------- value checks of the sources

#: data source key -> check(entry) raising ValueError with the problem (the source's own hook)
SOURCE_CHECKS: dict[str, Callable[[dict], None]] = {}


def register_source_check(source: str, check: Callable[[dict], None]) -> None:
    """Declare how a data source checks the values of one ``[[datasets]]`` entry (raise ValueError)."""
    SOURCE_CHECKS[source] = check


def _check_generator(entry: dict) -> None:
    from datasets.synthetic import check_params
    check_params(entry["generator"], entry.get("params", {}))
    for key, values in entry.get("grid", {}).items():
        for v in values:
            check_params(entry["generator"], {key: v})
            if key in entry.get("params", {}):
                raise ValueError(f"{key} is both in params and in grid")


def _check_published(entry: dict) -> None:
    import datasets
    if entry["published"] not in datasets.list():
        raise ValueError(f"unknown published data set {entry['published']!r}; known: {', '.join(datasets.list())}")


register_source_check("generator", _check_generator)
register_source_check("published", _check_published)


def check_values(cfg: dict, where: str) -> None:
    """The checks a schema cannot express: data source parameter values (each source's hook) and
    method parameter values (the registry's ``check_params``)."""
    from experiments.engine import ConfigError
    import methods
    for i, entry in enumerate(cfg.get("datasets", [])):
        source = next(s for s in DATASET_SOURCES if s in entry)
        check = SOURCE_CHECKS.get(source)
        if check is not None:
            try:
                check(entry)
            except ValueError as exc:
                raise ConfigError(f"{where}: datasets[{i}] ({source} {entry[source]!r}): {exc}") from None
    for i, entry in enumerate(cfg.get("methods", [])):
        if isinstance(entry, str):
            entry = {"id": entry}
        mid = entry["id"]
        if "." not in mid:  # a study-specific method name (its study validates it)
            continue
        try:
            specs = methods.list_methods(mid[:-2]) if mid.endswith(".*") else [methods.get(mid)]
        except methods.UnknownMethodError as exc:
            raise ConfigError(f"{where}: methods[{i}]: {exc}") from None
        if not specs:
            raise ConfigError(f"{where}: methods[{i}]: no registered methods in family {mid[:-2]!r}")
        for spec in specs:
            try:
                spec.check_params(entry.get("params", {}))
                for key, values in entry.get("grid", {}).items():
                    for v in values:
                        spec.check_params({key: v})
            except ValueError as exc:
                raise ConfigError(f"{where}: methods[{i}]: {exc}") from None
