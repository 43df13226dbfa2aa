"""A method parameter with a fixed set of values (a backend, a stopping rule, a start vector) is checked when the
study's config is loaded, by the checks the method's own code makes (``methods._registry.body_checks``): a typo is
one line and exit 2 before any row, never a ``skipped`` row (which is not run again) and exit 0."""
from __future__ import annotations

import pytest

import methods
from cli_calls import call, one_error_line
from experiments import config as configs
from experiments import run
from experiments.study import ConfigError
from methods._validation import check_choice, check_positive, check_vector

STUDY = '''
name = "{name}"
title = "t"
seed = 1
[[datasets]]
source = "circle"
params = {{ radius = 5.0, noise = 0.01, n = 30 }}
[[methods]]
id = "{method}"
{extra}
'''


def _write(tmp_path, method, extra, name="choices"):
    path = tmp_path / f"{name}.toml"
    path.write_text(STUDY.format(name=name, method=method, extra=extra), encoding="utf-8")
    return path


@pytest.mark.parametrize("method, extra, said", [
    ("circle.nelder_mead", 'grid = { backend = ["scipy", "bogus"] }',
     "circle.nelder_mead: parameter backend='bogus' is not one of 'scipy', 'nlopt'"),
    ("circle.gauss_newton", 'params = { stop = "nope" }',
     "circle.gauss_newton: parameter stop='nope' is not one of 'objective', 'step', 'gradient'"),
    ("circle.gauss_newton", 'params = { start = "centroid" }',
     "circle.gauss_newton: parameter start='centroid' is not a list of 3 numbers"),
    ("circle.nelder_mead", 'params = { step = [1e-3, 1e-3] }',
     "circle.nelder_mead: parameter step=[0.001, 0.001] needs 3 finite numbers"),
    # checked in a loop over (name, parameter) pairs: circle.gauss_newton refuses xtol = 0 (the convention takes >= 0)
    ("circle.gauss_newton", 'grid = { xtol = [1e-12, 0.0] }', "circle.gauss_newton: parameter xtol=0.0 must be a positive number"),
    # checked by a function the method calls (ellipse.geometric_nm's _setup), and after a return for partial arcs
    ("ellipse.geometric_nm", 'params = { backend = "NLopt" }', "parameter backend='NLopt' is not one of"),
    ("circle.max_inscribed", 'params = { global_search = "sometimes" }',
     "parameter global_search='sometimes' is not one of 'always', 'never'"),
])
def test_a_value_the_method_refuses_is_refused_with_the_config(tmp_path, method, extra, said):
    path = _write(tmp_path, method, extra + ("\nany_family = true" if method.startswith("ellipse") else ""))
    with pytest.raises(ConfigError) as caught:
        configs.load(str(path))
    assert said in str(caught.value) and "methods[0]" in str(caught.value)
    assert "\n" not in str(caught.value)


def test_the_run_refuses_it_in_one_line_before_any_row(tmp_path):
    path = _write(tmp_path, "circle.nelder_mead", 'grid = { backend = ["scipy", "bogus"] }')
    one_error_line(call(run.main, path, "--out", tmp_path / "out", "--no-report"),
                   "backend='bogus' is not one of 'scipy', 'nlopt'")
    assert not (tmp_path / "out" / "choices" / "results.csv").exists()


def test_the_values_the_method_takes_still_load(tmp_path):
    path = _write(tmp_path, "circle.nelder_mead",
                  'grid = { backend = ["scipy", "nlopt"] }\nparams = { start = [0.0, 0.0, 5.0], step = [1e-3, 1e-3, 1e-3] }')
    cfg = configs.load(str(path))
    assert sorted(p["backend"] for _, p in ((m, e["params"]) for m, e in cfg.expand_methods())) == ["nlopt", "scipy"]


def _setup(name, mode):
    check_choice("mode", mode, ("fast", "exact"), name)


def _choice_method(points, *, mode="fast", centre=None, limit=3, gap=1.0):
    name = "circle.choicetest"
    _setup(name, mode)
    for key, val in (("gap", gap),):
        check_positive(key, val, name)
    for key, val in (("gap", gap),):
        if key:  # under an if: not read
            check_choice(key, val, (1.0, 2.0), name)
    if limit > 5:  # a check under a condition on another parameter is not the parameter's own
        check_choice("centre", centre, ("a", "b"), name)
    check_vector("centre", centre, 2, name)
    return methods.fit("circle.kasa", points)


def test_a_method_of_any_package_gets_the_checks_its_code_makes():
    from methods._registry import _REGISTRY
    spec = methods.register("circle.choicetest", kind="closed form", summary="a test method with a choice",
                            reference="tests/test_config_method_choices.py")(_choice_method)
    try:
        with pytest.raises(methods.InvalidInputError, match=r"parameter mode='slow' is not one of 'fast', 'exact'$"):
            spec.check_params({"mode": "slow"})
        with pytest.raises(methods.InvalidInputError, match=r"parameter centre=\[1\] needs 2 finite numbers"):
            spec.check_params({"centre": [1]})
        with pytest.raises(methods.InvalidInputError, match=r"parameter gap=-1.0 must be a positive number$"):
            spec.check_params({"gap": -1.0})
        spec.check_params({"mode": "exact", "centre": [1.0, 2.0], "limit": 9, "gap": 3.0})  # conditional checks unread
    finally:
        _REGISTRY.pop("circle.choicetest", None)
