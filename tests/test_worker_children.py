"""Processes a method starts do not outlive the run: a local worker leads a process group of its own, which the
processes its methods start join, and the run ends that group with the worker: when the run is done, and when it
kills the worker of a row past its time limit. (A ``sleep`` a plugin method started, and the ``sleep`` a shell it
started started, were alive with parent 1 after the run had ended.)"""
import contextlib
import os
import signal

import pytest

from conftest import install_plugin, run_python
from study_kinds import circle_study

SPAWNER = '''
import os
import subprocess
import time

from methods import register
from methods.results import circle_result


def _start_children():
    """A child (sleep 60) and a grandchild (sleep 61, started by a shell): their ids go to $FITBENCH_TEST_PIDS."""
    out = os.environ["FITBENCH_TEST_PIDS"]
    child = subprocess.Popen(["sleep", "60"], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
    shell = subprocess.Popen(["sh", "-c", 'sleep 61 </dev/null >/dev/null 2>&1 & echo $! >> "$1"; wait', "sh", out],
                             stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(out, "a") as fh:
        fh.write(f"{child.pid}\\n{shell.pid}\\n")
    deadline = time.monotonic() + 10
    while len(open(out).read().split()) < 3 and time.monotonic() < deadline:
        time.sleep(0.01)


@register("circle.spawns_children", kind="closed form", summary="leaves a child and a grandchild running",
          reference="fitbench test")
def spawns_children(points):
    _start_children()
    c = points.mean(axis=0)
    return circle_result(points, c, float(((points - c) ** 2).sum(axis=1).mean() ** 0.5), converged=True,
                         message="closed form")


@register("circle.spawns_and_hangs", kind="closed form", summary="starts children, then never returns",
          reference="fitbench test")
def spawns_and_hangs(points):
    _start_children()
    time.sleep(600)
'''


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("spawner"), "fitbench-spawner", {"fitbench_spawner": SPAWNER},
                          {"fitbench.methods": {"spawner": "fitbench_spawner"}})


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:   # a zombie (ended, not yet reaped by its new parent) is no running process
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return True


def _run(site, tmp_path, method: str, *options):
    study = circle_study(tmp_path, "spawn", "A method that starts processes", ["circle.kasa", method], repetitions=1)
    pids_file = tmp_path / "pids"
    proc = run_python("-m", "experiments.run", study, "--out", tmp_path / "out", "--jobs", "1", "--no-report",
                      *options, path_first=[site], FITBENCH_TEST_PIDS=str(pids_file), timeout=120)
    pids = [int(p) for p in pids_file.read_text().split()] if pids_file.exists() else []
    return proc, pids


def _check_ended(pids):
    left = [p for p in pids if _alive(p)]
    for p in left:   # the test's own processes: not left behind whatever the outcome
        with contextlib.suppress(ProcessLookupError):
            os.kill(p, signal.SIGKILL)
    assert len(pids) == 3 and not left, f"still running after the run: {left} of {pids}"


@pytest.mark.skipif(not hasattr(os, "killpg") or not os.path.isdir("/proc"), reason="POSIX process groups, /proc")
def test_a_method_s_children_end_with_the_run(site, tmp_path):
    proc, pids = _run(site, tmp_path, "circle.spawns_children")
    assert proc.returncode == 0, proc.stderr
    _check_ended(pids)


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(os, "killpg") or not os.path.isdir("/proc"), reason="POSIX process groups, /proc")
def test_a_method_s_children_end_with_the_worker_killed_at_the_time_limit(site, tmp_path):
    # a limit that circle.kasa's row (a spawned worker's first, with the plugin's import) keeps on a loaded machine:
    # at 1 s both rows of a CI run under load ended as timeouts
    proc, pids = _run(site, tmp_path, "circle.spawns_and_hangs", "--row-timeout", "4")
    assert proc.returncode == 0, proc.stderr
    assert "timeout" in (tmp_path / "out" / "spawn" / "results.csv").read_text()
    _check_ended(pids)


def test_a_worker_outside_the_terminal_s_group_is_not_stopped_by_writing_to_it():
    """A worker leads its own process group, a background group of the terminal: under `stty tostop` a write to the
    terminal (a method's warning) would stop it by SIGTTOU and its chunk would never return; it ignores SIGTTOU and
    SIGTTIN."""
    from conftest import run_python
    out = run_python("-c", "import signal; from experiments import localworkers; localworkers._lead_own_group(); "
                           "print(signal.getsignal(signal.SIGTTOU) is signal.SIG_IGN, "
                           "signal.getsignal(signal.SIGTTIN) is signal.SIG_IGN)")
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "True"]
