"""pytest-benchmark cases for the ellipse family at N = 3358 (a circular test of the circle/ellipse
paper) and N = 10^5, with scikit-image's EllipseModel (a direct fit) as the baseline in the same run.

Run:  python -m pytest tests/benchmarks/test_bench_ellipse.py --benchmark-enable --benchmark-group-by=group
"""
import warnings

import numpy as np
import pytest

import methods
from datasets.synthetic import ellipse_points

SIZES = [3358, 100_000]
FAST = ["ellipse.fitzgibbon", "ellipse.halir_flusser", "ellipse.orthogonal"]
PAPER = dict(center=(1200.0, 650.0), semi_axes=(299.0243, 299.0022), angle=np.radians(32.04))


@pytest.fixture(scope="module", params=SIZES, ids=lambda n: f"n={n}")
def trace(request):
    """The paper's near-circle ellipse (tables 3-5) with 5 um noise."""
    return request.param, ellipse_points(n=request.param, noise=0.005, rng=np.random.default_rng(3358), **PAPER)


def _check(center, axes):
    assert np.abs(np.asarray(center) - PAPER["center"]).max() < 1e-3
    assert np.abs(np.sort(axes)[::-1] - PAPER["semi_axes"]).max() < 1e-3


@pytest.mark.parametrize("method_id", FAST)
def test_fitbench(benchmark, trace, method_id):
    n, pts = trace
    benchmark.group = f"ellipse n={n}"
    res = benchmark(methods.fit, method_id, pts)
    assert res.converged, res.message
    _check(res.center, res.semi_axes)


@pytest.mark.parametrize("method_id", ["ellipse.algebraic_nm", "ellipse.geometric_nm"])
def test_fitbench_nelder_mead(benchmark, method_id):
    """Nelder–Mead only at N = 3358, from the paper's start (table 3), a few rounds."""
    pts = ellipse_points(n=3358, noise=0.005, rng=np.random.default_rng(3358), **PAPER)
    benchmark.group = "ellipse n=3358"
    res = benchmark.pedantic(methods.fit, args=(method_id, pts),
                             kwargs={"start": (299.0, 299.0, 0.0, 1200.0, 650.0), "step": (1e-3, 1e-3, 1e-2, 1e-3, 1e-3)},
                             rounds=3, iterations=1)
    assert res.converged, res.message
    _check(res.center, res.semi_axes)


def test_baseline_skimage_ellipsemodel(benchmark, trace):
    measure = pytest.importorskip("skimage.measure", reason="scikit-image is a test extra (pip install -e .[test])")
    n, pts = trace
    benchmark.group = f"ellipse n={n}"

    def fit():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)
            if hasattr(measure.EllipseModel, "from_estimate"):
                m = measure.EllipseModel.from_estimate(pts)
                return m.center, m.axis_lengths
            m = measure.EllipseModel()
            m.estimate(pts)
            return m.params[:2], m.params[2:4]

    center, axes = benchmark(fit)
    _check(center, axes)


def test_baseline_skimage_ellipsemodel_with_residuals(benchmark):
    """What a user needs for a form error with scikit-image: the fit plus its residuals (orthogonal
    distances, solved point by point there). N = 3358 only (about 0.1 s a call)."""
    measure = pytest.importorskip("skimage.measure", reason="scikit-image is a test extra (pip install -e .[test])")
    pts = ellipse_points(n=3358, noise=0.005, rng=np.random.default_rng(3358), **PAPER)
    benchmark.group = "ellipse n=3358"

    def fit_and_residuals():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)
            if hasattr(measure.EllipseModel, "from_estimate"):
                m = measure.EllipseModel.from_estimate(pts)
            else:
                m = measure.EllipseModel()
                m.estimate(pts)
            return m.residuals(pts)

    r = benchmark.pedantic(fit_and_residuals, rounds=5, iterations=1)
    assert r.shape == (3358,) and np.abs(r).max() < 0.05


_PEAK_SCRIPT = """
import sys, tracemalloc
import numpy as np
import methods
from datasets.synthetic import ellipse_points
n, method_id = int(sys.argv[1]), sys.argv[2]
pts = ellipse_points(n=n, noise=0.005, rng=np.random.default_rng(3358), center=(1200.0, 650.0),
                     semi_axes=(299.0243, 299.0022), angle=np.radians(32.04))
methods.fit(method_id, pts)
tracemalloc.start()
methods.fit(method_id, pts)
print(tracemalloc.get_traced_memory()[1] / pts.nbytes)
"""


@pytest.mark.parametrize("method_id", FAST)
def test_peak_memory(benchmark, trace, method_id):
    """Peak memory of one fit (tracemalloc: every NumPy allocation) as a multiple of the input array, in
    the benchmark output (extra_info). Measured in a fresh interpreter: tracemalloc also counts what other
    threads allocate, and a long test session leaves some running. Measured at N = 10^5: 1.50x for the direct
    fits (the compiled kernel writes the orthogonal residuals without temporaries; 4.00x with the NumPy path's
    blocks), 2.52x for ellipse.orthogonal (the unit frame, the distances of its last two evaluations; its Jacobian
    is folded into a 6 x 6 R as the sweep goes); at N = 3358 1.58x and 3.41x."""
    import os
    import subprocess
    import sys
    from conftest import REPO

    n, pts = trace
    benchmark.group = f"ellipse peak memory n={n}"
    env = {**os.environ, "PYTHONPATH": str(REPO), "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", _PEAK_SCRIPT, str(n), method_id], cwd=REPO, env=env,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    ratio = float(out.stdout.strip().splitlines()[-1])
    benchmark.extra_info["peak_memory_over_input"] = round(ratio, 2)
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)
    # the target: <= 4x the input
    assert ratio <= 4.0, f"{method_id}: peak memory {ratio:.2f}x the input"
