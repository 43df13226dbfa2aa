"""Issue 20: peak memory of a circle fit <= 4x the input array (tracemalloc counts NumPy's allocations
exactly, so this is a deterministic test, not a timing)."""
import tracemalloc

import numpy as np
import pytest

import methods
from datasets.synthetic import circle_points


@pytest.mark.parametrize("method_id", ["circle.kasa", "circle.pratt", "circle.taubin", "circle.hyper",
                                       "circle.gauss_newton", "circle.levenberg_marquardt", "circle.nelder_mead",
                                       "circle.powell_hybrid", "circle.minimum_zone", "circle.max_inscribed",
                                       "circle.min_circumscribed", "circle.chebyshev_lp"])
def test_peak_memory_of_a_fit_is_at_most_four_times_the_input(method_id):
    pts = circle_points((1200.0, 650.0), 299.0, 200_000, noise=0.005, rng=np.random.default_rng(3358))
    methods.fit(method_id, pts)  # imports and caches outside the measurement
    tracemalloc.start()
    try:
        res = methods.fit(method_id, pts)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert res.converged
    assert peak <= 4.0 * pts.nbytes + 64_000, f"{method_id}: peak {peak / pts.nbytes:.2f}x the input"
