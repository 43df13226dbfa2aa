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


@pytest.mark.parametrize("command", [("list",), ("fit", "circle.kasa", "{p}"), ("roundness", "{p}")])
def test_json_stdout_is_the_json_alone_when_a_plugin_prints_at_import(chatty_site, profile, command):
    args = [a.format(p=profile) for a in command]
    out = run_python("-m", "fitbench", *args, "--json", path_first=[chatty_site])
    assert out.returncode == 0, out.stderr
    json.loads(out.stdout)                                   # the whole of stdout is one JSON document
    assert "chatty plugin imported" in out.stderr and "descriptor 1" in out.stderr
