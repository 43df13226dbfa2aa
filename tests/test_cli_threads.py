"""The subcommands compute with one BLAS thread (their solves are small: a second thread only waits, spinning;
``fitbench circular-test`` used 3-4 x the CPU of one thread on 2 cores), unless the user chose a count."""
import os

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from datasets.circular_test import circular_test, lola_hbg130
from fitbench.cli import circular_test as circular_test_cli, commands

VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")  # what BLAS and OpenMP libraries read


@pytest.fixture(scope="module")
def run_files(tmp_path_factory):
    cw, ccw, _ = circular_test(*lola_hbg130())
    folder = tmp_path_factory.mktemp("threads")
    paths = []
    for name, pts in (("cw", cw[::8]), ("ccw", ccw[::8])):   # ~420 points a run: the same solves, smaller
        paths.append(folder / f"{name}.csv")
        np.savetxt(paths[-1], pts, delimiter=",", header="x,y", comments="", fmt="%.6f")
    return [str(p) for p in paths]


def circular_test_seeing_threads(monkeypatch, capsys, run_files):
    """Run ``circular-test`` with BLAS at 2 threads outside; what the command saw: (threads per library, env)."""
    seen = {}
    real = circular_test_cli.run   # the function the parser's circular-test calls (fitbench/cli/circular_test.py)

    def spy(args):
        code = real(args)
        seen["threads"] = {i["filepath"]: i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}
        seen["env"] = {v: os.environ.get(v) for v in VARS}
        return code

    monkeypatch.setattr(circular_test_cli, "run", spy)
    with threadpool_limits(limits=2, user_api="blas"):
        outside = {i["filepath"]: i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}
        assert commands.main(["circular-test", *run_files, "--nominal-radius", "298.997",
                              "--nominal-center", "1200", "650"]) == 0
        after = {i["filepath"]: i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}
    out = capsys.readouterr().out
    assert "G(b)" in out and "squareness" in out                 # the command ran to its end, diagnostics too
    return seen, outside, after


def test_a_subcommand_computes_with_one_blas_thread_and_restores_the_pools(monkeypatch, capsys, run_files):
    for v in VARS:
        monkeypatch.delenv(v, raising=False)
    seen, outside, after = circular_test_seeing_threads(monkeypatch, capsys, run_files)
    assert seen["threads"] and set(seen["threads"].values()) == {1}, seen
    assert seen["env"] == dict.fromkeys(VARS, "1")            # libraries loaded during the command read these
    assert {k: after[k] for k in outside} == outside             # the pools loaded before are as they were
    assert all(v not in os.environ for v in VARS)               # and the environment too


def test_a_thread_count_the_user_chose_is_kept(monkeypatch, capsys, run_files):
    for v in VARS:
        monkeypatch.delenv(v, raising=False)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    seen, outside, _ = circular_test_seeing_threads(monkeypatch, capsys, run_files)
    assert {k: seen["threads"][k] for k in outside} == outside, seen
    assert seen["env"]["OPENBLAS_NUM_THREADS"] == "2"
