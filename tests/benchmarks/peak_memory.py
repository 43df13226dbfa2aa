"""Peak memory of every circle and ellipse fit as a multiple of its input array,
measured, printed, not asserted here (tests/test_circle_memory.py and tests/test_ellipse_memory.py assert it with
:func:`measure_many`).

Run (from the repository root, ~30 s):
    python tests/benchmarks/peak_memory.py [N]        (default N = 100000)

The fits run in an interpreter of their own (tracemalloc also counts what other threads allocate, e.g. a test
session's), each once to import and warm up, then once under tracemalloc (started for that call, stopped after it):
the peak of all Python and NumPy allocations during that call, divided by the input's bytes (16 N). The circle fits
fit the 299 mm circle of the benchmarks with 5 um noise, the ellipse fits the paper's near-circular ellipse (tables
3-5); the Nelder-Mead fits start from the paper's s1S.
"""
import os
import subprocess
import sys

SCRIPT = """
import sys, time, tracemalloc
import numpy as np
import methods
from datasets.synthetic import circle_points, ellipse_points
for n, method_id in zip(map(int, sys.argv[1::2]), sys.argv[2::2]):
    if method_id.startswith("circle."):
        pts, kw = circle_points((1200.0, 650.0), 299.0, n, noise=0.005, rng=np.random.default_rng(3358)), {}
    else:
        pts = ellipse_points(n=n, noise=0.005, rng=np.random.default_rng(3358), center=(1200.0, 650.0),
                             semi_axes=(299.0243, 299.0022), angle=np.radians(32.04))
        kw = {"start": (299.0, 299.0, 0.0, 1200.0, 650.0), "step": (1e-3, 1e-3, 1e-2, 1e-3, 1e-3)} \\
            if method_id.endswith("_nm") else {}
    methods.fit(method_id, pts, **kw)
    tracemalloc.start()
    t = time.perf_counter()
    res = methods.fit(method_id, pts, **kw)
    seconds = time.perf_counter() - t
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    print(peak / pts.nbytes, res.converged, seconds, flush=True)
    del res
"""

FITS = ["circle.kasa", "circle.pratt", "circle.taubin", "circle.hyper", "circle.gauss_newton",
        "circle.levenberg_marquardt", "circle.nelder_mead", "circle.powell_hybrid", "circle.minimum_zone",
        "circle.max_inscribed", "circle.min_circumscribed", "circle.chebyshev_lp", "ellipse.halir_flusser",
        "ellipse.fitzgibbon", "ellipse.orthogonal", "ellipse.algebraic_nm", "ellipse.geometric_nm"]


def measure(method_id: str, n: int) -> tuple[float, bool, float]:
    """(peak / input, converged, seconds) of one fit of ``method_id`` to N = ``n`` points, in a fresh interpreter."""
    return measure_many([(method_id, n)])[0]


def measure_many(cases) -> list[tuple[float, bool, float]]:
    """:func:`measure` of each ``(method_id, n)`` of ``cases``, one after the other in one fresh interpreter (each fit
    traced alone; tests/test_circle_memory.py and tests/test_ellipse_memory.py: one interpreter start, not one a fit)."""
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = {**os.environ, "PYTHONPATH": root, "OPENBLAS_NUM_THREADS": "1"}
    args = [str(a) for method_id, n in cases for a in (n, method_id)]
    out = subprocess.run([sys.executable, "-c", SCRIPT, *args], cwd=root, env=env, capture_output=True, text=True,
                         timeout=900)
    lines = out.stdout.splitlines()
    if out.returncode != 0:
        method_id, n = cases[len(lines)]
        raise RuntimeError(f"{method_id} at N = {n} failed: {out.stderr.strip().splitlines()[-1]}")
    return [(float(ratio), converged == "True", float(seconds))
            for ratio, converged, seconds in (line.split() for line in lines)]


def main(n: int) -> int:
    print(f"peak memory of one fit / input array (16 N bytes), N = {n}")
    print(f"{'fit':28s} {'peak / input':>12s}  {'<= 4x':>5s}  {'converged':>9s}  {'time under tracemalloc':>22s}")
    worst = 0.0
    for method_id in FITS:
        try:
            ratio, converged, seconds = measure(method_id, n)
        except RuntimeError as exc:
            print(f"{method_id:28s} {exc}")
            continue
        worst = max(worst, ratio)
        print(f"{method_id:28s} {ratio:11.2f}x  {'yes' if ratio <= 4 else 'NO':>5s}  {str(converged):>9s}  "
              f"{seconds * 1e3:19.1f} ms")
    print(f"largest: {worst:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main(int(sys.argv[1]) if len(sys.argv) > 1 else 100_000))
