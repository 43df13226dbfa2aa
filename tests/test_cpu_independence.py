"""Reproduction on another CPU: the quick studies give the same statuses and counts, and values within
the tolerances declared in experiments/metrics.py, whichever BLAS kernel and SIMD instruction set the machine has.

Two runs stand for two machines: an AVX2 machine (OpenBLAS's Haswell kernels, NumPy's loops limited to AVX2 + FMA)
and this CPU's NumPy loops with OpenBLAS's Sandybridge kernels (AVX, no FMA). (x86-64 CPUs without FMA, older than
2013-2015, are not simulated: NumPy's sin/cos round differently there, so synthetic data differ in their last bits.) Before the fitters' sums left BLAS (methods._frame.dot) and the 3x3
solves left LAPACK (methods.circle._frame.solve3), Nelder–Mead's iteration counts, minimum-zone evaluation
counts and Gauss–Newton starts differed between these two runs, as they did between an Intel and an AMD machine."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pytest

from conftest import MACHINES, REPO, quick_run_on, run_python, subprocess_env


def _cpu_flags() -> set[str]:
    try:
        with open("/proc/cpuinfo") as f:
            return next((set(line.split(":", 1)[1].split()) for line in f if line.startswith("flags")), set())
    except OSError:
        return set()


#: ``python -m experiments.run ARGS`` without the analysis of the rows (no table nor figure; results.csv and meta.json
#: as a whole run writes them)
ROWS_ONLY = """
import runpy, sys
from experiments import analysis
from experiments.study import Analysis
analysis.analyse = lambda study, df, cfg, target, log: ({}, Analysis())
sys.argv = ["experiments.run", *sys.argv[1:]]
runpy.run_module("experiments.run", run_name="__main__", alter_sys=True)
"""


@pytest.mark.system
@pytest.mark.skipif(not {"avx2", "fma"} <= _cpu_flags(),
                    reason="the two simulated machines need a CPU with AVX2 and FMA (OpenBLAS's Haswell kernels)")
def test_quick_studies_agree_across_blas_kernels_and_simd_levels(tmp_path, tmp_path_factory):
    """The AVX2 machine's run is the session's (conftest.quick_run_on; tests/test_verify.py reads its report too):
    copied, since the verdict is written into it. The other machine's run starts first and runs beside it (each
    leaves a core idle at times: its start-up, its last rows, the report; alone on two cores, one after the other
    took 69 s of wall for 45 s of CPU). Verify compares the rows (results.csv, with meta.json): the other machine's run
    is ``python -m experiments.run`` with the analysis step (tables and figures, which the AVX2 run draws) left out,
    :data:`ROWS_ONLY` (23 -> 13 s of CPU; its rows identical to a whole run's, checked)."""
    other = tmp_path / "other_blas" / "results"
    proc = subprocess.Popen([sys.executable, "-c", ROWS_ONLY, "--quick", "--out", str(other), "--jobs", "2",
                             "--no-report"],
                            cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=subprocess_env(OPENBLAS_NUM_THREADS="1", **MACHINES["other_blas"]))
    try:
        avx2 = tmp_path / "avx2_fma" / "results"
        shutil.copytree(quick_run_on(tmp_path_factory, "avx2_fma"), avx2)
        _, err = proc.communicate(timeout=900)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err[-2000:]
    proc = run_python("-m", "experiments.verify", "--quick", "--against", other, "--results", avx2, "--write-verdict")
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]
    verdict = json.loads((avx2 / "verify.json").read_text())
    assert verdict["agree"] and len(verdict["studies"]) >= 10
