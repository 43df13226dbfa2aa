"""A data source that breaks its contract (NaN points, (N, 3) points) is blamed for it: its rows are 'error' naming
the data set, the source and the problem, never 'skipped' rows blaming each method for refusing the data."""
import numpy as np
import pandas as pd
import pytest

from datasets.sources import register_source
from experiments.rows import points_problem
from experiments.run import main as run_main


def _nan_source(rng, *, n: int = 20):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    p = np.c_[np.cos(t), np.sin(t)]
    p[3, 0] = np.nan
    return p, {"center": (0.0, 0.0), "radius": 1.0}


def _three_source(rng, *, n: int = 20):
    return rng.normal(size=(n, 3)), None


def _good_source(rng, *, n: int = 20):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[np.cos(t), np.sin(t)] + rng.normal(0, 0.01, (n, 2)), {"center": (0.0, 0.0), "radius": 1.0}


STUDY = """name = "contract"
title = "broken data sources"
seed = 1
repetitions = 2
[[datasets]]
source = "test_contract_good"
[[datasets]]
source = "test_contract_nan"
[[datasets]]
source = "test_contract_3d"
[[methods]]
id = "circle.kasa"
[[methods]]
id = "circle.gauss_newton"
"""


@pytest.fixture
def contract_sources():
    """Data sources of a plugin, registered from this module for one test only."""
    from datasets import sources
    named = {"test_contract_nan": (_nan_source, "a circle with one NaN point (contract test)"),
             "test_contract_3d": (_three_source, "(N, 3) points (contract test)"),
             "test_contract_good": (_good_source, "a noisy unit circle (contract test)")}
    for name, (func, summary) in named.items():
        register_source(name, random=True, summary=summary)(func)
    yield
    for name in named:
        sources._REGISTRY.pop(name, None)


def test_broken_sources_give_error_rows_naming_the_source(tmp_path, contract_sources):
    cfg = tmp_path / "contract.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    assert run_main([str(cfg), "--jobs", "1", "--no-report", "--out", str(tmp_path / "out")]) == 0
    df = pd.read_csv(tmp_path / "out" / "contract" / "results.csv")
    assert len(df) == 3 * 2 * 2
    good = df[df["dataset"] == "test_contract_good"]
    assert (good["status"] == "ok").all()
    for label, problem in (("test_contract_nan", "gave 1 of 20 points with NaN or inf (first at index 3)"),
                           ("test_contract_3d", "gave points of shape (20, 3), not an (N, 2) array of x, y")):
        bad = df[df["dataset"] == label]
        assert len(bad) == 4 and (bad["status"] == "error").all(), bad[["method", "status", "message"]]
        for message in bad["message"]:
            assert f"data set '{label}' (source '{label}') {problem}" in message, message
            assert "the data source is at fault" in message and "circle." not in message, message


@pytest.mark.parametrize("data, words", [
    (np.zeros((0, 2)), "gave no points"),
    (np.array([[1.0, 2.0], [np.inf, 0.0], [np.nan, 1.0]]), "gave 2 of 3 points with NaN or inf (first at index 1)"),
    (np.zeros((5, 2), dtype=complex), "not real numbers"),
    (np.array([["a", "b"]]), "not real numbers"),
    ([[0.0, 1.0]], "gave a list, not an (N, 2) numpy array"),
    (np.zeros((2, 5)), "shape (2, 5)"),
])
def test_points_problem_names_what_is_wrong(data, words):
    assert words in points_problem(data)


def test_good_points_pass():
    assert points_problem(np.zeros((3, 2), dtype=np.float32)) is None
    assert points_problem(np.arange(6).reshape(3, 2)) is None
