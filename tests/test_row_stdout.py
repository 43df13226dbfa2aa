"""What a method prints while its rows run (print, bytes written to descriptor 1, a process it starts) goes to the
run's stderr: the run's stdout carries its own lines alone (a log of ``python -m experiments.run ... > log`` held a
plugin's prints and NUL bytes between the progress lines). As ``fitbench fit`` does."""
from __future__ import annotations

import os
import textwrap

import pytest

from conftest import install_plugin, run_python

TALKER = '''
import os

import numpy as np
from methods import register
from methods.results import circle_result


@register("circle.talker", kind="closed form", summary="prints while it fits", reference="stdout test")
def talker(points):
    print("TALKER-PRINT", "." * 2000)
    os.write(1, b"\\x00\\x01TALKER-BYTES\\n")
    os.system("echo TALKER-CHILD")
    c = points.mean(axis=0)
    return circle_result(points, c, float(np.hypot(*(points - c).T).mean()), converged=True, message="closed form")
'''


@pytest.mark.slow   # a run in a subprocess, its rows in a worker and its plugin's in a child of it: 5-8 s
def test_a_method_s_prints_stay_out_of_the_run_s_stdout(tmp_path):
    site = install_plugin(tmp_path / "plug", "fitbench-talker", {"fitbench_talker": TALKER},
                          {"fitbench.methods": {"talker": "fitbench_talker"}})
    study = tmp_path / "talk.toml"
    study.write_text(textwrap.dedent('''
        name = "talk"
        title = "talk"
        seed = 1
        repetitions = 2
        [[datasets]]
        source = "circle"
        params = { radius = 5.0, noise = 0.01, n = 20 }
        [[methods]]
        id = "circle.kasa"
        [[methods]]
        id = "circle.talker"
    '''), encoding="utf-8")
    proc = run_python("-m", "experiments.run", study, "--out", tmp_path / "out", "--jobs", "1", "--no-report",
                      path_first=[site], timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "TALKER" not in proc.stdout and "\x00" not in proc.stdout, proc.stdout
    assert "== talk: talk" in proc.stdout and "4 rows: 0 already stored, 4 to run" in proc.stdout, proc.stdout
    assert "talk/results.csv (4 rows" in proc.stdout, proc.stdout
    for text in ("TALKER-PRINT", "TALKER-BYTES", "TALKER-CHILD"):
        assert proc.stderr.count(text) == 2, proc.stderr   # said, on stderr: one per row


def test_rows_run_in_the_run_s_process_print_to_stderr(capfd):
    """``--jobs 1`` with fitbench's own methods: the chunks run in the run's process, each with descriptor 1 on
    stderr; what the engine prints between them (a stored chunk, the progress) stays on stdout."""
    from experiments import executors

    class Store:
        def put_batch(self, keys, batch):
            print(f"ENGINE-STORED {keys}")

    def work(chunk):
        print("ROW-PRINT")
        os.write(1, b"\x00ROW-BYTES\n")
        return {"columns": {}, "seconds": 0.001}

    tasks = [{"key": f"k{i}"} for i in range(3)]
    executors.execute(tasks, Store(), work=work, jobs=1, executor="local", scheduler=None, desc="t", total=3,
                      chunk_rows=1, log=print)
    out, err = capfd.readouterr()
    assert "ROW" not in out and "\x00" not in out, out
    assert out.splitlines() == ["ENGINE-STORED ['k0']", "ENGINE-STORED ['k1']", "ENGINE-STORED ['k2']"], out
    assert err.count("ROW-PRINT") == 3 and err.count("ROW-BYTES") == 3, err
