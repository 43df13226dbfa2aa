"""fitbench's method tests run on fitbench's own methods: with the README's example plugin installed (a centroid fit,
``circle.my_fit``) the suite failed on it (exact-data recovery, minimal point sets), as if fitbench were broken. A
plugin method joins them only when named in FITBENCH_TEST_METHODS (docs/plugins.md)."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import methods
from methods.results import circle_result
from plugin_methods import registered

HERE = Path(__file__).parent
#: the test modules that parametrise over a family's methods, and their lists of method ids
PARAMETRISED = {"test_circle_exact.py": ["ALL"], "test_circle_flags.py": ["ALL", "LEAST_SQUARES"],
                "test_properties.py": ["ALL"], "test_validation.py": ["ALL"], "test_ellipse.py": ["ALL"],
                "test_registry.py": ["CIRCLE_IDS"]}
PLUGIN = "circle.zz_centroid_plugin"


def _centroid(points):
    """A plugin's circle: the centroid and the mean distance to it (the README's example method)."""
    c = points.mean(axis=0)
    return circle_result(points, c, float(np.hypot(*(points - c).T).mean()), converged=True, message="ok")


@pytest.fixture
def plugin_method():
    methods.list_methods()
    with registered({PLUGIN: _centroid}, kind="closed form", summary="centroid and mean distance", reference="a test"):
        assert not methods.get(PLUGIN).builtin
        yield PLUGIN


def _fresh(name):
    spec = importlib.util.spec_from_file_location(f"fresh_{name[:-3]}", HERE / name)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name", sorted(PARAMETRISED))
def test_the_method_tests_leave_an_installed_plugin_out(plugin_method, name, monkeypatch):
    monkeypatch.delenv("FITBENCH_TEST_METHODS", raising=False)
    module = _fresh(name)
    for listed in PARAMETRISED[name]:
        ids = getattr(module, listed)
        assert plugin_method not in ids and ids, (name, listed)


def test_a_plugin_method_named_in_the_environment_joins_them(plugin_method, monkeypatch):
    monkeypatch.setenv("FITBENCH_TEST_METHODS", plugin_method)
    ids = _fresh("test_circle_exact.py").ALL
    assert plugin_method in ids and "circle.kasa" in ids
    monkeypatch.setenv("FITBENCH_TEST_METHODS", "circle.zz_no_such_fit")
    with pytest.raises(LookupError, match="circle.zz_no_such_fit, which no installed method is"):
        _fresh("test_circle_exact.py")
