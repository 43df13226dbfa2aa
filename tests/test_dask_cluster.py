"""A Dask scheduler and two workers as separate processes on 127.0.0.1, started in
another folder than the client's; the rows of a small study are identical (non-timing columns) to a local run."""
from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from conftest import stop_processes, subprocess_env
from results_csv import non_timing

pytestmark = pytest.mark.system  # starts a Dask scheduler and workers as separate processes

DASK = shutil.which("dask", path=str(Path(sys.executable).parent)) or shutil.which("dask")

STUDY = '''name = "cluster"
title = "dask cluster test"
kind = "grid"
seed = 17
repetitions = 3

[[datasets]]
generator = "circle"
params = { center = [10.0, -3.0], radius = 2.0, noise = 0.01 }
grid = { n = [12, 40] }

[[methods]]
id = "circle.kasa"
[[methods]]
id = "circle.levenberg_marquardt"
[[methods]]
id = "circle.nelder_mead"
'''


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_listening(proc: subprocess.Popen, port: int, timeout: float = 300.0) -> None:
    """Until ``proc`` (the scheduler) accepts connections on ``port``; it must not end meanwhile."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, f"the scheduler ended (exit code {proc.returncode}) before it listened"
        try:
            socket.create_connection(("127.0.0.1", port), timeout=5).close()
            return
        except OSError:
            time.sleep(0.1)
    raise AssertionError(f"the scheduler did not listen on port {port} within {timeout:.0f} s")


@pytest.mark.skipif(DASK is None, reason="the dask command line (package distributed) is not installed")
def test_study_on_a_separate_scheduler_and_workers_matches_local_run(tmp_path):
    client_dir, worker_dir = tmp_path / "client", tmp_path / "elsewhere"
    client_dir.mkdir()
    worker_dir.mkdir()
    cfg = client_dir / "cluster.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    env = subprocess_env(OPENBLAS_NUM_THREADS="1")  # workers: fitbench importable, nothing else
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                              cwd=worker_dir, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        wait_listening(procs[0], port)  # 0.3 s here, 1.8 s beside 10 busy processes: not a fixed sleep
        for _ in range(2):
            procs.append(subprocess.Popen([DASK, "worker", address, "--nthreads", "1", "--no-dashboard",
                                           "--local-directory", str(worker_dir)],
                                          cwd=worker_dir, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client
        with Client(address, timeout=120) as c:
            c.wait_for_workers(2, timeout=120)
            assert all(Path(d) != client_dir for d in c.run(os.getcwd).values())
        common = [sys.executable, "-m", "experiments.run", str(cfg)]
        dask_run = subprocess.run(common + ["--executor", "dask", "--scheduler", address, "--out", "dask_out"],
                                  cwd=client_dir, env=env, capture_output=True, text=True, timeout=300)
        assert dask_run.returncode == 0, dask_run.stderr
        local = subprocess.run(common + ["--jobs", "1", "--out", "local_out"], cwd=client_dir, env=env,
                               capture_output=True, text=True, timeout=300)
        assert local.returncode == 0, local.stderr
        assert not list(worker_dir.rglob("rows.sqlite")), "rows are written by the client, not the workers"
        a = non_timing(client_dir / "dask_out" / "cluster" / "results.csv")
        b = non_timing(client_dir / "local_out" / "cluster" / "results.csv")
        assert len(a) == 2 * 3 * 3
        pd.testing.assert_frame_equal(a, b)
    finally:
        stop_processes(procs)
