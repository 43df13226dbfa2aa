"""Peak memory of an ellipse fit <= 4x the input array. tracemalloc counts NumPy's allocations exactly,
so this is a deterministic test, not a timing; the fits run in an interpreter of their own, each traced alone, since
tracemalloc also counts what other threads of a long test session allocate (the benchmark script's
:func:`measure_many`; the Nelder–Mead fits start from the paper's s1S, table 3)."""
import pytest

from benchmarks.peak_memory import measure_many

#: (method, N): every ellipse fit at N = 10^5; the direct and orthogonal fits also at N = 3358 (the Nelder–Mead fits
#: keep one objective value per evaluation, hundreds of them, which is not data-sized memory)
CASES = [(m, n) for m in ("ellipse.orthogonal", "ellipse.halir_flusser", "ellipse.fitzgibbon") for n in (3358, 100_000)] + \
    [("ellipse.algebraic_nm", 100_000), ("ellipse.geometric_nm", 100_000)]


@pytest.mark.slow
def test_peak_memory_of_an_ellipse_fit_is_at_most_four_times_the_input():
    """Every fit of :data:`CASES`, one interpreter for all (one start, not 8)."""
    measured = measure_many(CASES)
    assert len(measured) == len(CASES)
    failed = [f"{method_id} at N = {n}: peak memory {ratio:.2f}x the input, converged {converged}"
              for (method_id, n), (ratio, converged, _) in zip(CASES, measured) if not (converged and ratio <= 4.0)]
    assert not failed, failed
