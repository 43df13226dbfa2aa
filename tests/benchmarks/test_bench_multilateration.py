"""pytest-benchmark cases for multilateration: every scheme on a simulated MCV 754 campaign (6 stations,
a 10 x 8 x 8 grid x 3 tool offsets = 1920 points, 11,520 lengths), and the baseline a user would write
first: scipy's trust-region-reflective ``least_squares`` called once per station and once per point
(the paper's Case A, eq. 7), measured in the same run.

Run:  python -m pytest tests/benchmarks/test_bench_multilateration.py --benchmark-enable
"""
import numpy as np
import pytest
from scipy.optimize import least_squares

import methods
from datasets.multilateration import simulate

IDS = [s.id for s in methods.list_methods("multilateration")]


@pytest.fixture(scope="module")
def campaign():
    return simulate(stations=6, grid=(10, 8, 8), noise=1.0, rng=np.random.default_rng(754))


def _check(points, truth):
    assert np.sqrt(np.mean(np.sum((points - truth["actual"]) ** 2, axis=1))) < 0.1   # sane (< 0.1 mm)


@pytest.mark.parametrize("method_id", IDS)
def test_fitbench(benchmark, campaign, method_id):
    data, truth = campaign
    benchmark.group = "multilateration n=1920 points, 6 stations"
    res = benchmark(methods.fit, method_id, data)
    _check(res.points, truth)


def scipy_case_a(data):
    """Case A (eq. 7) with one scipy least_squares call per station and per point."""
    P = data.lengths
    stations = []
    for k in range(P.shape[1]):
        x0 = np.r_[data.points.mean(axis=0) + 500.0, 0.0]
        r = least_squares(lambda th: np.linalg.norm(data.points - th[:3], axis=1) - (th[3] + P[:, k]), x0,
                          method="trf")
        stations.append(r.x)
    S = np.array(stations)
    pts = np.array([least_squares(lambda x, i=i: np.linalg.norm(x - S[:, :3], axis=1) - (S[:, 3] + P[i]),
                                  data.points[i], method="trf").x for i in range(P.shape[0])])
    return pts


def test_scipy_per_point_baseline(benchmark, campaign):
    data, truth = campaign
    benchmark.group = "multilateration n=1920 points, 6 stations"
    pts = benchmark.pedantic(scipy_case_a, args=(data,), rounds=3, iterations=1)
    _check(pts, truth)
    ours = methods.fit("multilateration.case_a_distance", data).points
    assert np.abs(pts - ours).max() < 1e-4      # the same estimator (scipy's default tolerances are looser)
