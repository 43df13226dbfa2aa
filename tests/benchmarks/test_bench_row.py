"""pytest-benchmark cases: the CPU of one benchmark row inside a worker (``experiments.rows.run_task``) against
the fit alone, on the tasks of the engine's benchmark study (``engine_40k.toml``: a 100-point circle, full and
a 90° arc, 0.01 noise; circle.kasa and circle.gauss_newton). The difference between a row and its fit is the
engine's per-row overhead (the result gate, the metrics, the row's columns); the data generation is measured
on its own (each repetition draws new data; the methods of one repetition share it). docs/speed.md lists the
figures.

Run:  python -m pytest tests/benchmarks/test_bench_row.py --benchmark-enable --benchmark-group-by=group
(the default test run executes each case once, as a smoke test, with benchmarking disabled).
"""
from pathlib import Path

import pytest

import methods
from experiments import config as configs, rows
from experiments.metrics import metrics
from experiments.studies import study_of

STUDY = Path(__file__).resolve().parent / "engine_40k.toml"


@pytest.fixture(scope="module")
def tasks():
    """The first repetition's four tasks (two data sets x two methods) of the benchmark study."""
    cfg = configs.load(str(STUDY))
    out = []
    for task in study_of(cfg["kind"]).prepared_tasks(cfg):
        if task["repetition"] == 0:
            out.append(task)
        if len(out) == 4:
            return out
    raise AssertionError("the benchmark study has fewer than four tasks")


def _pick(tasks, method, label):
    return next(t for t in tasks if t["method"] == method and t["dataset"]["label"] == label)


CASES = [(m, d) for m in ("circle.kasa", "circle.gauss_newton") for d in ("full", "arc90")]


@pytest.mark.parametrize("method_id,label", CASES)
def test_row(benchmark, tasks, method_id, label):
    """A whole row (its data made once: the same task again finds them shared, as the next method's row does)."""
    task = _pick(tasks, method_id, label)
    benchmark.group = f"row {method_id} {label}"
    row = benchmark(rows.run_task, task)
    assert row["status"] == "ok" and row["method"] == method_id


@pytest.mark.parametrize("method_id,label", CASES)
def test_fit_alone(benchmark, tasks, method_id, label):
    """The fit the row times (``MethodSpec.unchecked``: validation and fit, no gate)."""
    task = _pick(tasks, method_id, label)
    points, _ = rows.task_data(task)
    benchmark.group = f"row {method_id} {label}"
    res = benchmark(methods.get(method_id).unchecked, points)
    assert res.converged


@pytest.mark.parametrize("method_id,label", CASES)
def test_gate_and_metrics(benchmark, tasks, method_id, label):
    """The result gate and the metrics of one result (the largest parts of the per-row overhead)."""
    task = _pick(tasks, method_id, label)
    points, truth = rows.task_data(task)
    res = methods.get(method_id).unchecked(points)
    benchmark.group = f"row {method_id} {label}"
    out = benchmark(lambda: (methods.check_result(res, points), metrics(res, truth)))
    assert out[0] is None and out[1]["residual_rms"] > 0


@pytest.mark.parametrize("label", ["full", "arc90"])
def test_data(benchmark, tasks, label):
    """One repetition's data from its seed stream (``rows.load_data``), shared by the methods of that repetition."""
    task = _pick(tasks, "circle.kasa", label)
    benchmark.group = f"data {label}"
    points, truth = benchmark(rows.load_data, task["dataset"], task["seed"], task["stream"])
    assert points.shape == (100, 2) and truth["radius"] == 1.0
