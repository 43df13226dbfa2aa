"""``experiments.report`` and ``experiments.verify`` (also ``fitbench report`` / ``fitbench verify``) end as the other
fitbench commands do. Ctrl-C, SIGTERM and SIGHUP: one line, exit 130 / 143 / 129, no traceback, and the report folder
as it was (the report is built in a hidden folder and moved into place whole) or no verdict written; a signal arriving
while the report moves into place waits until all of it is there. A reader that goes (``| head -1``): the command
still ends, writes its report or verdict, and exits as it would have, without a word. Before, Ctrl-C was a
traceback with the previous report's files deleted, SIGTERM and SIGHUP killed the build half-way, and a closed
pipe was a BrokenPipeError traceback, exit 1, no verdict written."""
from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO, subprocess_env

#: a committed study: 25 rows, tables and a figure (its report builds in about 2 s)
STUDY = REPO / "results" / "circular_test"

ENTRIES = {"experiments": "from experiments import {module} as entry\nsys.exit(entry.main(sys.argv[1:]))\n",
           "fitbench": "from fitbench.cli import main\nsys.exit(main(['{command}', *sys.argv[1:]]))\n"}

#: a report whose build, once every file is staged, waits to be stopped
SLOW_REPORT = ("import sys, time\n"
               "from experiments import report\n"
               "real = report._build\n"
               "def staged_then_wait(*args, **kwargs):\n"
               "    got = real(*args, **kwargs)\n"
               "    print('staged', file=sys.stderr, flush=True)\n"
               "    time.sleep(120)\n"
               "    return got\n"
               "report._build = staged_then_wait\n")

#: a check that, comparing, waits to be stopped
SLOW_VERIFY = ("import sys, time\n"
               "from experiments import verify\n"
               "def comparing(*args, **kwargs):\n"
               "    print('comparing', file=sys.stderr, flush=True)\n"
               "    time.sleep(120)\n"
               "verify.verify = comparing\n")


def snapshot(folder: Path) -> dict | None:
    """{relative path: digest} of every file under ``folder`` (hidden ones too), None when it is not there."""
    if not folder.exists():
        return None
    return {p.relative_to(folder).as_posix(): hashlib.md5(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture
def results(tmp_path):
    """tmp_path/mine holding one finished study, and its report built in tmp_path/mine/paper."""
    shutil.copytree(STUDY, tmp_path / "mine" / STUDY.name)
    done = subprocess.run([sys.executable, "-m", "experiments.report", "--results", "mine"], cwd=tmp_path,
                          env=subprocess_env(), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return tmp_path / "mine"


def stopped(script: str, args, cwd: Path, name: str, wait_for: str):
    """Run ``script`` with ``args``, send it signal ``name`` once it printed ``wait_for`` on stderr; (exit status,
    stdout, the stderr lines after ``wait_for``)."""
    num = getattr(signal, name)
    proc = subprocess.Popen([sys.executable, "-c", script, *map(str, args)], cwd=cwd, env=subprocess_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(num, signal.SIG_DFL))   # as from a terminal
    try:
        assert proc.stderr.readline().strip() == wait_for
        proc.send_signal(num)
        out, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    return proc.returncode, out, [line for line in err.splitlines() if line.strip()]


def words(name: str) -> str:
    return "interrupted" if name == "SIGINT" else f"terminated ({name})"


@pytest.mark.parametrize("entry", ["experiments", "fitbench"])
@pytest.mark.parametrize("name", ["SIGINT", "SIGTERM", "SIGHUP"])
def test_a_stopped_report_leaves_the_folder_as_it_was(results, entry, name):
    """Stopped once every file of the new report is written (staged): one line, 128 + the signal, the previous report
    byte for byte with no file of the new one and no hidden folder left; a report folder it created is removed."""
    script = SLOW_REPORT + ENTRIES[entry].format(module="report", command="report")
    before = snapshot(results / "paper")
    code, out, err = stopped(script, ["--results", "mine"], results.parent, name, "staged")
    assert code == 128 + getattr(signal, name), (code, err)
    assert err == [f"experiments.report: {words(name)}; no report written (the folder is as it was)"], err
    assert out == "" and snapshot(results / "paper") == before
    if name == "SIGTERM":
        code, _, err = stopped(script, ["--results", "mine", "--out", "new"], results.parent, name, "staged")
        assert code == 143 and len(err) == 1, err
        assert not (results.parent / "new").exists()


def test_a_signal_while_the_report_moves_into_place_waits_for_all(results):
    """SIGTERM as the first file of the report replaces its target: the others follow, then the command stops with
    its line ('after the report was written') and 143; the folder holds the whole new report."""
    done = subprocess.run([sys.executable, "-m", "experiments.report", "--results", "mine", "--out", "expected"],
                          cwd=results.parent, env=subprocess_env(), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    shutil.rmtree(results / "paper")
    (results / "paper").mkdir()
    (results / "paper" / "report.md").write_text("OLD\n")
    script = ("import os, signal, sys\n"
              "real = os.replace\n"
              "def replace(a, b):\n"
              "    if '.report-build-' not in str(b):   # the first file of the built report onto its target\n"
              "        os.replace = real\n"
              "        os.kill(os.getpid(), signal.SIGTERM)\n"
              "    real(a, b)\n"
              "os.replace = replace\n" + ENTRIES["experiments"].format(module="report"))
    got = subprocess.run([sys.executable, "-c", script, "--results", "mine"], cwd=results.parent,
                         env=subprocess_env(), capture_output=True, text=True, timeout=300,
                         preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL))
    assert got.returncode == 143, got.stderr
    assert got.stderr.strip() == "experiments.report: terminated (SIGTERM) after the report was written", got.stderr
    new, expected = snapshot(results / "paper"), snapshot(results.parent / "expected")
    assert set(new) == set(expected) and new["report.md"] == expected["report.md"]


@pytest.mark.parametrize("entry", ["experiments", "fitbench"])
@pytest.mark.parametrize("name", ["SIGINT", "SIGTERM", "SIGHUP"])
def test_a_stopped_check_writes_no_verdict(results, entry, name):
    """experiments.verify --write-verdict stopped while comparing: one line, 128 + the signal, no verdict written."""
    shutil.copytree(results, results.parent / "again")
    script = SLOW_VERIFY + ENTRIES[entry].format(module="verify", command="verify")
    code, out, err = stopped(script, ["--results", "mine", "--against", "again", "--write-verdict"], results.parent,
                             name, "comparing")
    assert code == 128 + getattr(signal, name), (code, err)
    assert err == [f"experiments.verify: {words(name)}; no verdict written"], err
    assert out == "" and not (results / "verify.json").exists()


@pytest.mark.parametrize("command", ["report", "verify"])
@pytest.mark.parametrize("streams", ["stdout", "stdout and stderr"])
def test_a_reader_closing_the_pipe_early_still_gets_the_outputs(results, command, streams):
    """`fitbench report | head -1`, `python -m experiments.verify --write-verdict 2>&1 | head -1`: the reader has gone
    before the command prints; it still ends, writes the report (the same as a build printing everything) or the
    verdict, and exits as it would have (0: the two runs agree), without a word."""
    shutil.copytree(results, results.parent / "again")
    expected = snapshot(results / "paper")
    shutil.rmtree(results / "paper")
    args = {"report": ["--results", "mine"], "verify": ["--results", "mine", "--against", "again", "--write-verdict"]}
    for cmd in ([sys.executable, "-m", f"experiments.{command}"], [sys.executable, "-m", "fitbench", command]):
        read, write = os.pipe()
        os.close(read)   # the reader has gone before the command prints
        try:
            done = subprocess.run([*cmd, *args[command]], cwd=results.parent, env=subprocess_env(), stdout=write,
                                  stderr=write if streams != "stdout" else subprocess.PIPE, timeout=300)
        finally:
            os.close(write)
        assert done.returncode == 0 and not done.stderr, done.stderr
        if command == "report":
            assert snapshot(results / "paper") == expected
            shutil.rmtree(results / "paper")
        else:
            assert (results / "verify.json").is_file()
            (results / "verify.json").unlink()


def test_a_report_that_cannot_be_moved_into_place_is_one_line_and_leaves_the_folder_as_it_was(results, monkeypatch):
    """A target of the report that is not a regular file (report.html a folder): refused in one line, exit 2, before
    any file replaced its target (the previous report whole, no hidden folder left); a new --out removed again."""
    from cli_calls import call
    from experiments import report
    monkeypatch.chdir(results.parent)
    paper = results / "paper"
    (paper / "report.html").unlink()
    (paper / "report.html").mkdir()
    before = snapshot(paper)
    got = call(report.main, "--results", "mine")
    assert got.returncode == 2 and got.stdout == "", got
    assert got.stderr.startswith("experiments.report: error: cannot write the report into mine/paper: ") and \
        "report.html: is a folder, not a regular file" in got.stderr and len(got.stderr.splitlines()) == 1, got.stderr
    assert got.stderr.rstrip().endswith("no report written (the folder is as it was)"), got.stderr
    assert snapshot(paper) == before and sorted(p.name for p in paper.iterdir() if p.name.startswith("."))\
        == [".report-build.json"]
    monkeypatch.setattr(report, "_move_into_place", lambda *a: (_ for _ in ()).throw(OSError(28, "No space left")))
    got = call(report.main, "--results", "mine", "--out", "new")
    assert got.returncode == 2 and "No space left" in got.stderr and not (results.parent / "new").exists(), got
