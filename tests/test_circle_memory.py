"""Peak memory of a circle fit <= 4x the input array, at the benchmarks' N = 3358 and at N = 200 000.
tracemalloc counts NumPy's allocations exactly, so this is a deterministic test, not a timing; each fit runs in a
fresh interpreter (tracemalloc also counts what other threads of a long test session allocate), by the benchmark
script's :func:`measure` (``python tests/benchmarks/peak_memory.py N`` prints the table)."""
import pytest

from benchmarks.peak_memory import measure

CIRCLE_FITS = ["circle.kasa", "circle.pratt", "circle.taubin", "circle.hyper", "circle.gauss_newton",
               "circle.levenberg_marquardt", "circle.nelder_mead", "circle.powell_hybrid", "circle.minimum_zone",
               "circle.max_inscribed", "circle.min_circumscribed", "circle.chebyshev_lp"]


@pytest.mark.slow
@pytest.mark.parametrize("n", [3358, 200_000])
@pytest.mark.parametrize("method_id", CIRCLE_FITS)
def test_peak_memory_of_a_fit_is_at_most_four_times_the_input(method_id, n):
    ratio, converged, _ = measure(method_id, n)
    assert converged
    assert ratio <= 4.0, f"{method_id} at N = {n}: peak memory {ratio:.2f}x the input"
