"""A third-party fitter registers through the 'fitbench.methods' entry-point group.

The test builds and installs a tiny plugin distribution with pip (offline, into a temporary
target directory) and checks that a fresh interpreter lists it and fits with it.
"""
import json

import pytest

from conftest import install_plugin, run_python

PLUGIN = '''
"""A tiny external fitter: the circle through the centroid with the mean distance as radius."""
import numpy as np
from methods import register
from methods.results import circle_result


@register("circle.centroid_mean", kind="closed form", summary="centroid and mean distance (plugin demo)",
          reference="fitbench plugin test")
def centroid_mean(points, *, shrink=1.0):
    """Centre = centroid, radius = shrink x mean distance to it."""
    c = points.mean(axis=0)
    r = np.hypot(*(points - c).T).mean() * shrink
    return circle_result(points, c, r, converged=True, message="closed form")
'''


@pytest.fixture(scope="module")
def plugin_path(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("plugin"), "fitbench-demo-plugin",
                          {"fitbench_demo_plugin": PLUGIN}, {"fitbench.methods": {"centroid_mean": "fitbench_demo_plugin"}})


def run_with(plugin_path, *args):
    return run_python("-m", "methods", *args, path_first=[plugin_path])


def test_plugin_is_listed(plugin_path):
    out = run_with(plugin_path, "list", "--family", "circle")
    assert out.returncode == 0, out.stderr
    assert any(line.startswith("circle.centroid_mean") for line in out.stdout.splitlines())


def test_plugin_fits_with_its_parameters(plugin_path):
    out = run_with(plugin_path, "fit", "circle.centroid_mean", "roundness_set2", "--param", "shrink=0.5", "--json")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    assert d["method"] == "circle.centroid_mean" and d["params"] == {"shrink": 0.5}
    assert 3.0 < d["radius"] < 4.0  # half the ~7.1 mm mean radius of set 2


def test_without_plugin_it_is_absent():
    out = run_python("-m", "methods", "list")
    assert out.returncode == 0, out.stderr
    assert any(line.startswith("circle.kasa") for line in out.stdout.splitlines())
    assert "circle.centroid_mean" not in out.stdout
