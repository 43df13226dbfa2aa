"""The schema of a study config and the checks it cannot express. The config is typed (the pydantic models
below); the JSON Schema generated from them is checked with ``jsonschema`` once, when the config is loaded
(``experiments.config.load``), so that every error is one line naming the key.

ONE PLACE TO EXTEND:
* a new top-level key of every study (e.g. ``report``, ``tables``, ``figures``): add a field to
  :class:`StudyConfigModel` (:data:`TOP_LEVEL` is generated from it);
* a key only one kind of study uses (``rounding``, ``scenarios``, ...) is declared by that study's module as
  ``Study.config_schema`` = {key: JSON Schema}, merged here when a config of that kind is checked: adding a study
  needs no edit of this file (its ``validate`` checks the values the schema cannot express);
* a new kind of data source in ``[[datasets]]`` (e.g. ``file = "trace.csv"``, a plugin source): add its
  key to :data:`DATASET_SOURCES` with the schema of the entry's own keys (:func:`properties` of its model), and register the check of its
  parameter values with :func:`register_source_check`; a registered data source (``source = "NAME"``, a plugin's
  too) needs nothing here: its parameters' declared types (``DataSource.parameter_types``) are its schema.
Structure errors come from the schema; value errors of data source and method parameters from the sources'
declared types (:func:`check_source_params`) and the method registry's ``MethodSpec.check_params``. Every error
is one line: ``FILE: KEY: PROBLEM``.
"""
from __future__ import annotations

import copy
import difflib
import inspect
import math
from typing import Annotated, Any, Callable, Literal, Union

import jsonschema
from pydantic import BaseModel, Field

from experiments.study import ConfigTable

# ---------------------------------------------------------------- the typed config (pydantic models)
# A study config is these models; the JSON Schema checked below is generated from them (``model_json_schema``,
# normalised to plain JSON Schema: references inlined, optional keys as the key's own schema, no titles).
# Keys every study has are fields of :class:`StudyConfigModel`; a ``[[datasets]]`` entry is one of the entry
# models; the keys of one kind of study are its ``Study.config_schema``.

PositiveInt = Annotated[int, Field(ge=1)]
Grid = Annotated[dict[str, Annotated[list[Any], Field(min_length=1)]],
                 Field(description="parameter -> non-empty list of values (the cartesian product is taken)")]
Params = Annotated[dict[str, Any], Field(description="parameter -> value")]
Columns = Annotated[Union[str, list[str]], Field(description="a column name or a list of them")]


_Table = ConfigTable  # (experiments.study: a study kind's own keys are such a model too)


class GeneratorEntry(_Table):
    """A synthetic data set of a generator (the older spelling of ``source``)."""
    generator: str
    params: Params = None
    grid: Grid = None
    label: str = None


class PublishedEntry(_Table):
    """A published data set (``datasets.list()``)."""
    published: str
    variant: Literal["drop_repeated_closing_point"] = None
    label: str = None


class SourceEntry(_Table):
    """A data set of a registered data source (``datasets.sources``)."""
    source: str
    params: Params = None
    grid: Grid = None
    label: str = None


class FileEntry(_Table):
    """A points file, with its truth when known, and how to read it (``datasets.read_points``' options)."""
    file: Annotated[str, Field(min_length=1, description="a points file, relative to the TOML")]
    truth: dict[str, Any] = None
    label: str = None
    columns: Annotated[list[Union[str, Annotated[int, Field(ge=0)]]],
                       Field(min_length=2, max_length=2, description="the x and y columns: header names or 0-based "
                                                                     "indices")] = None
    plane: Literal["xy", "yz", "zx"] = None
    unit: Annotated[str, Field(min_length=1, description="the file's length unit (default: the header's, else mm)")] = None
    skip_rows: Annotated[int, Field(ge=0, description="lines of preamble before the header or the numbers")] = None


class MethodEntry(_Table):
    """A method with fixed parameters, a grid of them, a size limit and the data sets it runs on."""
    id: Annotated[str, Field(min_length=1)]
    params: Params = None
    grid: Grid = None
    max_n: PositiveInt = None
    on: list[str] = None
    any_family: Annotated[bool, Field(description="run on data sets whose source declares another family's shape "
                                                  "too (no errors against their truth)")] = None


class Timing(_Table):
    min_time_s: Annotated[float, Field(gt=0)] = None
    rounds: PositiveInt = None


class Report(_Table):
    section: Annotated[str, Field(min_length=1)] = None
    order: int = None
    findings: str = None


class TableDeclaration(_Table):
    caption: Annotated[str, Field(min_length=1)]
    rows: Columns
    values: Columns
    columns: str = None
    aggregate: Literal["mean", "median", "max", "min", "std", "count", "rmse", "ok_share"] = None
    unit: str = None
    digits: Annotated[int, Field(ge=1, le=17, description="significant digits of the numbers shown (1-17)")] = None
    where: dict[str, Any] = None
    colour: Annotated[Literal["lower_is_better"], Field(description="a method comparison: HTML cells coloured by their "
                                                                    "ratio to the row's best (lowest) value")] = None


class Ranking(_Table):
    profile: Annotated[str, Field(min_length=1)]
    metric: Annotated[str, Field(min_length=1)]
    unit: str = None
    methods: Annotated[str, Field(min_length=1)] = None
    problem: Annotated[list[str], Field(min_length=1)] = None
    floor: Annotated[float, Field(ge=0)] = None
    where: dict[str, Any] = None


class FigureDeclaration(_Table):
    caption: Annotated[str, Field(min_length=1)]
    plot: str = None
    file: str = None
    x: str = None
    y: str = None
    by: str = None
    aggregate: str = None
    logx: bool = None
    logy: bool = None
    xlabel: str = None
    ylabel: str = None
    args: dict[str, Any] = None
    width: Annotated[float, Field(gt=0)] = None
    height: Annotated[float, Field(gt=0)] = None
    where: dict[str, Any] = None


class StudyConfigModel(_Table):
    name: Annotated[str, Field(pattern=r"^[A-Za-z0-9_][A-Za-z0-9_-]*$",
                               description="the file name without .toml (ASCII letters A-Z a-z, digits, _ and -)")]
    title: Annotated[str, Field(min_length=1)]
    kind: Annotated[str, Field(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$")] = "grid"
    default: bool = False
    seed: Annotated[int, Field(ge=0)] = 0
    repetitions: PositiveInt = 1
    max_jobs: PositiveInt = None
    row_timeout: Annotated[float, Field(gt=0, description="seconds a row may run (engine)")] = None
    chunk_rows: PositiveInt = None
    length_unit: Annotated[str, Field(min_length=1, description="the unit of the study's lengths when they are not "
                                                                 "in mm, e.g. R for data on a unit circle")] = None
    summary_by: Annotated[list[str], Field(min_length=1)] = None
    datasets: Annotated[list[Union[GeneratorEntry, PublishedEntry, SourceEntry, FileEntry]], Field(min_length=1)] = None
    methods: Annotated[list[Annotated[Union[Annotated[str, Field(min_length=1)], MethodEntry],
                                      Field(description="a method id, or a table with id, params, grid, max_n, on")]],
                       Field(min_length=1)] = None
    timing: Timing = None
    quick: dict[str, Any] = None
    report: Report = None
    tables: list[TableDeclaration] = None
    rankings: list[Ranking] = None
    figures: list[FigureDeclaration] = None


def _inline(schema: dict) -> dict:
    """``schema`` with its ``$ref``s replaced by the definitions (jsonschema's error paths then name the key)."""
    defs = schema.get("$defs", {})
    def walk(node):
        if isinstance(node, dict):
            if "$ref" in node:
                target = copy.deepcopy(defs[node["$ref"].split("/")[-1]])
                rest = {k: v for k, v in node.items() if k != "$ref"}
                target.update(rest)
                return walk(target)
            return {k: walk(v) for k, v in node.items() if k != "$defs"}
        if isinstance(node, list):
            return [walk(v) for v in node]
        return node
    return walk(schema)


def _plain(node):
    """Pydantic's schema as the plain JSON Schema the messages read: an optional key is its own schema (not
    ``anyOf`` with null), no titles, defaults or model docstrings, an enum without a redundant type."""
    if isinstance(node, list):
        return [_plain(v) for v in node]
    if not isinstance(node, dict):
        return node
    node = {k: ({p: _plain(s) for p, s in v.items()} if k == "properties" else _plain(v))
            for k, v in node.items() if k not in ("title", "default")}
    if node.get("type") == "object" and "properties" in node:
        node.pop("description", None)  # a model's docstring
    if "anyOf" in node:
        alts = [a for a in node["anyOf"] if a != {"type": "null"}]
        if len(alts) == 1:
            rest = {k: v for k, v in node.items() if k != "anyOf"}
            node = {**alts[0], **rest}
        else:
            node["anyOf"] = alts
    if node.get("additionalProperties") is True:
        del node["additionalProperties"]
    if node.get("items") == {}:
        del node["items"]
    if "enum" in node or "const" in node:
        node.pop("type", None)
    if "const" in node and "enum" not in node:
        node = {**{k: v for k, v in node.items() if k != "const"}, "enum": [node["const"]]}
    if node.get("type") == "object" and "properties" in node and not node.get("required"):
        node.pop("required", None)
    return node


def properties(model: type[BaseModel]) -> dict[str, dict]:
    """{key: JSON Schema} of a model's fields, as :func:`config_schema` merges them."""
    return _plain(_inline(model.model_json_schema()))["properties"]


#: The keys of one ``[[datasets]]`` entry, per data source (the source key names the source).
DATASET_SOURCES: dict[str, dict] = {"generator": properties(GeneratorEntry), "published": properties(PublishedEntry),
                                    "source": properties(SourceEntry), "file": properties(FileEntry)}

#: Every top-level key a study config may have (generated from :class:`StudyConfigModel`; ``[[datasets]]`` entries
#: are checked against :data:`DATASET_SOURCES`). Keys overridable by ``[quick]`` are all but :data:`NOT_IN_QUICK`.
TOP_LEVEL: dict[str, dict] = {**properties(StudyConfigModel),
                              "datasets": {"type": "array", "minItems": 1, "items": {"type": "object"}}}
REQUIRED = tuple(StudyConfigModel.model_json_schema()["required"])
NOT_IN_QUICK = ("name", "kind", "default", "quick")


def _dataset_schema() -> dict:
    alternatives = []
    for source, keys in DATASET_SOURCES.items():
        alternatives.append({"type": "object", "required": [source], "properties": keys, "additionalProperties": False})
    return {"oneOf": alternatives}


def config_schema(study_keys: dict | type[BaseModel] | None = None) -> dict:
    """The JSON Schema of a whole config file (its ``[quick]`` table: the same keys, none required), with the
    keys its study kind declares (``study_keys``: its ``Study.config_schema``, a model of them or their JSON
    Schema)."""
    required = list(REQUIRED)
    if isinstance(study_keys, type) and issubclass(study_keys, BaseModel):
        required += study_keys.model_json_schema().get("required", [])  # the kind's keys without a default
        study_keys = properties(study_keys)
    clash = set(study_keys or {}) & set(TOP_LEVEL)
    if clash:
        raise ValueError(f"config_schema redefines the common key(s) {', '.join(sorted(clash))}")
    props = {k: dict(v) for k, v in {**TOP_LEVEL, **(study_keys or {})}.items()}
    props["datasets"] = {**props["datasets"], "items": _dataset_schema()}
    quick = {k: v for k, v in props.items() if k not in NOT_IN_QUICK}
    props["quick"] = {"type": "object", "properties": quick, "additionalProperties": False}
    return {"type": "object", "required": required, "properties": props, "additionalProperties": False}


def _path(error) -> str:
    parts = []
    for p in error.absolute_path:
        if isinstance(p, int):
            parts[-1:] = [f"{parts[-1]}[{p}]"] if parts else [f"[{p}]"]
        else:
            parts.append(str(p))
    return ".".join(parts) or "(top level)"


def _slip(error, extra: list[str], known, top_level) -> str:
    """The likely cause of an unknown key in a table (``[report]``) or in an entry of an array of tables
    (``[[methods]]``): the table's own key it is close to, else a top-level key written after the table's header
    (in TOML it belongs to that table)."""
    path = list(error.absolute_path)
    header = (f"[{path[0]}]" if len(path) == 1 and isinstance(path[0], str) else
              f"[[{path[0]}]]" if len(path) == 2 and isinstance(path[0], str) and isinstance(path[1], int) else None)
    for key in extra:
        own = difflib.get_close_matches(key, list(known), n=1)
        top = [key] if key in top_level else difflib.get_close_matches(key, list(top_level), n=1)
        if header and top and (top[0] == key or not own):
            what = f"{key!r} is a top-level key, and" if top[0] == key else f"did you mean the top-level key {top[0]!r}?"
            return (f"; {what} a key written after {header} belongs to that table in TOML: move it above the "
                    f"first [...] or [[...]]")
        if own:
            return f"; did you mean {own[0]!r}?"
    return ""


def _message(error, top_level=()) -> str:
    """A one-line reading of a jsonschema error (the most specific one for oneOf/anyOf); ``top_level``: the keys a
    config may have at its top level (for the hint of a key written after a ``[[table]]``)."""
    v = error.validator
    if v == "additionalProperties":
        extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
        known = ", ".join(sorted(error.schema.get("properties", {})))
        return (f"unknown key{'s' if len(extra) > 1 else ''} {', '.join(map(repr, extra))} (known: {known})"
                + _slip(error, extra, error.schema.get("properties", {}), top_level))
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
            return (where + ": " if where else "") + _message(best, top_level)
    if v == "anyOf" and isinstance(error.instance, dict):  # a table where a value or a table may stand: the table's
        tables = [k for k, alt in enumerate(error.validator_value) if alt.get("type") == "object"]   # own problem
        sub = [e for e in error.context if e.relative_schema_path and e.relative_schema_path[0] in tables]
        if len(tables) == 1 and sub:
            best = jsonschema.exceptions.best_match(sub)
            where = ".".join(str(p) for p in best.relative_path)
            return (where + ": " if where else "") + _message(best, top_level)
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
    from experiments.study import ConfigError
    schema = config_schema(study_keys)
    validator = _Validator(schema)
    errors = sorted(validator.iter_errors(cfg), key=lambda e: (list(map(str, e.absolute_path)), e.validator))
    if errors:
        err = errors[0]
        raise ConfigError(f"{where}: {_path(err)}: {_message(err, schema['properties'])}")
    _check_finite(cfg, where, "")


def _check_finite(value, where: str, path: str) -> None:
    """TOML accepts inf and nan: no config value may be one."""
    from experiments.study import ConfigError
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


#: the JSON Schema of each parameter of a data source, by (name, function): its declared types (annotations, else
#: the defaults' types, ``datasets.sources.DataSource.parameter_types``) through pydantic
_SOURCE_SCHEMAS: dict = {}


def source_parameters(source) -> dict[str, dict]:
    """{parameter: JSON Schema} of a registered data source (``datasets.sources.DataSource``)."""
    memo = (source.name, source.func)
    if memo not in _SOURCE_SCHEMAS:
        from pydantic import PydanticSchemaGenerationError, TypeAdapter
        schemas = {}
        for name, (kind, _) in source.parameter_types().items():
            try:
                schemas[name] = _bounded(_plain(_inline(TypeAdapter(kind).json_schema())))
            except PydanticSchemaGenerationError:
                raise ValueError(f"data source {source.name!r}: parameter {name!r} is annotated {kind!r}, a type no "
                                 f"TOML value has; annotate it with int, float, str, bool, list[...], tuple[...] or "
                                 f"Literal[...]") from None
        _SOURCE_SCHEMAS[memo] = schemas
    return _SOURCE_SCHEMAS[memo]


#: the largest value of a data source's integer parameter that declares no bound of its own (a count of points,
#: targets, runs: every row holds its data set in memory, and n = 10^9 points of a circle would be 16 GB); a source
#: declares a larger one by annotation (``n: Annotated[int, Field(ge=1, le=10**8)]``)
MAX_COUNT = 10_000_000


def _bounded(schema):
    """``schema`` with :data:`MAX_COUNT` as the maximum of every integer in it that declares none."""
    if isinstance(schema, list):
        return [_bounded(v) for v in schema]
    if not isinstance(schema, dict):
        return schema
    out = {k: _bounded(v) for k, v in schema.items()}
    if out.get("type") == "integer" and "maximum" not in out and "exclusiveMaximum" not in out:
        out["maximum"] = MAX_COUNT
    return out


_BOUNDS = (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="), ("exclusiveMaximum", "<"))
_NOUNS = {"integer": ("an integer", "integers"), "number": ("a number", "numbers"), "string": ("a string", "strings"),
          "boolean": ("true or false", "booleans"), "object": ("a table", "tables"), "array": ("a list", "lists")}


def describe(schema: dict, plural: bool = False) -> str:
    """What a value of a (plain) JSON Schema must be, in words: ``an integer >= 1``, ``a list of 2 numbers``,
    ``one of 'isotropic', 'radial'``."""
    if "description" in schema:
        return schema["description"]
    if "enum" in schema:
        return ("one of " if len(schema["enum"]) > 1 else "") + ", ".join(map(repr, schema["enum"]))
    if "anyOf" in schema:
        return " or ".join(describe(alt, plural) for alt in schema["anyOf"])
    kind = schema.get("type")
    if kind not in _NOUNS:
        return "values" if plural else "any value"
    text = _NOUNS[kind][plural]
    bounds = [f"{op} {schema[key]}" for key, op in _BOUNDS if key in schema]
    if bounds:
        text += " " + " and ".join(bounds)
    if kind == "array":
        items = schema.get("prefixItems")
        if items and all(item == items[0] for item in items):
            text = f"{'lists' if plural else 'a list'} of {len(items)} {describe(items[0], True)}"
        elif items:
            text += " [" + ", ".join(describe(item) for item in items) + "]"
        elif schema.get("items"):
            text += " of " + describe(schema["items"], True)
    return text


def check_source_params(name: str, params: dict, grid: dict, what: str = "data source") -> None:
    """Raise ValueError for the first parameter of data source ``name`` (a ``[[datasets]]`` entry's ``params`` and
    ``grid``) that it does not have, that is missing, or whose value is not of its declared type
    (:func:`source_parameters`): ``grid.n = 30.5 must be an integer >= 1``. Numbers given as strings are refused,
    never coerced (``radius = "5"``)."""
    from datasets import sources
    try:
        source = sources.get_source(name)
    except KeyError:
        known = ", ".join(s.name for s in sources.list_sources() if s.name not in ("published", "file"))
        raise ValueError(f"unknown {what} {name!r}; known: {known}") from None
    if name in ("published", "file"):
        raise ValueError(f"write {name} = ... instead of source = {name!r}")
    schemas = source_parameters(source)
    for key in [*params, *grid]:
        if key not in schemas:
            raise ValueError(f"{what} {name!r} has no parameter {key!r}; its parameters are: "
                             f"{', '.join(sorted(schemas)) or 'none'}")
        if key in params and key in grid:
            raise ValueError(f"{key} is both in params and in grid")
    missing = [key for key, (_, default) in source.parameter_types().items()
               if default is inspect.Parameter.empty and key not in params and key not in grid]
    if missing:
        raise ValueError(f"{what} {name!r} needs the parameter(s) {', '.join(missing)} (in params or grid)")
    values = [(f"params.{k}", k, v) for k, v in params.items()]
    values += [(f"grid.{k}", k, v) for k, vs in grid.items() for v in (vs if isinstance(vs, list) else [vs])]
    for label, key, value in values:
        error = next(_Validator(schemas[key]).iter_errors(value), None)
        if error is not None:
            why = (" (the bound of a data source's integer parameters that declare none: every row holds its data "
                   "in memory)" if error.validator == "maximum" and error.validator_value == MAX_COUNT else "")
            raise ValueError(f"{label} = {value!r} must be {describe(schemas[key])}{why}")


def _check_generator(entry: dict) -> None:
    check_source_params(entry["generator"], entry.get("params", {}), entry.get("grid", {}), "generator")


def _check_source(entry: dict) -> None:
    check_source_params(entry["source"], entry.get("params", {}), entry.get("grid", {}))


def _check_published(entry: dict) -> None:
    import datasets
    if entry["published"] not in datasets.list():
        raise ValueError(f"unknown published data set {entry['published']!r}; known: {', '.join(datasets.list())}")


register_source_check("generator", _check_generator)
register_source_check("source", _check_source)
register_source_check("published", _check_published)


# ---------------------------------------------------------------- a file's truth table

def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _numbers(v, n: int, positive: bool = False) -> bool:
    return isinstance(v, list) and len(v) == n and all(_number(x) and (x > 0 or not positive) for x in v)


#: The keys of a ``file = ...`` data set's ``truth`` table: what the built-in result classes' ``truth_errors`` compare
#: (``methods.result_base.center_errors``, ``CircleFit``, ``EllipseFit``, ``CircularTestFit``; read by
#: tests/test_file_truth.py) and ``family`` (the shape the points are of, ``check_data_kinds``): key -> (what its value
#: must be, its check).
TRUTH_KEYS: dict[str, tuple[str, Callable]] = {
    "center": ("2 finite numbers [x, y] (the true centre, in mm: the points are read in mm)", lambda v: _numbers(v, 2)),
    "radius": ("a number > 0 (the true radius, in mm)", lambda v: _number(v) and v > 0),
    "semi_axes": ("2 numbers > 0 [a, b] (the true semi-axes in mm, a the one at angle)",
                  lambda v: _numbers(v, 2, positive=True)),
    "angle": ("a number (the true direction of semi-axis a, in rad)", _number),
    "family": ("the family name of the points' shape (e.g. 'circle', 'ellipse')", lambda v: isinstance(v, str) and v),
}
#: the truth keys each built-in family's result class compares (a family declared here: no other key may stand in its
#: truth; another family's truth is read by its own class, whatever its keys)
FAMILY_TRUTH: dict[str, tuple[str, ...]] = {"circle": ("center", "radius"), "ellipse": ("center", "semi_axes", "angle"),
                                            "circular_test": ("center",)}


def truth_problem(truth: dict) -> tuple[str, str] | None:
    """(the key, what is wrong with it) of the first problem of a file's ``truth`` table (:data:`TRUTH_KEYS`), before
    any row: a shape a fit cannot be compared with (``center = [120.0]``) made every row ``error`` with an
    IndexError, an unknown key (``centre``) was ignored. None when sound."""
    family = truth.get("family")
    known = (*FAMILY_TRUTH[family], "family") if family in FAMILY_TRUTH else tuple(TRUTH_KEYS)
    for key, value in truth.items():
        if key not in TRUTH_KEYS or key not in known:
            if key not in TRUTH_KEYS and isinstance(family, str) and family not in FAMILY_TRUTH:
                continue  # another family's class reads its own keys
            close = difflib.get_close_matches(str(key), list(known), n=1)
            whose = f"the truth of a {family} has" if family in FAMILY_TRUTH else "a file's truth has"
            return key, (f"unknown key ({whose}: {', '.join(known)}; no fit compares {key!r})"
                         + (f"; did you mean {close[0]!r}?" if close else ""))
        words, ok = TRUTH_KEYS[key]
        if not ok(value):
            return key, f"must be {words}, got {value!r}"
    if ("semi_axes" in truth) != ("angle" in truth):
        given, lacking = ("semi_axes", "angle") if "semi_axes" in truth else ("angle", "semi_axes")
        return given, f"needs {lacking} too (an ellipse's errors compare the semi-axes and the angle together)"
    return ellipse_truth_problem(truth) if "semi_axes" in truth else None


def ellipse_truth_problem(truth: dict) -> tuple[str, str] | None:
    """(key, problem) of an ellipse truth the ellipse family's convention cannot compare (``EllipseFit``: a >= b, the
    angle that of a in rad, its error taken modulo pi): ``semi_axes = [40.0, 50.0]`` compared a with b crosswise
    (semi_axis_a_error 10 mm of an exact fit), ``angle = 30.0`` (degrees, as generators' ``angle_deg``) gave an angle
    error of -0.60 rad. An angle beyond +-2 pi is no radian convention's (0..pi, -pi..pi, 0..2 pi)."""
    (a, b), angle = truth["semi_axes"], truth["angle"]
    if a < b:
        turned = (angle + math.pi / 2) % math.pi
        return "semi_axes", (f"a >= b (the semi-major axis first, at angle; the fits give a >= b), got [{a:g}, {b:g}]: "
                             f"write semi_axes = [{b:g}, {a:g}], angle = {turned:.6g} (the angle of {b:g} in rad)")
    if abs(angle) > 2 * math.pi:
        return "angle", (f"{angle:g} is beyond ±2π: the angle is in rad (the direction of semi-axis a; "
                         f"{angle:g}° is {math.radians(angle):.6g} rad)")
    return None


def check_values(cfg: dict, where: str) -> None:
    """The checks a schema cannot express: data source parameter values (each source's hook) and
    method parameter values (the registry's ``check_params``)."""
    from experiments.study import ConfigError
    import methods
    for i, entry in enumerate(cfg.get("datasets", [])):
        source = next(s for s in DATASET_SOURCES if s in entry)
        check = SOURCE_CHECKS.get(source)
        if check is not None:
            try:
                check(entry)
            except ValueError as exc:
                raise ConfigError(f"{where}: datasets[{i}] ({source} {entry[source]!r}): {exc}") from None
        if source == "file" and isinstance(entry.get("truth"), dict):
            problem = truth_problem(entry["truth"])
            if problem:
                raise ConfigError(f"{where}: datasets[{i}].truth.{problem[0]}: {problem[1]}")
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
    check_data_kinds(cfg, where)
    check_on_labels(cfg, where)


def check_on_labels(cfg: dict, where: str) -> None:
    """Refuse a method's ``on = [...]`` label that names no ``[[datasets]]`` entry (a typo would run the method on
    nothing, silently, or leave the study without rows)."""
    from experiments.study import ConfigError
    if not cfg.get("datasets"):
        return
    labels = list(dict.fromkeys(_entry_source(e)[1] for e in cfg["datasets"]))
    for i, entry in enumerate(cfg.get("methods", [])):
        for label in ([] if isinstance(entry, str) else entry.get("on") or []):
            if label not in labels:
                close = difflib.get_close_matches(label, labels, n=1)
                raise ConfigError(f"{where}: methods[{i}]: on = [...] names {label!r}, no data set's label"
                                  f"{f' (did you mean {close[0]!r}?)' if close else ''}; the labels are: "
                                  f"{', '.join(map(repr, labels))} (a [[datasets]] entry's label, else its source, "
                                  f"published set or file name)")


def method_takes(spec) -> type | None:
    """The type of data a method takes: what its family's validator returns (its return annotation,
    ``methods.register(validator=...)``), ``numpy.ndarray`` (an (N, 2) array of points) for a method without a
    validator (the registry's ``validate_points``); None when its validator declares no type."""
    import typing
    import numpy as np
    if spec.validator is None:
        return np.ndarray
    try:
        kind = typing.get_type_hints(spec.validator).get("return")
    except Exception:  # an annotation that cannot be resolved: not declared
        return None
    return kind if isinstance(kind, type) else None


def data_words(kind: type) -> str:
    """A type of data as a message names it: 'points (an (N, 2) array)', else the class name."""
    import numpy as np
    return "points (an (N, 2) array)" if kind is np.ndarray else kind.__name__


def _entry_source(entry: dict) -> tuple[str, str]:
    """(the registered source of a ``[[datasets]]`` entry, its label as ``on = [...]`` names it)."""
    if "published" in entry:
        return "published", entry.get("label", entry["published"] + (f":{entry['variant']}" if entry.get("variant")
                                                                      else ""))
    if "file" in entry:
        from pathlib import PurePath
        return "file", entry.get("label", PurePath(entry["file"]).stem)
    name = entry.get("source", entry.get("generator"))
    return name, entry.get("label", name)


def check_data_kinds(cfg: dict, where: str) -> None:
    """Refuse a method paired with a data set whose data it cannot take (a positioning method on the points of
    ``source = "circle"``): the type the data source declares it gives (``datasets.sources.register_source(gives=
    ...)``) against the type the method takes (:func:`method_takes`), for every data set the method runs on (all,
    or those its ``on`` names). Nothing is checked where either side declares no type. Likewise a method of one
    family paired with a source whose data are another family's shape (``register_source(family=...)``, or the
    ``family`` of a file's truth table): a circle fit on a square outline, unless its entry says ``any_family = true``
    (its rows then carry no errors against that truth: ``experiments.rows``)."""
    from experiments.study import ConfigError
    from datasets import sources
    import methods
    if not cfg.get("datasets") or not cfg.get("methods"):
        return
    data, shapes = [], []
    for j, entry in enumerate(cfg["datasets"]):
        name, label = _entry_source(entry)
        try:
            source = sources.get_source(name)
        except KeyError:
            continue
        if source.gives is not None:
            data.append((j, name, label, source.gives))
        truth = entry.get("truth") if "file" in entry else None  # a file's truth table may name its shape
        family = truth.get("family") if isinstance(truth, dict) else source.family
        if isinstance(family, str):
            shapes.append((j, name, label, family))
    for i, entry in enumerate(cfg["methods"]):
        entry = {"id": entry} if isinstance(entry, str) else entry
        mid = entry["id"]
        if "." not in mid:
            continue
        specs = methods.list_methods(mid[:-2]) if mid.endswith(".*") else [methods.get(mid)]
        on = entry.get("on")
        for spec in specs:
            takes = method_takes(spec)
            if takes is None:
                continue
            for j, name, label, gives in data:
                if (on is None or label in on) and not issubclass(gives, takes):
                    raise ConfigError(
                        f"{where}: methods[{i}]{f' ({mid})' if mid != spec.id else ''}: {spec.id} cannot take the data "
                        f"of datasets[{j}] (source {name!r}): the source gives {data_words(gives)}, {spec.id} takes "
                        f"{data_words(takes)}; remove the method, or name the data sets it takes in its on = [...]")
        if entry.get("any_family"):
            continue
        for spec in specs:
            for j, name, label, family in shapes:
                if (on is None or label in on) and family != spec.family:
                    raise ConfigError(
                        f"{where}: methods[{i}]{f' ({mid})' if mid != spec.id else ''}: {spec.id} (family "
                        f"{spec.family!r}) would fit datasets[{j}] (source {name!r}), whose points and truth are of "
                        f"family {family!r}; remove the method, name the data sets it fits in its on = [...], or set "
                        f"any_family = true in its [[methods]] entry to fit them anyway (no errors against the truth "
                        f"of another family)")
