"""A row's cache key holds the versions of the libraries its code uses, not of those only the run, the report or the
figures use: a study module reaches the engine through its config (``cfg.grid_tasks()``, ``cfg.expand_methods()``)
and the row helpers in ``experiments.rows``, and its figures take matplotlib from output code that no row's key enters
(``experiments.render``: ``experiments.codehash.OUTPUT_PACKAGES``), so upgrading matplotlib, tqdm or Dask recomputes no row, upgrading NumPy
every row (docs/studies.md)."""
from __future__ import annotations

import contextlib
import types
from importlib import metadata

import pytest

from experiments import codehash, codekeys
from experiments import config as configs
from experiments.studies import study_of

#: libraries of the run (progress bars, Dask), of the report (templates, Markdown), of the figures and of the
#: config's checks (jsonschema)
NOT_ROW_LIBRARIES = {"matplotlib", "tqdm", "dask", "distributed", "jinja2", "markdown_it_py", "markdown-it-py",
                     "markupsafe", "MarkupSafe", "jsonschema"}


@pytest.fixture
def fresh_keys():
    codekeys.reset_caches()
    yield
    codekeys.reset_caches()  # no key of a reported version that is not installed outlives the test


def _first_key(monkeypatch, study: str, bumped: str | None = None) -> str:
    """The cache key of the first row of ``study`` (its quick config) when ``bumped`` reports another version."""
    real = metadata.version
    monkeypatch.setattr(metadata, "version", lambda name: "999.0" if name == bumped else real(name))
    codekeys.reset_caches()
    cfg = configs.load(study, quick=True)
    return next(iter(study_of(cfg["kind"]).prepared_tasks(cfg)))["key"]


def test_a_default_studys_row_key_follows_numpy_not_matplotlib_or_tqdm(monkeypatch, fresh_keys):
    key = _first_key(monkeypatch, "noise")  # a study that draws its own figures
    assert _first_key(monkeypatch, "noise", "matplotlib") == key
    assert _first_key(monkeypatch, "noise", "tqdm") == key
    assert _first_key(monkeypatch, "noise", "numpy") != key


def test_no_study_module_keys_its_rows_with_a_library_of_the_run_report_figures_or_checks(fresh_keys):
    kinds = sorted({configs.load(name)["kind"] for name in configs.available()} | {"grid"})
    for kind in kinds:
        used = codehash.libraries_of(f"experiments.studies.{kind}", "experiments.rows", "experiments.metrics",
                                     "experiments.timing")
        assert "numpy" in used and not NOT_ROW_LIBRARIES & set(used), (kind, sorted(used))


def test_output_code_is_in_the_outputs_hash_and_in_no_row_key(fresh_keys):
    """experiments.render (the figures' style and matplotlib) enters the outputs' hash, not the closure of a study's
    rows; the code every row runs imports no output code at all."""
    style = codehash.REPO / "experiments" / "render" / "style.py"
    rows = {p for m in ("experiments.studies.noise", "experiments.rows") for p in codehash.files_of(m)}
    outputs = set(codehash.files_of("experiments.studies.noise", outputs=True))
    assert style not in rows and style in outputs
    assert "matplotlib" in codehash.libraries_of("experiments.studies.noise", outputs=True)
    for module in ("experiments.rows", "experiments.metrics", "experiments.timing"):
        closure = {name for name, _ in codehash.module_closure(module, outputs=True)}
        assert not {n for n in closure if codehash._output_module(n)}, module


# ---------------------------------------------------------------- no row code reaches output code

#: a study's methods that make, count, check or key its rows (the rest, ``analyse``, is its outputs' code)
ROW_METHODS = ("validate", "count_rows", "tasks", "prepared_tasks", "execute", "row_columns")
#: fitbench's packages, whose functions the check follows
OURS = ("experiments", "methods", "datasets", "fitbench")


def _ours(name) -> bool:
    return isinstance(name, str) and name.split(".")[0] in OURS


def _codes(code):
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _codes(const)


def output_code_reached(cls, roots=ROW_METHODS) -> list[str]:
    """Where the code of ``cls``'s row methods can reach output code (:data:`experiments.codehash.OUTPUT_PACKAGES`):
    the functions it may call, followed through the names each uses (its globals and closure, a module's attributes,
    the class's methods: more than it calls, never less), stopping at code outside fitbench. An import of output code inside a
    reached function, or a reached name bound to output code, is a hit ("FUNCTION -> NAME")."""
    hits, seen = [], set()
    todo = [(getattr(cls, name), f"{cls.__name__}.{name}") for name in roots if hasattr(cls, name)]
    while todo:
        value, where = todo.pop()
        if isinstance(value, property):
            value = value.fget
        value = getattr(value, "__func__", value)
        code = getattr(value, "__code__", None)
        if code is None or code in seen or not _ours(getattr(value, "__module__", None)):
            continue
        seen.add(code)
        names = {n for c in _codes(code) for n in c.co_names}
        env = getattr(value, "__globals__", {})
        found = [(n, env[n]) for n in names if n in env] + [(n, getattr(cls, n)) for n in names if hasattr(cls, n)]
        for n, cell in zip(code.co_freevars, getattr(value, "__closure__", None) or ()):
            with contextlib.suppress(ValueError):   # an empty cell
                found.append((n, cell.cell_contents))
        found += [(f"{n}.{a}", getattr(m, a)) for n, m in list(found)
                  if isinstance(m, types.ModuleType) and _ours(m.__name__) for a in names if hasattr(m, a)]
        hits += [f"{where} -> import {n}" for n in names if codehash._output_module(n)]
        for name, obj in found:
            module = obj.__name__ if isinstance(obj, types.ModuleType) else getattr(obj, "__module__", None)
            if isinstance(module, str) and codehash._output_module(module):
                hits.append(f"{where} -> {name}")
            elif isinstance(obj, type) and _ours(module):
                todo += [(v, f"{obj.__name__}.{k}") for k, v in vars(obj).items() if k in names or k == "__init__"]
            elif not isinstance(obj, types.ModuleType):
                todo.append((obj, getattr(obj, "__qualname__", name)))
    return sorted(set(hits))


def test_no_study_s_row_code_reaches_output_code():
    """A row's key leaves experiments.render out (OUTPUT_PACKAGES); so no study's rows may run it: a study module
    imports it for its analysis and figures, and its row methods (and what they call) never reach it, or an edit of
    the output code would serve stale cached rows."""
    from experiments import studies
    from experiments.study import Study
    classes = [type(study_of(kind)) for kind in studies.kinds()] + [Study]
    for cls in classes:
        assert not output_code_reached(cls), (cls.__name__, output_code_reached(cls))
    assert output_code_reached(type(study_of("noise")), ("analyse",))  # it does reach it from its analysis


PLANTED = """
from experiments.render.text import joined
from experiments.study import Study


def label(parts):
    return joined(parts)


class Direct(Study):
    def execute(self, task):
        return {"label": joined(["a", "b"])}


class Nested(Study):
    def execute(self, task):
        return {"label": self._label(task)}

    def _label(self, task):
        from experiments.render import text
        return text.joined(["a"])


class Helper(Study):
    def tasks(self, cfg):
        return [label(["x"])]

    def analyse(self, rows, cfg, target, log):
        return joined(["fine: outputs"])
"""


def test_the_check_finds_row_code_that_reaches_output_code():
    """A study module importing output code at its top (as noise.py does for its analysis) whose rows call it:
    directly, through a helper of its module, or by an import inside a method."""
    from experiments import studies
    module = types.ModuleType("experiments.studies._planted")
    before = set(studies.CLASSES)
    try:
        exec(compile(PLANTED, "<planted study>", "exec"), vars(module))
    finally:
        studies.CLASSES.intersection_update(before)   # no planted kind outlives the test
    assert output_code_reached(module.Direct) == ["Direct.execute -> joined"]
    assert "Nested._label -> import experiments.render" in output_code_reached(module.Nested)
    assert output_code_reached(module.Helper) == ["label -> joined"]
