"""Run faults and the fault-injection test: kills, interrupts, a corrupt row store, history-
independent row order, --jobs and --out checks, a bad Dask scheduler. The runs are subprocesses started in
another folder than the repository (PYTHONPATH points at this checkout), but for those whose process is not what is
tested (the row store, the row order, --jobs and --out): ``experiments.run.main`` in this process, in that folder."""
from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pandas as pd
import pytest

from conftest import default_sigint, stored_rows, subprocess_env, while_storing_rows
from results_csv import non_timing

pytestmark = pytest.mark.slow  # kills, interrupts and restarts whole study runs

STUDY = '''name = "{name}"
title = "fault test study"
kind = "grid"
seed = 11
repetitions = {reps}

[[datasets]]
generator = "circle"
params = {{ center = [1.0, 2.0], radius = 5.0, noise = 0.01 }}
grid = {{ n = {ns} }}

[[methods]]
id = "circle.kasa"
[[methods]]
id = "circle.gauss_newton"
[[methods]]
id = "circle.nelder_mead"
'''


def study(folder: Path, name="faults", reps=3, ns="[10, 20]") -> Path:
    path = folder / f"{name}.toml"
    path.write_text(STUDY.format(name=name, reps=reps, ns=ns), encoding="utf-8")
    return path


def run(args, cwd, timeout=300, **variables):
    return subprocess.run([sys.executable, "-m", "experiments.run", *map(str, args)], cwd=cwd,
                          env=subprocess_env(**variables), capture_output=True, text=True, timeout=timeout)


def run_here(args, cwd, monkeypatch, capsys):
    """``python -m experiments.run ARGS`` in ``cwd`` as a call of ``experiments.run.main`` in this process: its exit
    status and what it printed."""
    from experiments.run import main
    monkeypatch.chdir(cwd)
    capsys.readouterr()
    code = main([str(a) for a in args])
    printed = capsys.readouterr()
    return SimpleNamespace(returncode=code, stdout=printed.out, stderr=printed.err)


def start(args, cwd):
    return subprocess.Popen([sys.executable, "-m", "experiments.run", *map(str, args)], cwd=cwd, env=subprocess_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=default_sigint)


def children(pid: int) -> set[int]:
    """Every live descendant of ``pid`` (from /proc)."""
    parent = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
                parent[int(d.name)] = int(stat.rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                pass
    out, todo = set(), [pid]
    while todo:
        p = todo.pop()
        for c, pp in parent.items():
            if pp == p and c not in out:
                out.add(c)
                todo.append(c)
    return out


def alive(pids) -> set[int]:
    left = set()
    for p in pids:
        try:
            state = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()[0]
            if state != "Z":
                left.add(p)
        except OSError:
            pass
    return left


def wait_rows(proc, db: Path, at_least: int, timeout=120):
    t0 = time.time()
    while time.time() - t0 < timeout:
        if proc.poll() is not None:
            return False
        if stored_rows(db) >= at_least:
            return True
        time.sleep(0.05)
    raise AssertionError("no rows were stored in time")



def no_survivors(pids, within=60.0):
    """The processes of ``pids`` still alive after waiting up to ``within`` seconds for them to end."""
    t0 = time.monotonic()
    while alive(pids) and time.monotonic() - t0 < within:
        time.sleep(0.1)
    return alive(pids)


def interrupted_among_rows(tmp_path, act, reps=400, ns="[50, 200]", attempts=3):
    """A --jobs 2 run (in its own session) of a study of ``reps`` x ``ns`` x 3 methods rows, and ``act(proc)`` done
    while some of its rows are stored and others are not (:func:`conftest.while_storing_rows`). The study is large
    (2,400 rows, about 3 s of rows here) and interrupted after its first rows: it costs its start only. The run is
    started again only when this test was descheduled for the whole of its rows."""
    cfg = study(tmp_path, reps=reps, ns=ns)
    total = reps * len(ns.strip("[]").split(",")) * 3
    for attempt in range(attempts):
        out = tmp_path / f"out{attempt}"
        proc = start([cfg, "--jobs", "2", "--out", out], tmp_path)
        if while_storing_rows(proc, out / "faults" / "rows.sqlite", 2, total, lambda: act(proc), group=True) is not None:
            return proc
        proc.kill()
        proc.communicate(timeout=60)
    raise AssertionError(f"the run stored all its {total} rows before this test could act, {attempts} times")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP], ids=lambda s: s.name)
def test_sigterm_and_ctrl_c_print_one_line_and_leave_no_process(tmp_path, sig):
    """Ctrl-C, SIGTERM and SIGHUP (a closed terminal, an ended session) among the rows: one line naming the signal and
    where the finished rows are, the shell's status for it (128 + the signal's number), no worker left."""
    kids = set()

    def interrupt(proc):
        kids.update(children(proc.pid))
        os.killpg(proc.pid, sig) if sig == signal.SIGINT else proc.send_signal(sig)  # Ctrl-C reaches the whole group
    proc = interrupted_among_rows(tmp_path, interrupt)
    assert kids, "the run started no worker"
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    what = "interrupted" if sig == signal.SIGINT else f"terminated ({signal.Signals(sig).name})"
    assert lines[0].startswith(f"experiments.run: {what}; finished rows are kept in "), lines
    assert "rows.sqlite" in lines[0] and "resume" in lines[0]
    assert not no_survivors(kids), "worker or resource tracker outlived the run"


def test_a_sighup_the_run_was_started_to_ignore_does_not_stop_it(tmp_path):
    """``nohup python -m experiments.run ...``: the SIGHUP the run was started to ignore stays ignored (the run's own
    handlers take SIGINT and SIGTERM only then), and the run ends with all its rows."""
    cfg = study(tmp_path, reps=40, ns="[50, 200]")
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "experiments.run", str(cfg), "--jobs", "1", "--no-report", "--out",
                             str(out)], cwd=tmp_path, env=subprocess_env(OPENBLAS_NUM_THREADS="1"),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGHUP, signal.SIG_IGN))
    deadline = time.monotonic() + 120
    while proc.poll() is None and not stored_rows(out / "faults" / "rows.sqlite") and time.monotonic() < deadline:
        time.sleep(0.02)
    proc.send_signal(signal.SIGHUP)
    stdout, err = proc.communicate(timeout=300)
    assert proc.returncode == 0 and "Traceback" not in err, err
    assert len(pd.read_csv(out / "faults" / "results.csv")) == 40 * 2 * 3


def test_a_reader_that_goes_ends_what_the_run_prints_not_the_run(tmp_path):
    """``python -m experiments.run A B | head -1``: the reader of stdout (and of stderr, ``2>&1 | head``) closing the
    pipe ends what the run prints, not the run: both studies are run and written, the report too, and the exit status
    is 0 (the run stopped with 'cannot write: Broken pipe' at its second line, exit 2, without its outputs)."""
    first, second = study(tmp_path, name="first", reps=2), study(tmp_path, name="second", reps=2)
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "experiments.run", str(first), str(second), "--jobs", "1",
                             "--out", str(out)], cwd=tmp_path, env=subprocess_env(OPENBLAS_NUM_THREADS="1"),
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    line = proc.stdout.readline()
    proc.stdout.close()   # the reader has what it wanted
    assert proc.wait(timeout=300) == 0
    assert line.startswith(b"== first")
    for name in ("first", "second"):
        assert len(pd.read_csv(out / name / "results.csv")) == 2 * 2 * 3
        assert (out / name / "meta.json").is_file()
    assert (out / "paper" / "report.md").is_file()


def test_sigkill_of_the_parent_ends_workers_and_resource_tracker(tmp_path):
    kids = set()

    def kill(proc):
        kids.update(children(proc.pid))
        proc.kill()
    proc = interrupted_among_rows(tmp_path, kill)
    proc.wait(timeout=60)
    assert len(kids) >= 2
    assert not no_survivors(kids), "processes outlived their SIGKILLed parent"


@pytest.mark.system  # kills whole runs at random moments, repeatedly
def test_fault_injection_sigkill_at_random_moments_then_rerun_reproduces(tmp_path):
    """SIGKILL at random moments during rows and during finalize (several seeds); each rerun gives the non-timing
    columns of an uninterrupted run exactly, and no process outlives its parent."""
    cfg = study(tmp_path, reps=2, ns="[10, 30]")
    ref = run([cfg, "--jobs", "1", "--out", tmp_path / "ref"], tmp_path)
    assert ref.returncode == 0, ref.stderr
    expected = non_timing(tmp_path / "ref" / "faults" / "results.csv")
    for seed in range(3):
        out = tmp_path / f"killed{seed}"
        rng = random.Random(seed)
        jobs = 2 if seed == 0 else 1
        proc = start([cfg, "--jobs", jobs, "--out", out], tmp_path)
        db = out / "faults" / "rows.sqlite"
        if seed < 2:  # during rows: after a random number of stored rows
            wait_rows(proc, db, rng.randint(1, 8))
        else:  # during finalize (seed 2): once every row is stored, after a random delay
            wait_rows(proc, db, len(expected))
            time.sleep(rng.uniform(0.0, 0.5))
        kids = children(proc.pid)
        proc.kill()
        proc.wait(timeout=60)
        assert not no_survivors(kids), f"seed {seed}: processes outlived their parent"
        again = run([cfg, "--jobs", jobs, "--out", out], tmp_path)
        assert again.returncode == 0, again.stderr
        assert not list(out.rglob("*.tmp")), "left-over temporary files"
        pd.testing.assert_frame_equal(non_timing(out / "faults" / "results.csv"), expected)


@pytest.mark.parametrize("damage", ["garbage", "truncated"])
def test_corrupt_row_store_is_moved_aside_and_recomputed(tmp_path, damage, monkeypatch, capsys):
    cfg = study(tmp_path, reps=1)
    out = tmp_path / "out"
    first = run_here([cfg, "--jobs", "1", "--out", out], tmp_path, monkeypatch, capsys)
    assert first.returncode == 0, first.stderr
    expected = non_timing(out / "faults" / "results.csv")
    db = out / "faults" / "rows.sqlite"
    data = db.read_bytes()
    db.write_bytes(b"this is not SQLite " * 200 if damage == "garbage" else data[: len(data) // 2])
    for extra in ([], ["--force"]):
        again = run_here([cfg, "--jobs", "1", "--out", out, *extra], tmp_path, monkeypatch, capsys)
        assert again.returncode == 0, again.stderr
        assert "Traceback" not in again.stderr
        if not extra:
            said = [ln for ln in again.stdout.splitlines() if "moved aside" in ln]
            assert len(said) == 1 and "rows.sqlite" in said[0], again.stdout
            assert list((out / "faults").glob("rows.sqlite.corrupt-*"))
        pd.testing.assert_frame_equal(non_timing(out / "faults" / "results.csv"), expected)
        db.write_bytes(b"\x00garbage" * 500)  # and --force on a corrupt store


def test_row_order_does_not_depend_on_history(tmp_path, monkeypatch, capsys):
    old = study(tmp_path, reps=1, ns="[10, 20]")
    resumed = tmp_path / "resumed"
    assert run_here([old, "--jobs", "1", "--out", resumed], tmp_path, monkeypatch, capsys).returncode == 0
    new_dir = tmp_path / "new"
    new_dir.mkdir()
    new = study(new_dir, reps=1, ns="[30, 20, 10]")  # reordered and extended grid: cached rows are reused
    second = run_here([new, "--jobs", "1", "--out", resumed], tmp_path, monkeypatch, capsys)
    assert second.returncode == 0 and "already stored" in second.stdout
    fresh = run_here([new, "--jobs", "1", "--out", tmp_path / "fresh"], tmp_path, monkeypatch, capsys)
    assert fresh.returncode == 0
    a = non_timing(resumed / "faults" / "results.csv")
    b = non_timing(tmp_path / "fresh" / "faults" / "results.csv")
    assert list(a["data_n"][:3]) == [30, 30, 30]
    pd.testing.assert_frame_equal(a, b)


def test_jobs_capped_out_checked_and_default_out_in_cwd(tmp_path, monkeypatch, capsys):
    cfg = study(tmp_path, reps=1, ns="[10]")
    res = run_here([cfg, "--jobs", "64"], tmp_path, monkeypatch, capsys)  # no --out: results/user/ in the working
    # directory (not the project's)
    assert res.returncode == 0, res.stderr
    capped = [ln for ln in res.stdout.splitlines() if "capped" in ln]
    assert len(capped) == 1 and "--jobs 64" in capped[0]
    assert (tmp_path / "results" / "user" / "faults" / "results.csv").is_file()
    afile = tmp_path / "a_file"
    afile.write_text("x")
    for out in (afile, afile / "below"):
        res = run_here([cfg, "--out", out], tmp_path, monkeypatch, capsys)
        assert res.returncode == 2 and "Traceback" not in res.stderr
        assert len(res.stderr.strip().splitlines()) == 1 and "--out" in res.stderr


#: distributed's own connection timeout in the runs of the bad-scheduler test: far beyond the run's limit
#: (experiments.dask_executor.DASK_CONNECT_TIMEOUT_S, 5 s), so that a run waiting on distributed's timeout (30 s by
#: default) or for ever cannot be mistaken for a slow start on a loaded machine
DISTRIBUTED_CONNECT_S = 600


def test_bad_dask_scheduler_is_one_line_in_bounded_time(tmp_path):
    """A scheduler that does not answer is refused in one line within the run's own connection limit. The bound
    is told from distributed's timeout, set to 600 s here, not from the clock: the run takes its limit (5 s) plus an
    interpreter start (2 s idle; the whole run took 26 s beside 8 busy processes on 2 cores and 32 s beside 10, past
    the 30 s bound this test had), and a run that used distributed's timeout would take 600 s."""
    from experiments.dask_executor import DASK_CONNECT_TIMEOUT_S
    cfg = study(tmp_path, reps=1, ns="[10]")
    for address in ("tcp://127.0.0.1:1", "not-an-address", ""):
        t0 = time.monotonic()
        res = run([cfg, "--executor", "dask", "--scheduler", address, "--out", tmp_path / "out"], tmp_path,
                  timeout=DISTRIBUTED_CONNECT_S // 2,
                  DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT=f"{DISTRIBUTED_CONNECT_S}s")
        took = time.monotonic() - t0
        assert res.returncode == 2, (address, res.stderr)
        assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr, res.stderr
        assert "scheduler" in res.stderr
        if address.startswith("tcp://"):
            assert f"within {DASK_CONNECT_TIMEOUT_S} s" in res.stderr, res.stderr
        assert took < DISTRIBUTED_CONNECT_S / 3, f"{address!r}: {took:.0f} s: distributed's connect timeout, not the run's"


@pytest.mark.parametrize("module", ["experiments.run", "experiments.report", "experiments.verify"])
def test_version(module, tmp_path):
    res = subprocess.run([sys.executable, "-m", module, "--version"], cwd=tmp_path, env=subprocess_env(),
                         capture_output=True, text=True, timeout=120)
    from importlib import metadata
    assert res.returncode == 0 and metadata.version("fitbench") in res.stdout


FILE_STUDY = '''name = "{name}"
title = "a study of a file"
kind = "grid"
seed = 1
repetitions = 1

[[datasets]]
file = "{file}"

[[methods]]
id = "circle.kasa"
'''


@pytest.mark.parametrize("place, extra, refused", [("out/filed/results.csv", [], True),
                                                   ("out/filed/figures/trace.csv", [], True),
                                                   ("out/paper/trace.csv", [], True),
                                                   ("out/paper/trace.csv", ["--no-report"], False),
                                                   ("out/data/trace.csv", ["--no-report"], False)])
def test_a_data_file_where_the_run_writes_is_refused_before_any_row(tmp_path, monkeypatch, capsys, place, extra,
                                                                    refused):
    """A study's data file in the folder the run writes (``OUT/STUDY``, ``OUT/paper`` when the report is built) is
    refused in one line before any row, the file unchanged: at ``OUT/STUDY/results.csv`` the measurement was replaced
    by the results table and the run then blamed the file's columns. Elsewhere in ``--out`` it is read."""
    trace = Path(__file__).resolve().parents[1] / "docs" / "examples" / "trace.csv"
    data = tmp_path / place
    data.parent.mkdir(parents=True)
    data.write_bytes(trace.read_bytes())
    (tmp_path / "filed.toml").write_text(FILE_STUDY.format(name="filed", file=place), encoding="utf-8")
    done = run_here(["filed.toml", "--jobs", "1", "--out", "out", *extra], tmp_path, monkeypatch, capsys)
    assert data.read_bytes() == trace.read_bytes()
    if refused:
        assert done.returncode == 2, done.stderr
        assert done.stderr.strip().splitlines() == [
            f"experiments.run: error: filed.toml datasets[0]: {data} is a data file in "
            f"{tmp_path / ('out/paper' if 'paper' in place else 'out/filed')}, which this run writes (--out out): "
            f"move the data out of it, or give another --out"], done.stderr
        assert not (tmp_path / "out" / "filed" / "rows.sqlite").exists()
    else:
        assert done.returncode == 0, done.stderr


def test_a_run_with_nothing_to_do_leaves_no_wal_files(tmp_path, monkeypatch, capsys):
    """A run into a folder whose rows and outputs are up to date reads its row store and leaves it as it was: no
    empty ``rows.sqlite-wal`` and ``rows.sqlite-shm`` beside it (a read-only connection left them after exit 0)."""
    cfg = study(tmp_path, reps=1, ns="[10]")
    for _ in range(2):
        assert run_here([cfg, "--jobs", "1", "--no-report", "--out", "out"], tmp_path, monkeypatch, capsys).returncode == 0
    assert sorted(p.name for p in (tmp_path / "out" / "faults").glob("rows.sqlite*")) == ["rows.sqlite"]
