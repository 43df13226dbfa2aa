"""A plugin whose import ends the process (``sys.exit(0)``, ``SystemExit(3)``) or raises another ``BaseException``
(a ``KeyboardInterrupt`` that is no signal's) is a plugin that failed to load: skipped with its one warning line, the
command goes on and ends as it would without it (before: ``fitbench list``, ``experiments.run``, ``--list`` and
``experiments.verify`` exited 0 having done nothing). The user's own Ctrl-C (a real SIGINT) during a plugin's import
still stops the command with its line and status 130."""
import csv

import pytest

from conftest import default_sigint, install_plugin, run_python

EXIT0 = '''
import sys
from methods import register
from methods.results import circle_result


@register("circle.exiter", kind="closed form", summary="registers, then its import exits", reference="fitbench test")
def exiter(points):
    return circle_result(points, points[0], 1.0, converged=True, message="closed form")


sys.exit(0)
'''

EXIT3 = '''
raise SystemExit(3)
'''

INTERRUPT = '''
raise KeyboardInterrupt("the plugin's own, no signal")
'''

#: (entry point, its module) of each group: three failing imports of methods, one of data sources
FAILING = {"fitbench.methods": {"exit_zero": "fitbench_exit0", "exit_three": "fitbench_exit3",
                                "interrupt": "fitbench_interrupt"},
           "fitbench.datasets": {"exit_source": "fitbench_exit0"}}

STUDY = ('name = "exitplug"\ntitle = "a study beside plugins whose import exits"\nseed = 1\nrepetitions = 2\n'
         '[[datasets]]\nsource = "circle"\nparams = { radius = 5.0, noise = 0.01, n = 12 }\n'
         '[[methods]]\nid = "circle.kasa"\n[[methods]]\nid = "circle.gauss_newton"\n')


@pytest.fixture(scope="module")
def exit_site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("exit"), "fitbench-exit-plugin",
                          {"fitbench_exit0": EXIT0, "fitbench_exit3": EXIT3, "fitbench_interrupt": INTERRUPT},
                          FAILING, version="0.5")


def check_warnings(stderr: str, groups=tuple(FAILING)) -> None:
    """One line per failing entry point of the ``groups`` loaded, naming it and what it raised; no traceback."""
    assert "Traceback" not in stderr, stderr
    lines = [line for line in stderr.splitlines() if "fitbench-exit-plugin" in line]
    assert len(lines) == sum(len(FAILING[g]) for g in groups), stderr
    for group in groups:
        eps = FAILING[group]
        for ep, module in eps.items():
            line = [line for line in lines if f"plugin {ep!r} (entry point {module!r} of group {group!r}" in line]
            assert len(line) == 1, (ep, stderr)
            raised = {"fitbench_exit0": "SystemExit: 0", "fitbench_exit3": "SystemExit: 3",
                      "fitbench_interrupt": "KeyboardInterrupt: the plugin's own, no signal"}[module]
            assert line[0].startswith("fitbench: warning: "), line[0]   # not warnings' format: file, line, source
            assert f"failed to load and is skipped: {raised}; fix or uninstall that distribution" in line[0], line[0]


@pytest.mark.parametrize("command, groups", [
    (("-m", "fitbench", "list"), ["fitbench.methods"]),
    pytest.param(("-m", "experiments.run", "--list"), list(FAILING), marks=pytest.mark.slow)])
def test_a_plugin_ending_its_import_leaves_the_listings_whole(exit_site, command, groups):
    without = run_python(*command)
    assert without.returncode == 0 and len(without.stdout.splitlines()) > 5, without.stderr
    out = run_python(*command, path_first=[exit_site])
    assert (out.returncode, out.stdout) == (0, without.stdout), out.stdout + out.stderr
    assert "circle.exiter" not in out.stdout
    check_warnings(out.stderr, groups)


def _rows(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return [(r["method"], r["repetition"], r["status"], r["radius"]) for r in csv.DictReader(fh)]


@pytest.mark.slow
def test_a_plugin_ending_its_import_does_not_end_run_or_verify(exit_site, tmp_path):
    """experiments.run stores the same rows as without the plugin; experiments.verify runs the study again and
    compares it with that run (before: both exited 0 having done nothing, no output folder, no verdict)."""
    study = tmp_path / "exitplug.toml"
    study.write_text(STUDY, encoding="utf-8")
    base = run_python("-m", "experiments.run", study, "--out", tmp_path / "base", "--no-report", "--jobs", "1")
    assert base.returncode == 0, base.stderr
    out = run_python("-m", "experiments.run", study, "--out", tmp_path / "with", "--no-report", "--jobs", "1",
                     path_first=[exit_site])
    assert out.returncode == 0, out.stdout + out.stderr
    check_warnings(out.stderr)
    rows = _rows(tmp_path / "with" / "exitplug" / "results.csv")
    assert rows == _rows(tmp_path / "base" / "exitplug" / "results.csv") and len(rows) == 4
    verify = run_python("-m", "experiments.verify", "--results", tmp_path / "base", "--jobs", "1", path_first=[exit_site])
    assert verify.returncode == 0, verify.stdout + verify.stderr
    assert "exitplug: agree (4 rows" in verify.stdout, verify.stdout
    check_warnings(verify.stderr)


SIGINT_ON_IMPORT = '''
"""Ctrl-C while this plugin is being imported: a real SIGINT to its own process, then work that a Ctrl-C interrupts;
FITBENCH_TEST_SWALLOW=exit: the plugin catches that KeyboardInterrupt and ends its import with sys.exit(0); =go_on: it
catches it and goes on, its import succeeding."""
import os
import signal
import sys
import time

try:
    os.kill(os.getpid(), signal.SIGINT)
    for _ in range(300):
        time.sleep(0.01)
except KeyboardInterrupt:
    if os.environ.get("FITBENCH_TEST_SWALLOW") == "exit":
        sys.exit(0)
    if os.environ.get("FITBENCH_TEST_SWALLOW") != "go_on":
        raise
'''


@pytest.fixture(scope="module")
def sigint_site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("sigint"), "fitbench-sigint-plugin", {"fitbench_sigint": SIGINT_ON_IMPORT},
                          {"fitbench.methods": {"sigint": "fitbench_sigint"}}, version="0.1")


@pytest.mark.parametrize("command, line, swallow", [
    *[(("-m", "fitbench", "list"), "fitbench: interrupted", swallow) for swallow in ("", "exit", "go_on")],
    (("-m", "experiments.run", "--list"), "experiments.run: interrupted", "")])
def test_the_user_s_ctrl_c_while_a_plugin_loads_still_stops_the_command(sigint_site, command, line, swallow):
    """Also when the plugin catches the interrupt and exits (its SystemExit was raised while handling it), or
    catches it and goes on (the user's Ctrl-C is not lost)."""
    out = run_python(*command, path_first=[sigint_site], FITBENCH_TEST_SWALLOW=swallow, preexec_fn=default_sigint)
    assert out.returncode == 130, out.stdout + out.stderr
    assert line in out.stderr and "Traceback" not in out.stderr, out.stderr
    assert "failed to load" not in out.stderr, out.stderr


def install_package_plugin(workdir, init_code: str):
    """A plugin that is a package (entry point ``fitbench_exitpkg.methods``) whose ``__init__`` runs ``init_code``."""
    from pip_target import pip_install, write_pyproject
    src = workdir / "src"
    (src / "fitbench_exitpkg").mkdir(parents=True)
    (src / "fitbench_exitpkg" / "__init__.py").write_text(init_code)
    (src / "fitbench_exitpkg" / "methods.py").write_text("X = 1\n")
    write_pyproject(src, "fitbench-exitpkg",
                    '[project.entry-points."fitbench.methods"]\npkg = "fitbench_exitpkg.methods"\n'
                    '[tool.setuptools]\npackages = ["fitbench_exitpkg"]\n')
    return pip_install(src, workdir / "site")


@pytest.mark.slow
@pytest.mark.parametrize("init_code, raised", [("import sys\nsys.exit(0)\n", "SystemExit: 0"),
                                               ("raise RuntimeError('boom in the package')\n",
                                                "RuntimeError: boom in the package")])
def test_a_plugin_package_failing_on_import_does_not_end_the_run(tmp_path, init_code, raised):
    """A plugin's entry point in a package whose ``__init__`` fails: the run warns once and writes its results. Before,
    the hash of the study's outputs looked for the failed plugin's module, which imports its package again: the run
    ended at that point with exit 0 and no results (sys.exit) or with a traceback (RuntimeError)."""
    site = install_package_plugin(tmp_path, init_code)
    study = tmp_path / "exitplug.toml"
    study.write_text(STUDY.replace("repetitions = 2", "repetitions = 1"), encoding="utf-8")
    out = run_python("-m", "experiments.run", study, "--out", tmp_path / "out", "--no-report", "--jobs", "1",
                     path_first=[site])
    assert out.returncode == 0 and "Traceback" not in out.stderr, out.stdout + out.stderr
    assert len(_rows(tmp_path / "out" / "exitplug" / "results.csv")) == 2, out.stdout + out.stderr
    lines = [line for line in out.stderr.splitlines() if "fitbench-exitpkg" in line]
    assert len(lines) == 1 and f"failed to load and is skipped: {raised};" in lines[0], out.stderr
