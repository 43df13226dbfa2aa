"""What reaches the terminal besides a command's answer: with ``--json`` stdout carries the JSON object alone,
whatever a plugin prints when it is imported (Python's print or a write to descriptor 1)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import install_plugin, run_python

CHATTY = '''
import os
import sys

print("chatty plugin imported: hello on stdout")
sys.stdout.flush()
os.write(1, b"chatty plugin: a C library's banner on descriptor 1\\n")

from methods import register
from methods.results import circle_result


@register("circle.chatty_first_point", kind="closed form", summary="prints when imported", reference="fitbench test")
def chatty_first_point(points):
    return circle_result(points, points[0], 1.0, converged=True, message="closed form")
'''


@pytest.fixture(scope="module")
def chatty_site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("chatty"), "fitbench-chatty-plugin", {"fitbench_chatty": CHATTY},
                          {"fitbench.methods": {"chatty": "fitbench_chatty"}})


@pytest.fixture(scope="module")
def profile(tmp_path_factory):
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    p = tmp_path_factory.mktemp("profile") / "ring.csv"
    p.write_text("x,y\n" + "\n".join(f"{10 * np.cos(a) + 1e-3 * np.cos(3 * a):.7f},{10 * np.sin(a):.7f}" for a in t) + "\n")
    return p


@pytest.mark.parametrize("command, loads_plugins", [(("list",), True), (("fit", "circle.chatty_first_point", "{p}"), True),
                                                    (("fit", "circle.kasa", "{p}"), False), (("roundness", "{p}"), False)])
def test_json_stdout_is_the_json_alone_when_a_plugin_prints_at_import(chatty_site, profile, command, loads_plugins):
    """With --json, stdout is the JSON alone: what a plugin prints when it is imported (Python's print and descriptor
    1) goes to stderr. A command that needs only built-in methods imports no plugin at all."""
    args = [a.format(p=profile) for a in command]
    out = run_python("-m", "fitbench", *args, "--json", path_first=[chatty_site])
    assert out.returncode == 0, out.stderr
    json.loads(out.stdout)                                   # the whole of stdout is one JSON document
    printed = "chatty plugin imported" in out.stderr and "descriptor 1" in out.stderr
    assert printed == loads_plugins, out.stderr


# ------------------------------------------------------------------------ Ctrl-C
SLEEPY = '''
import sys
import time

from methods import register
from methods.results import circle_result


@register("circle.sleepy", kind="closed form", summary="waits to be interrupted", reference="fitbench test")
def sleepy(points):
    print("sleepy: started", file=sys.stderr, flush=True)
    time.sleep(60)
    return circle_result(points, points[0], 1.0, converged=True, message="closed form")
'''


@pytest.fixture(scope="module")
def sleepy_site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("sleepy"), "fitbench-sleepy-plugin", {"fitbench_sleepy": SLEEPY},
                          {"fitbench.methods": {"sleepy": "fitbench_sleepy"}})


@pytest.mark.parametrize("json_out", [False, True])
def test_ctrl_c_is_one_line_and_status_130(sleepy_site, profile, json_out):
    import signal
    import subprocess
    import sys
    from conftest import REPO, subprocess_env
    cmd = [sys.executable, "-m", "fitbench", "fit", "circle.sleepy", str(profile), *(["--json"] if json_out else [])]
    # as from a terminal: SIGINT not ignored (a process started with it ignored, as a test worker may be, keeps it
    # ignored and Python installs no KeyboardInterrupt handler)
    proc = subprocess.Popen(cmd, cwd=REPO, env=subprocess_env(sleepy_site), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        assert proc.stderr.readline().strip() == "sleepy: started"    # the method runs: interrupt it there
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert err.strip() == "fitbench: interrupted" and out == "", (out, err)


def test_ctrl_c_in_every_subcommand(monkeypatch, profile, capsys):
    """Wherever a subcommand is when Ctrl-C arrives (here: as it starts computing), one line, status 130."""
    import contextlib
    import fitbench.cli
    import fitbench.cli.commands as commands

    @contextlib.contextmanager
    def interrupted():
        raise KeyboardInterrupt
        yield

    monkeypatch.setattr(commands, "one_blas_thread", interrupted)
    for argv in (["list"], ["fit", "circle.kasa", str(profile)], ["roundness", str(profile)],
                 ["circular-test", str(profile), str(profile), "--nominal-radius", "10"], ["positioning", str(profile)],
                 ["magnify", str(profile), str(profile), "--eta", "10"], ["multilaterate", str(profile)],
                 ["history", str(profile.parent)]):
        for main in (commands.main, fitbench.cli.main):
            try:
                code = main(argv)
            except KeyboardInterrupt:
                pytest.fail(f"{argv}: Ctrl-C escaped the command (a traceback)")
            assert code == 130, argv
            err = capsys.readouterr().err.strip().splitlines()
            assert err == ["fitbench: interrupted"], (argv, err)
