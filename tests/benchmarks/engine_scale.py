"""The engine at scale: wall time and peak memory of ``experiments.run`` on the 40,000-row benchmark study
(``engine_40k.toml``: 2 generated circles x circle.kasa, circle.gauss_newton x 10,000 repetitions) against
the same fits in one Python loop, ``--jobs 1`` against ``--jobs 2``, a re-run with every row cached, and the
peak memory at 40,000 and 160,000 rows (``engine_160k.toml``), and the same study with 400 rows (what a run costs
besides its rows: the other 39,600 rows cost the difference, against their fits alone). Measured, printed, not asserted (speed targets
live here, not in the tests; docs/engine.md lists the figures).

Run from the repository root (about 2 minutes on 2 cores):
    python tests/benchmarks/engine_scale.py [--skip-160k] [--dask] [--repeat N]

The fits alone, the start-up, ``--jobs 1``, ``--jobs 2`` and the re-run are measured in ``--repeat`` (3) interleaved
rounds; the medians and each round's ratios are printed (one round's figures move by 0.1-0.2 s on a shared machine).

Each run is a fresh interpreter (``python -m experiments.run STUDY --out TMP``); its peak memory is the
largest resident set of the run and its workers (``os.wait4``'s ``ru_maxrss``). The project's modules are compiled to
bytecode first (as an installed package has them; PYTHONDONTWRITEBYTECODE is dropped from the runs' environment).
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
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
    out = subprocess.run([sys.executable, "-c", probe, *map(str, cmd)], cwd=ROOT, env=env, capture_output=True, check=False,
                         text=True)
    wall, peak, rc, cpu = out.stdout.split()
    if rc != "0":
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed (exit {rc}): {out.stderr.strip()}")
    return float(wall), float(peak), float(cpu)


def _median(values):
    return statistics.median(values)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-160k", action="store_true")
    ap.add_argument("--dask", action="store_true", help="also the Dask LocalCluster with 2 workers")
    ap.add_argument("--repeat", type=int, default=3, help="rounds of the fits, start-up, --jobs 1, --jobs 2 and "
                                                           "re-run measurements, interleaved; medians are quoted")
    args = ap.parse_args(argv)
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    # the project's modules as an installed package has them, compiled to bytecode once (else every process of the
    # benchmark, the start-up's included, compiles them again: 0.2-0.3 s each under PYTHONDONTWRITEBYTECODE)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    subprocess.run([sys.executable, "-m", "compileall", "-q", *(str(ROOT / p) for p in PACKAGES)], cwd=ROOT, env=env,
                   check=True)
    study = HERE / "engine_40k.toml"
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start; "
          f"{args.repeat} interleaved rounds, medians quoted (each round's value in brackets)")
    m = {k: [] for k in ("fits", "fits_cpu", "gen", "start", "j1", "j2", "again", "small")}
    peaks = {1: [], 2: []}
    cpus = {1: [], 2: [], "again": []}
    run = [sys.executable, "-m", "experiments.run", study] + NO_REPORT
    with tempfile.TemporaryDirectory() as tmp:
        # the same study with 100 repetitions (400 rows): what a run costs besides its rows (imports, tasks, the
        # figure, the outputs), so that the cost of the other 39,600 rows is the difference of the two runs
        small = Path(tmp) / "engine_400.toml"
        small.write_text(study.read_text(encoding="utf-8").replace("repetitions = 10000", "repetitions = 100")
                         .replace('name = "engine_40k"', 'name = "engine_400"'), encoding="utf-8")
        for r in range(args.repeat):
            out = subprocess.run([sys.executable, "-c", FITS_ALONE, str(study)], cwd=ROOT, env=env,
                                 capture_output=True, text=True, check=True).stdout.split()
            m["fits"].append(float(out[0]))
            m["gen"].append(float(out[1]))
            m["fits_cpu"].append(float(out[2]))
            m["start"].append(run_peak([sys.executable, "-c", "import experiments.run, methods.circle"], env)[0])
            m["small"].append(run_peak([sys.executable, "-m", "experiments.run", small, *NO_REPORT, "--jobs", 1,
                                        "--out", Path(tmp) / f"small-{r}"], env)[0])
            for jobs in (1, 2):
                wall, peak, cpu = run_peak(run + ["--jobs", jobs, "--out", Path(tmp) / f"j{jobs}-{r}"], env)
                m[f"j{jobs}"].append(wall)
                peaks[jobs].append(peak)
                cpus[jobs].append(cpu)
            wall, _, cpu = run_peak(run + ["--jobs", 2, "--out", Path(tmp) / f"j2-{r}"], env)
            m["again"].append(wall)
            cpus["again"].append(cpu)
        med = {k: _median(v) for k, v in m.items()}
        each = {k: " ".join(f"{x:.2f}" for x in v) for k, v in m.items()}
        print(f"fits alone (40,000 fits, data made beforehand): {med['fits']:.2f} s wall [{each['fits']}], "
              f"{_median(m['fits_cpu']):.2f} s CPU; making the data: {med['gen']:.2f} s; "
              f"start-up (imports): {med['start']:.2f} s [{each['start']}]")
        for jobs in (1, 2):
            print(f"--jobs {jobs}: {med[f'j{jobs}']:.2f} s wall [{each[f'j{jobs}']}], {_median(cpus[jobs]):.2f} s CPU, "
                  f"peak {_median(peaks[jobs]):.0f} MB")
        again = [a / b for a, b in zip(m["again"], m["j2"])]
        print(f"re-run, every row cached (--jobs 2): {med['again']:.2f} s = {_median(again):.0%} of the first run "
              f"[{' '.join(f'{x:.0%}' for x in again)}] ({_median(cpus['again']):.2f} s CPU)")
        if args.dask:
            d = run_peak(run + ["--jobs", 2, "--executor", "dask", "--out", Path(tmp) / "dask"], env)
            print(f"--executor dask (LocalCluster, 2 workers): {d[0]:.2f} s wall, {d[2]:.2f} s CPU, peak {d[1]:.0f} MB")
        r1 = [j / (f + s) for j, f, s in zip(m["j1"], m["fits"], m["start"])]
        r2 = [b / a for a, b in zip(m["j1"], m["j2"])]
        print(f"ratios (medians; each round's in brackets): --jobs 1 / (fits + start-up) = {_median(r1):.2f} "
              f"[{' '.join(f'{x:.2f}' for x in r1)}]; --jobs 2 / --jobs 1 = {_median(r2):.2f} "
              f"[{' '.join(f'{x:.2f}' for x in r2)}]")
        per_row = [(j - w) / (f * 0.99) for j, w, f in zip(m["j1"], m["small"], m["fits"])]
        print(f"the same study with 400 rows, --jobs 1: {med['small']:.2f} s [{each['small']}]; the other 39,600 rows "
              f"cost --jobs 1 (40,000 - 400 rows) / their fits alone = {_median(per_row):.2f} "
              f"[{' '.join(f'{x:.2f}' for x in per_row)}] (the engine's cost a row against the fit's)")
        if not args.skip_160k:
            big = run_peak([sys.executable, "-m", "experiments.run", HERE / "engine_160k.toml", *NO_REPORT,
                            "--jobs", 2, "--out", Path(tmp) / "big"], env)
            print(f"160,000 rows (--jobs 2): {big[0]:.2f} s wall, {big[2]:.2f} s CPU, peak {big[1]:.0f} MB = "
                  f"{big[1] / _median(peaks[2]):.2f} x the 40,000-row peak")
    print(f"load average {os.getloadavg()[0]:.1f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
