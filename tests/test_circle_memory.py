"""Peak memory of a circle fit <= 4x the input array, at the benchmarks' N = 3358 and at N = 200 000.
tracemalloc counts NumPy's allocations exactly, so this is a deterministic test, not a timing; the fits run in an
interpreter of their own, each traced alone (tracemalloc also counts what other threads of a long test session
allocate), by the benchmark script's :func:`measure_many` (``python tests/benchmarks/peak_memory.py N`` prints the
table)."""
import pytest

from benchmarks.peak_memory import measure_many

CIRCLE_FITS = ["circle.kasa", "circle.pratt", "circle.taubin", "circle.hyper", "circle.gauss_newton",
               "circle.levenberg_marquardt", "circle.nelder_mead", "circle.powell_hybrid", "circle.minimum_zone",
               "circle.max_inscribed", "circle.min_circumscribed", "circle.chebyshev_lp"]
CASES = [(method_id, n) for method_id in CIRCLE_FITS for n in (3358, 200_000)]


@pytest.mark.slow
def test_peak_memory_of_a_fit_is_at_most_four_times_the_input():
    """Every fit of :data:`CASES`, one interpreter for all (one start, not 24)."""
    measured = measure_many(CASES)
    assert len(measured) == len(CASES)
    failed = [f"{method_id} at N = {n}: peak memory {ratio:.2f}x the input, converged {converged}"
              for (method_id, n), (ratio, converged, _) in zip(CASES, measured) if not (converged and ratio <= 4.0)]
    assert not failed, failed
