"""A row's cache key holds the versions of the libraries its code uses, not of those only the run, the report or the
figures use: a study module reaches the engine through its config (``cfg.grid_tasks()``, ``cfg.expand_methods()``)
and the row helpers in ``experiments.rows``, and its figures take matplotlib from output code that no row's key enters
(``experiments.render``: ``experiments.codehash.OUTPUT_PACKAGES``), so upgrading matplotlib, tqdm or Dask recomputes no row, upgrading NumPy
every row (docs/studies.md)."""
from __future__ import annotations

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
