"""pytest-benchmark cases for the ISO 230-4 diagnostics (methods.circular_test.diagnose): a CW and a CCW run of
R 150 mm with squareness, scale mismatch, backlash and noise, at 3600 and 100,000 points per run.

Run:  python -m pytest tests/benchmarks/test_bench_circular_test.py --benchmark-enable
(the default test run executes the small case once, as a smoke test, with benchmarking disabled; the 100,000-point
case is slow: ~10 s a diagnosis, the exact model's Gauss-Newton fit of 200,000 residuals).
"""
import numpy as np
import pytest

from methods.circular_test import diagnose

R = 150.0


def _runs(n, seed=230):
    """(cw, ccw) in mm about the centre (0, 0): r = R + squareness 10 urad, scale mismatch 5 um/m, backlash
    2 um on X, 0.5 um noise."""
    rng = np.random.default_rng(seed)
    t = 2 * np.pi * np.arange(n) / n
    runs = []
    for d in (-1.0, 1.0):
        dev = (10e-6 * R * np.sin(t) * np.cos(t) + 0.5 * 5e-6 * R * np.cos(2 * t)
               + 0.5 * d * 2e-3 * np.sign(np.sin(t)) * np.cos(t) + 0.5e-3 * rng.standard_normal(n))
        ang = t if d > 0 else -t
        runs.append(np.column_stack([(R + dev) * np.cos(ang), (R + dev) * np.sin(ang)]))
    return runs


@pytest.mark.parametrize("n", [3600, pytest.param(100_000, marks=pytest.mark.slow)])
def test_diagnose(benchmark, n):
    cw, ccw = _runs(n)
    benchmark.group = "circular-test diagnostics"
    benchmark.extra_info["points_per_run"] = n
    out = benchmark.pedantic(diagnose, args=(cw, ccw, R, (0.0, 0.0)), rounds=3 if n > 10_000 else 10, iterations=1)
    assert out["squareness"]["value"] is not None and abs(out["squareness"]["value"]) < 100   # sane (urad)
