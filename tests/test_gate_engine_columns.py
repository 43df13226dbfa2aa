"""A result cannot write the columns the engine writes: a plugin's class declaring ``status`` or ``time_median_s``
(docs/plugins.md's SquareFit recipe with two more columns) overwrote the row's status with 1 and showed a runtime the
engine never measured. The declaration is refused when the class is defined; a plugin's class giving such a column
without declaring it makes the row ``invalid`` with the column's name."""
import gc
from dataclasses import dataclass, fields

import numpy as np
import pytest

import methods
from experiments.rows import _finished, fit_row
from methods import result_base, results
from plugin_methods import registered

T = np.linspace(0.0, 2 * np.pi, 40, endpoint=False)
PTS = np.column_stack([3.0 + 2.0 * np.cos(T), -1.0 + 2.0 * np.sin(T)]) + np.random.default_rng(5).normal(
    scale=1e-3, size=(40, 2))
TRUTH = {"center": (3.0, -1.0), "radius": 2.0}

RESERVED = ["study", "dataset", "repetition", "seed", "data_stream", "method", "params", "status", "message",
            "converged", "iterations", "nfev", "task_index", "time_median_s", "time_iqr_s", "data_n", "param_shrink"]


@pytest.mark.parametrize("name", RESERVED)
def test_a_class_declaring_an_engine_column_is_refused_when_defined(name):
    try:
        with pytest.raises(results.DeclarationError, match=rf"declares the column '{name}', which the engine writes"
                                                           rf".*rename the column \(e\.g\. enginecols_{name}\)"):
            @dataclass(kw_only=True)
            class Clashing(results.FitResult):
                FAMILY = "enginecols"
                COLUMNS = (*results.FitResult.COLUMNS, results.Column(name, "count", results.EXACT))
    finally:
        gc.collect()  # the refused class is gone: no later test finds its declaration among the result classes
    assert name not in result_base.row_columns()


def _task(method, params=None, timing=None):
    task = {"study": "engine_columns", "dataset": {"label": "ring", "params": {"n": 40, "noise": 1e-3}},
            "repetition": 0, "seed": 1, "stream": (0,), "method": method, "params": params or {}, "index": 7}
    if timing:
        task["timing"] = timing
    return task


def test_every_column_the_engine_writes_is_reserved():
    """The row of a built-in method with a data set parameter, a method parameter and timing: each column no result
    class declares is one the engine writes, and reserved (the list cannot drift from experiments/rows.py)."""
    row = _finished(fit_row(_task("circle.levenberg_marquardt", {"max_iter": 50},
                                  {"min_time_s": 0.0, "rounds": 1}), PTS, TRUTH), _task("circle.kasa"))
    declared = result_base.row_columns()
    engine = [k for k in row if k not in declared]
    assert {"status", "task_index", "time_median_s", "data_n", "param_max_iter"} <= set(engine)
    assert [k for k in engine if not result_base.engine_column(k)] == []


@dataclass(kw_only=True)
class TileFit(results.FitResult):
    """A new family's class giving engine columns from geometry() without declaring them."""

    side: float
    FAMILY = "enginecols"
    SHAPES = {"residuals": ("n",)}

    def geometry(self):
        return {"side": self.side, "status": 1, "time_median_s": 1e-9}


@dataclass(kw_only=True)
class StatusCircleFit(results.CircleFit):
    """A circle method's class adding an undeclared 'status' and timing to its geometry."""

    def geometry(self):
        return {**super().geometry(), "status": 1.0, "time_median_s": 1e-9}


def _tile(points):
    lo, hi = points.min(axis=0), points.max(axis=0)
    side = float((hi - lo).mean())
    residuals = np.abs(points - (lo + hi) / 2).max(axis=1) - side / 2
    return TileFit(side=side, residuals=residuals, form_error=float(np.ptp(residuals)), converged=True,
                   message="closed form")


def _status_circle(points):
    c = points.mean(axis=0)
    base = results.circle_result(points, c, float(np.hypot(*(points - c).T).mean()), converged=True, message="ok")
    return StatusCircleFit(**{f.name: getattr(base, f.name) for f in fields(base)})


@pytest.fixture
def plugin_methods():
    methods.list_methods()
    with registered({"enginecols.tile": _tile}, kind="closed form", summary="bbox", reference="test"), \
            registered({"circle.test_status_column": _status_circle}, kind="closed form", summary="centroid",
                       reference="test"):
        yield


@pytest.mark.parametrize("method", ["enginecols.tile", "circle.test_status_column"])
def test_a_result_giving_an_engine_column_is_an_invalid_row(plugin_methods, method):
    row = fit_row(_task(method), PTS, TRUTH)
    assert row["status"] == "invalid", row
    assert "'status', 'time_median_s', which the engine writes in the row; rename them" in row["message"], row
    assert "time_median_s" not in row and row["method"] == method and row["repetition"] == 0
