"""Count the sweeps a circle fit makes over its input, measured, not
asserted: memory lines read, simulated by valgrind's cachegrind with a 1 MiB last-level cache (so the
16 MB input is read from memory at every sweep), in two runs that differ only by the fit.

Run (from the repository root, ~3 min):
    python tests/benchmarks/circle_passes.py circle.kasa
It prints (LL data-read misses with the fit - without) / (input bytes / 64) = sweeps over the input, and
LL write misses / (8 N / 64) = arrays of N numbers written (the residuals: 1).
"""
import os
import re
import subprocess
import sys
import tempfile

N = 1_000_000
SCRIPT = """
import numpy as np, methods
from datasets.synthetic import circle_points
P = circle_points((1200.0, 650.0), 299.0, {n}, noise=0.005, rng=np.random.default_rng(3358))
small = P[:100].copy()
methods.fit({method!r}, small)  # every import and first-call cost outside the difference
if {fit}:
    methods.fit({method!r}, P)
"""


def _misses(method: str, fit: bool) -> tuple[int, int]:
    with tempfile.TemporaryDirectory() as tmp:
        script = os.path.join(tmp, "run.py")
        with open(script, "w") as fh:
            fh.write(SCRIPT.format(n=N, method=method, fit=fit))
        out = os.path.join(tmp, "cg.out")
        env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": os.getcwd()}
        proc = subprocess.run(["valgrind", "--tool=cachegrind", "--cache-sim=yes", "--LL=1048576,16,64",
                               f"--cachegrind-out-file={out}", sys.executable, script],
                              capture_output=True, text=True, env=env, check=True)
        found = re.search(r"LLd misses:\s+([\d,]+)\s+\(\s*([\d,]+) rd\s+\+\s+([\d,]+) wr\)", proc.stderr)
        return int(found.group(2).replace(",", "")), int(found.group(3).replace(",", ""))


if __name__ == "__main__":
    method = sys.argv[1] if len(sys.argv) > 1 else "circle.kasa"
    with_fit, without = _misses(method, True), _misses(method, False)
    lines = 16 * N / 64
    print(f"{method} N={N} (FITBENCH_KERNELS={os.environ.get('FITBENCH_KERNELS', 'compiled')}): "
          f"LL read misses {with_fit[0] - without[0]:,} = {(with_fit[0] - without[0]) / lines:.2f} sweeps over the "
          f"input; LL write misses {with_fit[1] - without[1]:,} = {(with_fit[1] - without[1]) / (lines / 2):.2f} "
          f"arrays of N float64 written")
