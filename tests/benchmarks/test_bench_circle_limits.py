"""Speed targets for the circle least-squares fits, measured against their baselines in the same run:
every closed-form fit <= 1.0x circle-fit's ``hyperLSQ`` and ``circle.gauss_newton`` <= 0.5x scikit-image's
``CircleModel`` at N = 3358, 10^5 and 10^6; peak memory of a fit <= 4x the input array (tracemalloc).

Run:  python -m pytest tests/benchmarks/test_bench_circle_limits.py --benchmark-enable -s \
          --benchmark-columns=median,iqr,rounds --benchmark-group-by=group
The ratio table (median / baseline median) and the peak memory are printed at the end of the module
(``-s``) and stored in each case's ``extra_info``. Without --benchmark-enable each case runs once (smoke).
"""
import tracemalloc

import numpy as np
import pytest

import methods
from _baselines import circle_model
from datasets.synthetic import circle_points

SIZES = [3358, 100_000, 1_000_000]
CLOSED_FORM = ["circle.kasa", "circle.pratt", "circle.taubin", "circle.hyper"]
TARGETS = {**{m: ("hyperLSQ", 1.0) for m in CLOSED_FORM}, "circle.gauss_newton": ("CircleModel", 0.5),
           "circle.levenberg_marquardt": ("CircleModel", None)}  # LM: information only (same kernel as GN)
MEDIANS: dict = {}
MEMORY: dict = {}


@pytest.fixture(scope="module", params=SIZES, ids=lambda n: f"n={n}")
def trace(request):
    """A circular test: 299 mm radius at machine coordinates (1200, 650) mm, 5 µm radial noise."""
    rng = np.random.default_rng(3358)
    return request.param, circle_points((1200.0, 650.0), 299.0, request.param, noise=0.005, rng=rng)


@pytest.fixture(scope="module", autouse=True)
def ratio_table():
    yield
    if not MEDIANS:
        return
    lines = ["", "circle speed limits (median ms; ratio = median / baseline median, same run):"]
    for (name, n), med in sorted(MEDIANS.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        base, limit = TARGETS.get(name, (None, None))
        target = f"target <= {limit}x" if limit is not None else "no target"
        ratio = f"{med / MEDIANS[(base, n)]:.2f}x {base} ({target})" if (base, n) in MEDIANS else ""
        mem = f"peak memory {MEMORY[(name, n)]:.2f}x input" if (name, n) in MEMORY else ""
        lines.append(f"  n={n:>8} {name:<22} {med * 1e3:9.3f} ms  {ratio}  {mem}")
    print("\n".join(lines))


def _record(benchmark, name, n):
    if benchmark.stats is not None and benchmark.enabled:
        MEDIANS[(name, n)] = benchmark.stats.stats.median


def _check(center, radius):
    assert np.abs(np.asarray(center) - (1200.0, 650.0)).max() < 1e-3 and abs(radius - 299.0) < 1e-3


@pytest.mark.parametrize("method_id", [*CLOSED_FORM, "circle.gauss_newton", "circle.levenberg_marquardt"])
def test_fitbench(benchmark, trace, method_id):
    n, pts = trace
    benchmark.group = f"circle limits n={n}"
    methods.fit(method_id, pts)
    tracemalloc.start()
    methods.fit(method_id, pts)
    peak = tracemalloc.get_traced_memory()[1] / pts.nbytes
    tracemalloc.stop()
    MEMORY[(method_id, n)] = peak
    benchmark.extra_info.update(n=n, peak_memory_x_input=round(peak, 2))
    res = benchmark(methods.fit, method_id, pts)
    _record(benchmark, method_id, n)
    assert res.converged, res.message
    _check(res.center, res.radius)


def test_baseline_hyperlsq(benchmark, trace):
    circle_fit = pytest.importorskip("circle_fit", reason="circle-fit is a test extra")
    n, pts = trace
    benchmark.group = f"circle limits n={n}"
    xc, yc, r, _ = benchmark(circle_fit.hyperLSQ, pts)
    _record(benchmark, "hyperLSQ", n)
    _check((xc, yc), r)


def test_baseline_circlemodel(benchmark, trace):
    fit = circle_model()
    n, pts = trace
    benchmark.group = f"circle limits n={n}"

    center, radius = benchmark(fit, pts)
    _record(benchmark, "CircleModel", n)
    _check(center, radius)
