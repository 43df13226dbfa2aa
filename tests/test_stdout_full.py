"""Standard output that cannot be written (``> /dev/full``: a full disk, an I/O error) is not a reader that went
(``| head -1``, which ends what a command prints and not the command): the command ends with one line naming the
stream and the reason and exit status 2, no traceback. Before, ``fitbench`` and ``python -m experiments.run`` printed
a traceback of the last flush (exit 1)."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from conftest import subprocess_env

pytestmark = pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux), a device that "
                                                                          "refuses every write")

STUDY = '''name = "full"
title = "stdout test study"
kind = "grid"
seed = 5
repetitions = 2

[[datasets]]
source = "circle"
params = { n = 20 }

[[methods]]
id = "circle.kasa"
'''


def run_to_full(args, cwd):
    with open("/dev/full", "w") as full:
        return subprocess.run([sys.executable, *args], cwd=cwd, stdout=full, stderr=subprocess.PIPE, text=True,
                              env=subprocess_env(OPENBLAS_NUM_THREADS="1"), timeout=300)


def test_fitbench_fit_to_a_full_device(tmp_path):
    trace = os.path.join(os.path.dirname(__file__), "..", "docs", "examples", "trace.csv")
    out = run_to_full(["-m", "fitbench", "fit", "circle.kasa", os.path.abspath(trace)], tmp_path)
    assert out.returncode == 2, out.stderr
    assert out.stderr.strip().splitlines() == ["fitbench: error: cannot write standard output: No space left on "
                                               "device"], out.stderr


def test_a_run_and_its_report_to_a_full_device(tmp_path):
    (tmp_path / "full.toml").write_text(STUDY, encoding="utf-8")
    out = run_to_full(["-m", "experiments.run", "full.toml", "--jobs", "1", "--out", "o"], tmp_path)
    assert out.returncode == 2, out.stderr
    assert out.stderr.strip().splitlines() == ["experiments.run: error: cannot write standard output: No space left "
                                               "on device; the finished rows and outputs are kept"], out.stderr
    assert (tmp_path / "o" / "full" / "results.csv").is_file()
    rep = run_to_full(["-m", "experiments.report", "--results", "o"], tmp_path)
    assert rep.returncode == 2 and "Traceback" not in rep.stderr, rep.stderr
    assert rep.stderr.strip().splitlines()[-1].startswith("experiments.report: error: cannot write standard output")
