"""Dask runs with hostile methods: a row blocked in compiled code past its limit is ``timeout``, rows that end
their process are ``crashed`` while the innocent rows of their chunk are computed, a cluster that keeps losing
workers never hangs the run, a cluster left without workers stops it in one line, and no process of a run
outlives it (every process it started carries a marker in its environment, looked for in /proc).

The hostile methods are the plugin of :mod:`test_engine` (built offline, found by the Dask workers through
PYTHONPATH)."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import stop_processes, subprocess_env
from test_engine import hostile_methods, hostile_site, write_study  # noqa: F401 (hostile_site: a fixture)
from test_dask_cluster import DASK, free_port, wait_listening

pytestmark = pytest.mark.skipif(not Path("/proc/self/environ").exists(), reason="looks for processes in /proc")


def start(args, cwd, site, marker, **variables):
    return subprocess.Popen([sys.executable, "-m", "experiments.run", *map(str, args), "--no-report"], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=subprocess_env(site, OPENBLAS_NUM_THREADS="1", FITBENCH_TEST_RUN=marker, **variables))


def run(args, cwd, site, timeout=300, **variables):
    """The run's exit code, stdout and stderr, and the processes it left behind (none, once it ended)."""
    marker = uuid.uuid4().hex
    proc = start(args, cwd, site, marker, **variables)
    try:
        out, err = proc.communicate(timeout=timeout)
    finally:
        if proc.poll() is None:  # hung: end it and everything it started, so the test fails without leftovers
            proc.kill()
            proc.communicate()
            for pid in survivors(marker, wait_s=0):
                os.kill(pid, signal.SIGKILL)
    return proc.returncode, out, err, survivors(marker)


def survivors(marker: str, wait_s: float = 10.0, running: str = "") -> list[int]:
    """Processes whose environment carries ``marker`` (and whose command line contains ``running``), after
    waiting up to ``wait_s`` for them to end."""
    needle = f"FITBENCH_TEST_RUN={marker}".encode()
    deadline = time.monotonic() + wait_s
    while True:
        found = []
        for entry in Path("/proc").iterdir():
            if entry.name.isdigit():
                try:
                    if needle in (entry / "environ").read_bytes().split(b"\0"):
                        status = (entry / "status").read_text()
                        if "\nState:\tZ" not in status and running.encode() in (entry / "cmdline").read_bytes():
                            found.append(int(entry.name))  # (a zombie has ended; its parent has not reaped it yet)
                except OSError:
                    continue
        if not found or time.monotonic() > deadline:
            return found
        time.sleep(0.25)


def statuses(results: Path) -> pd.DataFrame:
    df = pd.read_csv(results)
    df["what"] = df["param_what"].fillna("") if "param_what" in df else ""
    return df


@pytest.mark.system  # a Dask cluster whose workers are killed and restarted: 10-40 s
def test_rows_blocked_in_c_end_as_timeout_on_dask(tmp_path, hostile_site):
    """--row-timeout on a Dask LocalCluster: a row sleeping in C with the alarm ignored (it ran for ever in the
    worker's thread: an exception raised in a thread cannot interrupt a C call) is ``timeout``, a Python loop
    too; os._exit, SystemExit and KeyboardInterrupt are ``crashed``; the other rows are ok; nothing outlives the run."""
    study = write_study(tmp_path, name="dc", reps=1,
                        methods=hostile_methods("hang_in_c", "hang", "exit", "sysexit", "kbint"))
    code, out, err, left = run([study, "--jobs", "2", "--executor", "dask", "--row-timeout", "1",
                                "--out", tmp_path / "out"], tmp_path, hostile_site)
    assert code == 0, err
    df = statuses(tmp_path / "out" / "dc" / "results.csv")
    assert len(df) == 2 * 7
    assert set(df.loc[df["what"] == "", "status"]) == {"ok"}
    assert set(df.loc[df["what"].isin(["hang_in_c", "hang"]), "status"]) == {"timeout"}
    assert set(df.loc[df["what"].isin(["exit", "sysexit", "kbint"]), "status"]) == {"crashed"}
    assert set(df.loc[df["what"] == "exit", "message"]) == {"the process running this row ended (exit code 3)"}  # the local executor's words
    assert set(df.loc[df["what"] == "hang_in_c", "message"]) == {"the row ran longer than its limit of 1 s (the process running it was ended)"}
    assert not left, f"processes of the run still alive after it ended: {left}"


@pytest.mark.system  # a Dask cluster whose workers are killed and restarted: 10-40 s
def test_workers_dying_again_and_again_never_hang_the_run(tmp_path, hostile_site):
    """No time limit: each ``kill_worker`` row kills its Dask worker (the plugin's row runs in a child of a row
    process, which kills the worker above it). With LocalCluster's lost-worker timeout short (it closed a nanny
    whose restarted worker had not registered yet: after a few deaths no worker was left and the run waited for
    ever) the run completes; the chunk holding a killer is bisected, so the rows beside it are computed and only
    the killer is ``crashed``; a plugin's os._exit ends only its row's process, never the worker; nothing outlives
    the run."""
    study = write_study(tmp_path, name="dd", reps=1, methods=hostile_methods("exit", "kill_worker"),
                        extra="chunk_rows = 6\n")
    code, out, err, left = run([study, "--jobs", "2", "--executor", "dask", "--out", tmp_path / "out"], tmp_path,
                               hostile_site, timeout=400, DASK_DISTRIBUTED__DEPLOY__LOST_WORKER_TIMEOUT="0.2s")
    assert code == 0, err
    df = statuses(tmp_path / "out" / "dd" / "results.csv")
    assert len(df) == 2 * 4
    assert set(df.loc[df["what"] == "", "status"]) == {"ok"}
    assert set(df.loc[df["what"].isin(["exit", "kill_worker"]), "status"]) == {"crashed"}
    assert df.loc[df["what"] == "kill_worker", "message"].str.contains("KilledWorker").all()
    assert set(df.loc[df["what"] == "exit", "message"]) == {"the process running this row ended (exit code 3)"}
    assert not left, f"processes of the run still alive after it ended: {left}"


@pytest.mark.slow
def test_a_killed_run_leaves_no_dask_worker_nor_row_process(tmp_path, hostile_site):
    """SIGKILL of the run while its Dask workers' row processes sleep in C: every process it started ends."""
    study = write_study(tmp_path, name="dk", reps=20, methods=hostile_methods("hang_in_c"))
    marker = uuid.uuid4().hex
    proc = start([study, "--jobs", "2", "--executor", "dask", "--row-timeout", "100", "--out", tmp_path / "out"],
                 tmp_path, hostile_site, marker)
    try:
        deadline = time.monotonic() + 120
        while (len(survivors(marker, wait_s=0, running="_child_main")) < 2 and time.monotonic() < deadline
               and proc.poll() is None):  # both workers' row processes are running rows
            time.sleep(0.5)
        assert proc.poll() is None, proc.communicate()[1]
        # the 2 workers' row processes, and the children they fork for the plugin's rows (one at a time each)
        assert 2 <= len(survivors(marker, wait_s=0, running="_child_main")) <= 4
        assert len(survivors(marker, wait_s=0)) >= 5  # the run, 2 workers, 2 row processes
        time.sleep(2)  # the rows are sleeping in C
    finally:
        proc.kill()
        proc.communicate()
    left = survivors(marker, wait_s=15)
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    assert not left, f"processes of a killed run still alive: {left}"


@pytest.mark.system  # a local Dask cluster, interrupted while it starts or while its workers run rows: about 15 s each
@pytest.mark.parametrize("after_s", [1.0, 3.0], ids=["while-the-cluster-starts", "while-rows-run"])
def test_ctrl_c_of_a_dask_run_prints_one_line_and_leaves_no_process(tmp_path, hostile_site, after_s):
    """Ctrl-C on a terminal reaches the whole process group: the local cluster's workers ignore it (the run stops
    them) and the run prints its one line (each worker printed a KeyboardInterrupt traceback, 68 lines in all).
    One second after the row store appears the local cluster is still starting on a 2-core machine: interrupted
    there, workers died in their imports and distributed's exit hook failed to close the half-started cluster,
    each with a long traceback (as once in CI, under load, with the later moment)."""
    study = write_study(tmp_path, name="dk", reps=20000)
    marker = uuid.uuid4().hex
    proc = subprocess.Popen([sys.executable, "-m", "experiments.run", str(study), "--jobs", "2", "--executor", "dask",
                             "--no-report", "--out", str(tmp_path / "out")], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            env=subprocess_env(hostile_site, OPENBLAS_NUM_THREADS="1", FITBENCH_TEST_RUN=marker))
    try:
        deadline = time.monotonic() + 120
        while not (tmp_path / "out" / "dk" / "rows.sqlite").exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        time.sleep(after_s)
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    left = survivors(marker)
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    assert err.strip().splitlines() == [f"experiments.run: interrupted; finished rows are kept in "
                                        f"{tmp_path / 'out' / 'dk' / 'rows.sqlite'}; run the same command again to "
                                        f"resume"], err
    assert not left


@pytest.mark.system
@pytest.mark.skipif(DASK is None, reason="the dask command line (package distributed) is not installed")
def test_a_cluster_without_workers_stops_the_run_in_one_line(tmp_path, hostile_site):
    """A scheduler whose only worker has no nanny: the first row that kills its worker leaves the cluster without
    workers. The run waited for ever; it stops after FITBENCH_DASK_NO_WORKER_S (2 s here: the worker has registered
    before the run starts, so the cluster is without workers only once it is killed) with one line and exit 2, the
    rows finished before are kept."""
    env = subprocess_env(hostile_site, OPENBLAS_NUM_THREADS="1")
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                              cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        wait_listening(procs[0], port)  # not a fixed sleep (2 s before)
        procs.append(subprocess.Popen([DASK, "worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                                       "--local-directory", str(tmp_path / "w")], cwd=tmp_path, env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client
        with Client(address, timeout=30) as c:
            c.wait_for_workers(1, timeout=120)
        study = write_study(tmp_path, name="dn", reps=3, methods=hostile_methods("kill_worker"))
        t0 = time.monotonic()
        code, out, err, left = run([study, "--executor", "dask", "--scheduler", address, "--out", tmp_path / "out"],
                                   tmp_path, hostile_site, timeout=300, FITBENCH_DASK_NO_WORKER_S="2")
        assert code == 2, err
        lines = err.strip().splitlines()
        assert len(lines) == 1 and "has had no worker for 2 s" in lines[0] and "run the same command again" in lines[0]
        assert time.monotonic() - t0 < 120
        assert not left
    finally:
        stop_processes(procs)


DRIFT = '''
"""A plugin method whose code the test edits while a Dask worker has it loaded."""
import numpy as np

from methods import register
from methods.results import circle_result

FACTOR = 1.0


@register("circle.drift", kind="closed form", summary="centroid and mean distance", reference="test")
def drift(points):
    """The centroid and FACTOR times the mean distance to it."""
    c = points.mean(axis=0)
    return circle_result(points, c, FACTOR * float(np.hypot(*(points - c).T).mean()), converged=True,
                         message="closed form")
'''


@pytest.mark.system
@pytest.mark.skipif(DASK is None, reason="the dask command line (package distributed) is not installed")
def test_a_worker_that_loaded_a_method_before_it_changed_stores_no_row(tmp_path):
    """A standing cluster's worker keeps the code it loaded: after an edit of a plugin's method the run keyed its rows
    by the new code while the worker computed them with the old (a reviewer found radius 5.0 stored where the edited
    method gives 10.0). The run now stops in one line before storing any row of it; a fresh worker runs them."""
    from conftest import install_plugin
    site = install_plugin(tmp_path, "fitbench-drift", {"fitbench_drift": DRIFT}, {"fitbench.methods": {"drift": "fitbench_drift"}})
    env = subprocess_env(site, OPENBLAS_NUM_THREADS="1")
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"

    def worker():
        return subprocess.Popen([DASK, "worker", address, "--nthreads", "1", "--no-dashboard",
                                 "--local-directory", str(tmp_path / "w")], cwd=tmp_path, env=env,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    procs = [subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                              cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        wait_listening(procs[0], port)  # not a fixed sleep (2 s before)
        procs.append(worker())
        from distributed import Client
        with Client(address, timeout=30) as c:
            c.wait_for_workers(1, timeout=120)
        methods = '[[methods]]\nid = "circle.drift"\n'
        args = ["--executor", "dask", "--scheduler", address, "--out", tmp_path / "out"]
        code, out, err, _ = run([write_study(tmp_path, name="dr", reps=2, methods=methods), *args], tmp_path, site)
        assert code == 0, err
        ident = ["data_arc_deg", "repetition"]
        first = pd.read_csv(tmp_path / "out" / "dr" / "results.csv").set_index(ident)["radius"]
        plugin = site / "fitbench_drift.py"
        time.sleep(0.05)  # a later time stamp than the worker saw, on any file system
        plugin.write_text(plugin.read_text().replace("FACTOR = 1.0", "FACTOR = 2.0"))
        code, out, err, _ = run([write_study(tmp_path, name="dr", reps=4, methods=methods), *args], tmp_path, site)
        lines = err.strip().splitlines()
        assert code == 2 and len(lines) == 1 and "circle.drift" in lines[0] and "restart the workers" in lines[0], err
        stored = pd.read_csv(tmp_path / "out" / "dr" / "results.csv").set_index(ident)["radius"]
        assert stored.equals(first)  # the first run's outputs, nothing of the second
        procs[1].terminate()
        procs[1].wait(timeout=30)
        procs[1] = worker()
        code, out, err, _ = run([write_study(tmp_path, name="dr", reps=4, methods=methods), *args], tmp_path, site)
        assert code == 0, err
        fresh = pd.read_csv(tmp_path / "out" / "dr" / "results.csv").set_index(ident)["radius"]
        assert len(fresh) == 8  # every row by the edited code (all were keyed anew): twice the first run's radii
        assert np.allclose(fresh.loc[first.index] / first, 2.0, rtol=1e-12, atol=0)
    finally:
        stop_processes(procs)


def test_a_worker_with_other_code_or_environment_is_refused():
    """The check a Dask task makes before its rows: the run's code hashes and environment against the worker's."""
    from experiments import dask_executor, engine
    task = next(engine.iter_grid_tasks({"name": "ck", "kind": "grid", "seed": 1, "repetitions": 1,
                                        "datasets": [{"source": "circle", "params": {"n": 10}}],
                                        "methods": [{"id": "circle.kasa"}]}, "ck.toml"))
    reps, env = dask_executor.expected_code([task])
    dask_executor.check_code([task], (reps, env))  # this process: the same code
    with pytest.raises(dask_executor.WorkerCodeError, match=r"other code than this run for circle.kasa \(method\)"):
        dask_executor.check_code([task], ([(0, {**reps[0][1], "method": "0" * 16})], env))
    with pytest.raises(dask_executor.WorkerCodeError, match="another environment than this run"):
        dask_executor.check_code([task], (reps, {**env, "kernels": "elsewhere"}))


def test_a_row_running_long_in_a_dask_workers_thread_is_named_once():
    """Rows in a Dask worker's thread without a time limit: a row running for the notice's seconds is named once to
    the run, in the local executor's words (a hung row left the progress line frozen with no word on Dask)."""
    from experiments import dask_executor
    tasks = [{"method": "circle.slow", "dataset": {"label": "arc"}, "repetition": 3},
             {"method": "circle.kasa", "dataset": {"label": "arc"}, "repetition": 4}]
    said = []

    def work(chunk, row_timeout, progress):
        for i, pause in enumerate((1.2, 0.0)):
            progress[0], progress[1] = time.monotonic(), i
            time.sleep(pause)
        return {"rows": len(chunk)}

    out = dask_executor._watched(work, tasks, dask_executor._LongRows(tasks, 0.2, said.append))
    assert out == {"rows": 2}
    slow = [line for line in said if "circle.slow on arc, repetition 3" in line]
    assert len(slow) == 1, said
    assert "a row has been running for" in slow[0] and "--row-timeout SECONDS" in slow[0]


@pytest.mark.system  # a local Dask cluster of one worker, two rows of 2.5 s in its row process: about 15 s
def test_a_row_running_long_on_dask_is_named_once_in_the_runs_output(tmp_path, hostile_site):
    """A plugin's study on Dask (rows in the workers' row processes), no time limit: each row running longer than
    STUCK_NOTICE_S (1 s here; the rows take 2.5 s) is named once in the run's output, as with local workers."""
    study = write_study(tmp_path, name="dlong", reps=1, methods=hostile_methods("slow"))
    code = ("import sys; import experiments.executors as e; e.STUCK_NOTICE_S = 1.0; from experiments import run; "
            "sys.exit(run.main(sys.argv[1:]))")
    marker = uuid.uuid4().hex
    res = subprocess.run([sys.executable, "-c", code, str(study), "--executor", "dask", "--jobs", "1", "--out",
                          str(tmp_path / "o"), "--no-report"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=600, env=subprocess_env(hostile_site, OPENBLAS_NUM_THREADS="1",
                                                         FITBENCH_TEST_RUN=marker))
    assert res.returncode == 0, res.stderr
    named = [line for line in res.stdout.splitlines() if "a row has been running for" in line]
    assert len(named) == 2, res.stdout  # the study's two slow rows (one per data set), each named once
    assert all("circle.hostile on " in line and "--row-timeout SECONDS" in line for line in named), named
    assert not survivors(marker), "processes of the run still alive after it ended"


def test_a_row_process_that_cannot_start_leaves_nothing_open(monkeypatch):
    """A row process that cannot be spawned (too many processes or open files): its socket and its progress page
    are closed as the error is raised (they stayed open while the error's traceback lived, e.g. in Dask's report)."""
    from experiments import dask_executor

    def no_process(args, fds):
        raise OSError(11, "Resource temporarily unavailable")
    monkeypatch.setattr(dask_executor, "_spawn", no_process)
    before = sorted(os.listdir("/proc/self/fd"))
    with pytest.raises(OSError, match="Resource temporarily unavailable") as caught:
        dask_executor._RowProcess()
    assert sorted(os.listdir("/proc/self/fd")) == before, "descriptors left open by a row process that never started"
    del caught


@pytest.mark.parametrize("interrupted", [False, True], ids=["busy-machine", "ctrl-c-while-it-starts"])
def test_a_local_cluster_that_does_not_start_is_one_line(tmp_path, monkeypatch, capsys, interrupted):
    """distributed gives the thread of its event loop 10 s to start, then fails an ``assert`` (seen in a test at load
    7): the run said nothing but a traceback, exit 1. Now one line, exit 2; and when the user's Ctrl-C (held while
    the cluster started) came first, the run's own interrupt line, exit 130."""
    import distributed

    from experiments import rows
    from experiments import run as run_module

    def not_starting(*args, **kwargs):
        if interrupted:  # the run's own Ctrl-C handler, called as the signal would call it (no real signal: it
            signal.getsignal(signal.SIGINT)(signal.SIGINT, None)  # would reach the test runner's process too)
        raise AssertionError

    monkeypatch.setattr(distributed, "LocalCluster", not_starting)
    study = write_study(tmp_path, name="dk0", reps=2)
    try:
        code = run_module.main([str(study), "--executor", "dask", "--jobs", "1", "--no-report", "--out",
                                str(tmp_path / "out")])
    finally:
        rows.clear_signal()  # this process goes on with other tests
    err = capsys.readouterr().err.strip().splitlines()
    if interrupted:
        assert code == 130 and len(err) == 1 and "interrupted" in err[0], err
    else:
        assert code == 2 and len(err) == 1, err
        assert "the local Dask cluster did not start (AssertionError: no message" in err[0]
        assert "--executor local" in err[0]
