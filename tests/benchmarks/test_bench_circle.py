"""pytest-benchmark cases: every circle method at N = 3358 (a circular test of the circle/ellipse
paper) and N = 10^5, with scikit-image's CircleModel and the circle-fit package as baselines
measured in the same run.

Run:  python -m pytest tests/benchmarks --benchmark-enable --benchmark-group-by=param:n
(the default test run executes each case once, as a smoke test, with benchmarking disabled).
"""

import numpy as np
import pytest

import methods
from _baselines import circle_model
from datasets.synthetic import circle_points

SIZES = [3358, 100_000]
# the least-squares methods (the zone methods, kind "convex program", have test_bench_zone.py)
CIRCLE_IDS = [s.id for s in methods.list_methods("circle") if s.kind != "convex program"]


@pytest.fixture(scope="module", params=SIZES, ids=lambda n: f"n={n}")
def trace(request):
    """A circular test: 299 mm radius at machine coordinates (1200, 650) mm, 5 µm radial noise."""
    rng = np.random.default_rng(3358)
    return request.param, circle_points((1200.0, 650.0), 299.0, request.param, noise=0.005, rng=rng)


def _check(center, radius):
    assert np.abs(np.asarray(center) - (1200.0, 650.0)).max() < 1e-3 and abs(radius - 299.0) < 1e-3


@pytest.mark.parametrize("method_id", CIRCLE_IDS)
def test_fitbench(benchmark, trace, method_id):
    n, pts = trace
    benchmark.group = f"circle n={n}"
    benchmark.extra_info["n"] = n
    if method_id == "circle.nelder_mead" and n > 10_000:  # ~0.1 s a fit: a few rounds suffice
        res = benchmark.pedantic(methods.fit, args=(method_id, pts), rounds=5, iterations=1, warmup_rounds=1)
    else:
        res = benchmark(methods.fit, method_id, pts)
    assert res.converged, res.message
    _check(res.center, res.radius)


def test_baseline_skimage_circlemodel(benchmark, trace):
    fit = circle_model()
    n, pts = trace
    benchmark.group = f"circle n={n}"

    center, radius = benchmark(fit, pts)
    _check(center, radius)


@pytest.mark.parametrize("func", ["hyperLSQ", "least_squares_circle"])
def test_baseline_circle_fit(benchmark, trace, func):
    circle_fit = pytest.importorskip("circle_fit", reason="circle-fit is a test extra (pip install -e .[test])")
    n, pts = trace
    benchmark.group = f"circle n={n}"
    xc, yc, r, _ = benchmark(getattr(circle_fit, func), pts)
    _check((xc, yc), r)
