"""The experiments engine: configs, determinism across runs and executors, resume, retries."""
import json
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap

import pandas as pd
import pytest

import methods
from conftest import REPO, quick_study, while_storing_rows
from experiments import config as configs
from experiments.study import ConfigError
from experiments.run import main, run_study
from plugin_methods import registered
from results_csv import non_timing

TINY = """
name = "{name}"
title = "tiny"
kind = "grid"
seed = 11
repetitions = {reps}

[[datasets]]
generator = "circle"
params = {{ center = [3.0, -2.0], radius = 5.0, noise = 0.01 }}
grid = {{ n = [12, 40], arc_deg = [360.0, 120.0] }}

[[datasets]]
published = "roundness_set2"

[[methods]]
id = "circle.kasa"
[[methods]]
id = "circle.gauss_newton"
[[methods]]
id = "circle.nelder_mead"
grid = {{ backend = ["scipy", "nlopt"] }}
[[methods]]
id = "circle.minimum_zone"
"""


def tiny(tmp_path, name="tiny", reps=3, extra=""):
    path = tmp_path / f"{name}.toml"
    path.write_text(TINY.format(name=name, reps=reps) + extra)
    return path


def table(out, name="tiny"):
    return non_timing(out / name / "results.csv")


def test_list_and_defaults(capsys):
    assert main(["--list"]) == 0
    out = capsys.readouterr().out
    for name in ("published", "noise", "convergence", "scaling", "ellipse_angle", "circular_test", "nist_circle",
                 "multilateration"):
        assert name in out
    assert {"published", "noise", "convergence", "scaling"} <= {
        n for n in configs.available() if configs.load(n).get("default")}


def test_list_into_a_closed_pipe_ends_quietly():
    """`python -m experiments.run --list | head -1`: the reader closed the pipe; the listing ends with exit 0 and
    nothing on stderr, as `fitbench list | head` (it said "cannot write: Broken pipe; the finished rows are
    kept ..." with exit 2)."""
    read, write = os.pipe()
    os.close(read)   # the reader has gone before anything is written
    try:
        done = subprocess.run([sys.executable, "-m", "experiments.run", "--list"], cwd=REPO, stdout=write,
                              stderr=subprocess.PIPE, text=True, timeout=120)
    finally:
        os.close(write)
    assert done.returncode == 0 and done.stderr == ""


@pytest.mark.slow
def test_two_runs_identical_and_rows_complete(tmp_path):
    cfg = tiny(tmp_path)
    run_study(str(cfg), tmp_path / "a", jobs=1, log=lambda *a: None)
    run_study(str(cfg), tmp_path / "b", jobs=2, log=lambda *a: None)
    a, b = table(tmp_path / "a"), table(tmp_path / "b")
    pd.testing.assert_frame_equal(a, b)
    # 4 synthetic grid points x 3 repetitions + 1 published set, x 5 method runs
    assert len(a) == (4 * 3 + 1) * 5
    assert {"data_n", "data_arc_deg", "param_backend", "center_error", "radius_error", "form_error",
            "residual_rms", "status", "iterations", "nfev"} <= set(a.columns)
    full = pd.read_csv(tmp_path / "a" / "tiny" / "results.csv")
    assert {"time_median_s", "time_iqr_s", "time_rounds"}.isdisjoint(full.columns)  # no [timing] in this config
    meta = json.loads((tmp_path / "a" / "tiny" / "meta.json").read_text())
    for key in ("git_commit", "git_dirty", "versions", "blas", "cpu", "date", "config", "config_hash"):
        assert key in meta
    assert {"numpy", "scipy", "cvxpy", "clarabel", "nlopt"} <= set(meta["versions"])
    assert (tmp_path / "a" / "tiny" / "summary.md").read_text().startswith("# tiny")


def test_every_method_sees_the_same_noise(tmp_path):
    run_study(str(tiny(tmp_path)), tmp_path, jobs=1, log=lambda *a: None)
    df = table(tmp_path)
    syn = df[df["dataset"] == "circle"]
    # the same data stream gives the same data: Kåsa is deterministic, so its circle per stream is unique
    assert syn.groupby("data_stream")["data_n"].nunique().max() == 1
    kasa = syn[syn["method"] == "circle.kasa"].set_index("data_stream")["radius"]
    run_study(str(tiny(tmp_path, reps=3)), tmp_path / "again", jobs=2, force=True, log=lambda *a: None)
    again = table(tmp_path / "again")
    pd.testing.assert_series_equal(kasa, again[(again["dataset"] == "circle") & (again["method"] == "circle.kasa")]
                                   .set_index("data_stream")["radius"])


@pytest.mark.slow
def test_interrupted_run_resumes_to_the_uninterrupted_rows(tmp_path):
    """Ctrl-C (SIGINT) in the middle of a run; the next run finishes without redoing or duplicating."""
    cfg = tiny(tmp_path, reps=25)
    run_study(str(cfg), tmp_path / "whole", jobs=1, log=lambda *a: None)
    total = (4 * 25 + 1) * 5
    for attempt in range(3):  # its rows take 1 s here: started again only if this test slept through all of them
        out = tmp_path / f"cut{attempt}"
        proc = subprocess.Popen([sys.executable, "-m", "experiments.run", str(cfg), "--out", str(out), "--jobs", "1"],
                                cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        db = out / "tiny" / "rows.sqlite"
        if while_storing_rows(proc, db, 30, total, lambda: proc.send_signal(signal.SIGINT), group=False) is not None:
            break
        proc.kill()
        proc.communicate(timeout=60)
    else:
        raise AssertionError(f"the run stored all its {total} rows before this test could interrupt it, 3 times")
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "interrupted" in err and "Traceback" not in err
    assert not (out / "tiny" / "results.csv").exists()  # nothing half-written
    with sqlite3.connect(db) as con:
        partial = con.execute("SELECT COUNT(*) FROM rows").fetchone()[0]
    assert 30 <= partial < total
    logged = []
    run_study(str(cfg), out, jobs=1, log=logged.append)
    assert any(f"{partial} already stored, {total - partial} to run" in line for line in logged)
    pd.testing.assert_frame_equal(table(tmp_path / "whole"), table(out))


_crash = {"on": True}


def _flaky(points):
    """Kåsa's fit, or a crash while the switch is on."""
    if _crash["on"]:
        raise RuntimeError("simulated crash")
    return methods.get("circle.kasa").func(points)


@pytest.fixture
def flaky_method():
    """A method registered for one test only (it must not leak into 'circle.*' of other tests)."""
    with registered({"circle.test_flaky": _flaky}, kind="closed form", summary="crashes while _crash['on'] (test)",
                    reference="fitbench test"):
        yield


def test_crashed_rows_are_recorded_and_retried(tmp_path, flaky_method):
    path = tmp_path / "flaky.toml"
    path.write_text(textwrap.dedent('''
        name = "flaky"
        title = "flaky"
        kind = "grid"
        repetitions = 2
        [[datasets]]
        generator = "circle"
        params = { n = 10, noise = 0.01 }
        [[methods]]
        id = "circle.kasa"
        [[methods]]
        id = "circle.test_flaky"
    '''))
    _crash["on"] = True
    run_study(str(path), tmp_path, jobs=1, log=lambda *a: None)
    df = pd.read_csv(tmp_path / "flaky" / "results.csv")
    bad = df[df["method"] == "circle.test_flaky"]
    assert set(bad["status"]) == {"error"} and bad["message"].str.contains("simulated crash").all()
    assert set(df[df["method"] == "circle.kasa"]["status"]) == {"ok"}
    _crash["on"] = False
    logged = []
    run_study(str(path), tmp_path, jobs=1, log=logged.append)
    assert any("2 failed before, retried" in line for line in logged)
    df = pd.read_csv(tmp_path / "flaky" / "results.csv")
    assert set(df["status"]) == {"ok"} and len(df) == 4


def test_a_table_of_rows_without_a_result_names_why(tmp_path, flaky_method):
    """A declared table whose metric no row has (every fit failed) says that no row has a result, with the statuses
    and the most frequent message (was only: no column 'radius_error' in the rows)."""
    path = tmp_path / "allfail.toml"
    path.write_text(textwrap.dedent('''
        name = "allfail"
        title = "every fit fails"
        repetitions = 2
        [[datasets]]
        source = "circle"
        params = { n = 10, noise = 0.01 }
        [[methods]]
        id = "circle.test_flaky"
        [[tables]]
        caption = "Radius RMSE"
        rows = ["method"]
        values = "radius_error"
        aggregate = "rmse"
        unit = "mm"
    '''))
    _crash["on"] = True
    with pytest.raises(ConfigError) as info:
        run_study(str(path), tmp_path, jobs=1, log=lambda *a: None)
    msg = str(info.value)
    assert "no column 'radius_error'" in msg and "no row has a result (2 error; most often: RuntimeError: simulated " \
        "crash)" in msg and "\n" not in msg, msg


@pytest.mark.parametrize("body, match", [
    ('title = "t"\nkind = "grid"\n', "missing required key 'name'"),
    ('name = "bad"\ntitle = "t"\nkind = "nope"\n', "unknown kind 'nope'"),
    ('name = "bad"\ntitle = "t"\nkind = "grid"\n[[datasets]]\ngenerator = "square"\n', r"datasets\[0\].*unknown generator 'square'"),
    ('name = "bad"\ntitle = "t"\nkind = "grid"\n[[datasets]]\ngenerator = "circle"\nparams = { radios = 1 }\n',
     r"datasets\[0\].*generator 'circle' has no parameter 'radios'"),
    ('name = "bad"\ntitle = "t"\nkind = "grid"\n[[datasets]]\ngenerator = "circle"\ngrid = { n = 5 }\n',
     r"datasets\[0\]: grid.n: must be an array"),
    ('name = "bad"\ntitle = "t"\nkind = "grid"\n[[methods]]\nid = "circle.gauss_newtn"\n',
     r"methods\[0\]: unknown method id 'circle.gauss_newtn'; did you mean circle.gauss_newton"),
    ('name = "bad"\ntitle = "t"\nkind = "grid"\n[[methods]]\nid = "circle.kasa"\nparams = { tol = 1 }\n',
     r"methods\[0\]: circle.kasa has no parameter 'tol'"),
    ('name = "bad"\ntitle = "t"\nkind = "grid"\nrepetitions = 0\n', "repetitions: must be >= 1, got 0"),
    ('name = "bad"\ntitle = "t"\nkind = "grid"\n[[datasets]]\npublished = "roundness_set9"\n',
     "unknown published data set 'roundness_set9'"),
    ('name = "bad"\ntitle = "t"\nkind = "grid"\nseed = "x"\n', "seed: must be an integer"),
    ('name = "bad"\ntitle = "t"\nkind = grid\n', "not valid TOML"),
])
def test_bad_config_names_file_key_problem(tmp_path, body, match, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(body)
    assert main([str(path), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.toml" in err[0]
    import re
    assert re.search(match, err[0]), err[0]


def test_unknown_study_and_bad_flags(capsys):
    assert main(["no_such_study"]) == 2
    assert "unknown study" in capsys.readouterr().err
    assert main(["--jobs", "0", "published"]) == 2
    assert main(["--scheduler", "tcp://x:1", "published"]) == 2


@pytest.mark.parametrize("given, said", [
    ("{tmp}/nope/x.toml", "no such file: {tmp}/nope/x.toml"),
    ("x.toml", "no such file: x.toml"),
    ("noise.toml", "no such file: noise.toml; the built-in study 'noise' is run by its name"),
    ("{tmp}/notes.txt", "{tmp}/notes.txt: not a .toml file"),
])
def test_a_study_path_that_is_no_toml_file_is_one_line(tmp_path, capsys, monkeypatch, given, said):
    """A name that is a path (a separator, or .toml) names the file that is missing, not the built-in studies."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "notes.txt").write_text("x")
    assert main([given.format(tmp=tmp_path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(f"experiments.run: error: {said.format(tmp=tmp_path)}"), err
    assert "unknown study" not in err and not (tmp_path / "out").exists()


SMALL = """name = "small"
title = "small"
[[datasets]]
source = "circle"
params = { n = 12, noise = 0.01 }
[[methods]]
id = "circle.kasa"
"""


def test_main_releases_its_out_lock_when_it_returns(tmp_path, capsys):
    """``experiments.run.main`` (the Python API) called twice in one process writes to the same --out twice; the
    lock it holds while it runs still keeps another process out, and is free again when that process ends."""
    import fcntl
    from experiments import run as runner
    study, out = tmp_path / "small.toml", tmp_path / "out"
    study.write_text(SMALL)
    args = [str(study), "--out", str(out), "--jobs", "1", "--no-report"]
    assert main(args) == 0
    assert main(args) == 0, capsys.readouterr().err  # was: "--out ... is in use by another experiments.run (pid <its own>)"
    assert not runner._LOCKS
    with open(out / runner.LOCK_NAME, "a+") as fh:  # nothing of this process holds the folder any more
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    holder = subprocess.Popen([sys.executable, "-c", "import sys; from pathlib import Path; from experiments import run; "
                               f"run.lock_out(Path({str(out)!r})); print('locked', flush=True); sys.stdin.read()"],
                              cwd=REPO, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        capsys.readouterr()
        assert main(args) == 2
        err = capsys.readouterr().err.strip()
        assert "in use by another experiments.run" in err and f"pid {holder.pid}" in err, err
    finally:
        holder.communicate("", timeout=60)
    assert main(args) == 0


# The quick studies run once per test session (conftest.quick_study; the report's, the multilateration and the study
# contract's tests read the same runs): with one job in this process, or, with --system, the session's whole quick run
# with --jobs 2 (tests/test_cpu_independence.py's, compared with results/quick) rather than the same rows a second
# time; the same rows either way (the executors' equality is test_two_runs_identical_and_rows_complete's and
# test_engine's).
@pytest.mark.slow
def test_quick_published_study(tmp_path_factory):
    target = quick_study(tmp_path_factory, "published")
    rows = pd.read_csv(target / "results.csv")
    meta = json.loads((target / "meta.json").read_text())
    assert set(rows["status"]) == {"ok"}
    gn = rows[(rows.dataset == "roundness_set2") & (rows.method == "circle.gauss_newton")]
    assert round(float(gn.form_error.iloc[0]), 4) == 1.7487
    found = {(f["dataset"], f["column"]): f for f in meta["findings"]["published_vs_reproduced"]}
    for col in ("MIC", "MCC", "Voronoi (minimum zone)", "LSQ (paper's Gauss-Newton)"):
        assert found[("roundness_set2", col)]["reproduced"]
    assert not found[("roundness_set1", "LSQ (paper's Gauss-Newton)")]["reproduced"]
    assert found[("roundness_set1", "LSQ (paper's Gauss-Newton)")]["explained_by_rounding"]
    mc = rows["dataset"].str.endswith("(rounding Monte Carlo)")
    assert "time_median_s" in rows and rows.loc[~mc, "time_median_s"].notna().all()
    # the rounding Monte Carlo is one engine row per published figure (cached like every fit), quick: 100 fits each
    assert mc.sum() == len(meta["findings"]["published_vs_reproduced"]) and set(rows.loc[mc, "rounding_samples"]) == {100}
    assert (rows.loc[mc, "rounding_min"] <= rows.loc[mc, "rounding_max"]).all()


@pytest.mark.slow
@pytest.mark.parametrize("name", ["noise", "convergence", "ellipse_angle", "scaling", "circular_test", "positioning",
                                  "magnification", "multilateration"])
def test_quick_default_studies_run(tmp_path_factory, name):
    target = quick_study(tmp_path_factory, name)
    meta = json.loads((target / "meta.json").read_text())
    assert meta["n_rows"] > 0 and meta["findings"] and meta["quick"] is True
    manifest = json.loads((target / "report.json").read_text())  # what the report renders (the study contract)
    assert manifest["tables"] and manifest["figures"] and manifest["quick"] is True
    for t in manifest["tables"]:
        assert len(pd.read_csv(target / t["file"])) > 0 and t["caption"]
    # a findings paragraph generated from the run's numbers (a digit in it), never a template left unfilled
    findings = manifest["findings"]
    assert findings and "not filled" not in findings and any(ch.isdigit() for ch in findings), findings
    for f in manifest["figures"]:
        assert (target / f["file"]).stat().st_size > 10_000 and f["caption"]


def test_workers_get_one_blas_thread_and_the_environment_is_restored(monkeypatch):
    from experiments.executors import BLAS_THREAD_VARS, _one_blas_thread_per_worker
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", "3")                 # a user's choice is kept
    with _one_blas_thread_per_worker():
        assert os.environ["OPENBLAS_NUM_THREADS"] == "1" and os.environ["OMP_NUM_THREADS"] == "3"
    assert "OPENBLAS_NUM_THREADS" not in os.environ and os.environ["OMP_NUM_THREADS"] == "3"
    assert "MKL_NUM_THREADS" in BLAS_THREAD_VARS
