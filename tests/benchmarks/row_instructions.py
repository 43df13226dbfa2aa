"""What one row of the engine costs beyond its fit and its data, in instructions (valgrind callgrind): independent
of the load of a shared machine, where CPU times of a few microseconds move by tens of percent.

Runs 2000 rows of the engine's benchmark study (``engine_40k.toml``: 100-point circles, full and a 90° arc;
circle.kasa and circle.gauss_newton) in four fresh interpreters under callgrind, each doing the same start-up
and warm-up (100 rows) and then one of: nothing, the rows (``experiments.rows.run_task``), the fits alone on the
same data (``MethodSpec.unchecked``, after making the data), the data alone (``rows.load_data``, once per
repetition: its methods share it). Prints instructions per row of the fits, per repetition of the data and per
row of everything else (rows - fits: the gate, the metrics, the row's columns). docs/speed.md lists the figures.

Run from the repository root (about 4 minutes):  python tests/benchmarks/row_instructions.py
"""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ROWS = 2000

CHILD = """
import sys
sys.path.insert(0, {root!r})
from experiments import chunkrows, config as configs, rows
from experiments.studies import study_of
import methods
cfg = configs.load({study!r})
tasks = []
for t in study_of(cfg["kind"]).prepared_tasks(cfg):
    tasks.append(t)
    if len(tasks) == {n} + 100:
        break
chunkrows.run_chunk(tasks[:100])
work = tasks[100:]
mode = sys.argv[1]
if mode == "rows":
    for t in work:
        rows.run_task(t)
elif mode in ("fits", "data"):
    data = [rows.load_data(t["dataset"], t["seed"], t["stream"])[0] for t in work[::2]]
    if mode == "fits":
        specs = [methods.get(t["method"]).unchecked for t in work]
        for i, s in enumerate(specs):
            s(data[i // 2])
"""


def instructions(mode: str) -> int:
    code = CHILD.format(root=str(ROOT), study=str(ROOT / "tests" / "benchmarks" / "engine_40k.toml"), n=ROWS)
    env = {**os.environ, "PYTHONHASHSEED": "0", "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable, "-c", code,
                          mode], capture_output=True, text=True, env=env, cwd=ROOT)
    found = re.search(r"I\s+refs:\s+([\d,]+)", out.stderr)
    if out.returncode or not found:
        sys.exit(f"row_instructions: valgrind failed for {mode!r}: {out.stderr.strip()[-400:]}")
    return int(found.group(1).replace(",", ""))


def main() -> None:
    instructions("none")  # warm-up: a first run after a code change also parses the changed modules for the cache keys
    counts = {mode: instructions(mode) for mode in ("none", "rows", "fits", "data")}
    fits = (counts["fits"] - counts["data"]) / ROWS
    data = (counts["data"] - counts["none"]) / (ROWS // 2)
    overhead = (counts["rows"] - counts["fits"]) / ROWS
    print(f"{ROWS} rows of engine_40k.toml, instructions (valgrind callgrind):")
    print(f"  fit (MethodSpec.unchecked)          {fits / 1e3:8.1f} k per row")
    print(f"  data (rows.load_data)               {data / 1e3:8.1f} k per repetition ({data / 2e3:.1f} k per row)")
    print(f"  rest of the row (run_task - fits)   {overhead / 1e3:8.1f} k per row")


if __name__ == "__main__":
    main()
