"""The engine at scale: wall time and peak memory of ``experiments.run`` on the 40,000-row benchmark study
(``engine_40k.toml``: 2 generated circles x circle.kasa, circle.gauss_newton x 10,000 repetitions) against
the same fits in one Python loop, ``--jobs 1`` against ``--jobs 2``, a re-run with every row cached, and the
peak memory at 40,000 and 160,000 rows (``engine_160k.toml``). Measured, printed, not asserted (speed targets
live here, not in the tests; docs/engine.md lists the figures).

Run from the repository root (about 2 minutes on 2 cores):
    python tests/benchmarks/engine_scale.py [--skip-160k] [--dask]

Each run is a fresh interpreter (``python -m experiments.run STUDY --out TMP``); its peak memory is the
largest resident set of the run and its workers (``os.wait4``'s ``ru_maxrss``). The project's modules are compiled to
bytecode first (as an installed package has them; PYTHONDONTWRITEBYTECODE is dropped from the runs' environment).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
NO_REPORT = [] if os.environ.get("ENGINE_BENCH_OLD") else ["--no-report"]
PACKAGES = ("experiments", "methods", "datasets", "fitbench")  # the project's own code

FITS_ALONE = """
import time, tomllib, sys
import numpy as np
import methods
from datasets import sources
cfg = tomllib.load(open(sys.argv[1], "rb"))
src = sources.get_source("circle")
data = []
t0 = time.perf_counter()
for i, d in enumerate(cfg["datasets"]):
    for r in range(cfg["repetitions"]):
        rng = np.random.default_rng(np.random.SeedSequence(cfg["seed"], spawn_key=(i, 0, r)))
        data.append(src.load(rng, **d["params"])[0])
gen = time.perf_counter() - t0
ids = [methods.get(m["id"]).unchecked for m in cfg["methods"]]  # the fits without the result gate
for m in ids:
    m(data[0])
t0, c0 = time.perf_counter(), time.process_time()
for pts in data:
    for m in ids:
        m(pts)
print(f"{time.perf_counter() - t0:.3f} {gen:.3f} {time.process_time() - c0:.3f}")
"""


def run_peak(cmd: list, env) -> tuple[float, float, float]:
    """Wall time, peak RSS (MB) and CPU seconds (user + system) of the command and its descendants, measured
    in a helper process so that each measurement has its own RUSAGE_CHILDREN."""
    probe = ("import os, resource, subprocess, sys, time; t = time.perf_counter(); "
             "p = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
             "w = time.perf_counter() - t; "
             "sys.stderr.write(p.stderr[-800:] if p.returncode else ''); "
             "u = resource.getrusage(resource.RUSAGE_CHILDREN); "
             "print(f'{w:.3f} {u.ru_maxrss / 1024:.1f} {p.returncode} {u.ru_utime + u.ru_stime:.3f}')")
    out = subprocess.run([sys.executable, "-c", probe, *map(str, cmd)], cwd=ROOT, env=env, capture_output=True,
                         text=True)
    wall, peak, rc, cpu = out.stdout.split()
    if rc != "0":
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed (exit {rc}): {out.stderr.strip()}")
    return float(wall), float(peak), float(cpu)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-160k", action="store_true")
    ap.add_argument("--dask", action="store_true", help="also the Dask LocalCluster with 2 workers")
    args = ap.parse_args(argv)
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    # the project's modules as an installed package has them, compiled to bytecode once (else every process of the
    # benchmark, the start-up's included, compiles them again: 0.2-0.3 s each under PYTHONDONTWRITEBYTECODE)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    subprocess.run([sys.executable, "-m", "compileall", "-q", *(str(ROOT / p) for p in PACKAGES)], cwd=ROOT, env=env,
                   check=True)
    study = HERE / "engine_40k.toml"
    out = subprocess.run([sys.executable, "-c", FITS_ALONE, str(study)], cwd=ROOT, env=env, capture_output=True,
                         text=True, check=True).stdout.split()
    fits, gen, fits_cpu = float(out[0]), float(out[1]), float(out[2])
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start")
    start, _, start_cpu = run_peak([sys.executable, "-c", "import experiments.run, methods.circle"], env)
    print(f"fits alone (40,000 fits, data made beforehand): {fits:.2f} s wall, {fits_cpu:.2f} s CPU; "
          f"making the data: {gen:.2f} s; "
          f"start-up (imports): {start:.2f} s wall, {start_cpu:.2f} s CPU")
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        run = [sys.executable, "-m", "experiments.run", study] + NO_REPORT
        for jobs in (1, 2):
            o = Path(tmp) / f"j{jobs}"
            rows[jobs] = run_peak(run + ["--jobs", jobs, "--out", o], env)
            print(f"--jobs {jobs}: {rows[jobs][0]:.2f} s wall, {rows[jobs][2]:.2f} s CPU, peak {rows[jobs][1]:.0f} MB")
        again = run_peak(run + ["--jobs", 2, "--out", Path(tmp) / "j2"], env)
        print(f"re-run, every row cached (--jobs 2): {again[0]:.2f} s = {again[0] / rows[2][0]:.0%} of the first run "
              f"({again[2]:.2f} s CPU)")
        if args.dask:
            d = run_peak(run + ["--jobs", 2, "--executor", "dask", "--out", Path(tmp) / "dask"], env)
            print(f"--executor dask (LocalCluster, 2 workers): {d[0]:.2f} s wall, {d[2]:.2f} s CPU, peak {d[1]:.0f} MB")
        print(f"ratios: --jobs 1 / (fits + start-up) = {rows[1][0] / (fits + start):.2f}; "
              f"--jobs 2 / --jobs 1 = {rows[2][0] / rows[1][0]:.2f}")
        if not args.skip_160k:
            big = run_peak([sys.executable, "-m", "experiments.run", HERE / "engine_160k.toml", *NO_REPORT,
                            "--jobs", 2, "--out", Path(tmp) / "big"], env)
            print(f"160,000 rows (--jobs 2): {big[0]:.2f} s wall, {big[2]:.2f} s CPU, peak {big[1]:.0f} MB = "
                  f"{big[1] / rows[2][1]:.2f} x the 40,000-row peak")
    print(f"load average {os.getloadavg()[0]:.1f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
