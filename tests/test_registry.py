"""Registry and result contract."""
import json

import numpy as np
import pytest

import methods
from datasets.synthetic import circle_points
from method_ids import method_ids, method_specs

CIRCLE_IDS = method_ids("circle")
#: the circle methods of the circle/ellipse paper and of the form-error literature this project reproduces
PUBLISHED_CIRCLE_IDS = {"circle.chebyshev_lp", "circle.gauss_newton", "circle.hyper", "circle.kasa",
                        "circle.levenberg_marquardt", "circle.max_inscribed", "circle.min_circumscribed",
                        "circle.minimum_zone", "circle.nelder_mead", "circle.powell_hybrid", "circle.pratt",
                        "circle.taubin"}


def test_all_circle_methods_registered_with_metadata():
    specs = method_specs("circle")
    assert PUBLISHED_CIRCLE_IDS <= set(CIRCLE_IDS) and CIRCLE_IDS == sorted(CIRCLE_IDS)
    for s in specs:
        assert s.family == "circle" and s.id == f"{s.family}.{s.name}"
        assert s.kind in methods.KINDS
        assert s.summary and ("eq." in s.reference or "(19" in s.reference or "(20" in s.reference or "ISO" in s.reference)
        assert s.func.__doc__ and len(s.func.__doc__) > 40, f"{s.id} lacks a docstring"
        assert isinstance(s.defaults, dict)
    assert methods.get("circle.gauss_newton").defaults["stop"] == "step"
    assert methods.get("circle.nelder_mead").defaults["backend"] == "scipy"


def test_list_methods_filters_family():
    assert methods.list_methods("no_such_family") == []
    assert {s.family for s in methods.list_methods()} >= {"circle"}


def test_unknown_method_suggests_close_ids():
    with pytest.raises(methods.UnknownMethodError, match="circle.gauss_newton"):
        methods.get("circle.gauss_newtn")
    with pytest.raises(methods.InvalidInputError, match="circle.kasa"):
        methods.fit("kasa", np.eye(3))


def test_unknown_parameter_is_refused():
    pts = circle_points(n=10)
    with pytest.raises(methods.InvalidInputError, match="no parameter 'tolerance'"):
        methods.fit("circle.gauss_newton", pts, tolerance=1e-3)


def test_bad_parameter_values_are_refused():
    pts = circle_points(n=10)
    with pytest.raises(methods.InvalidInputError, match="stop"):
        methods.fit("circle.gauss_newton", pts, stop="never")
    with pytest.raises(methods.InvalidInputError, match="backend"):
        methods.fit("circle.nelder_mead", pts, backend="matlab")
    with pytest.raises(methods.InvalidInputError, match="start"):
        methods.fit("circle.powell_hybrid", pts, start=(0, 0))
    with pytest.raises(methods.InvalidInputError, match="xtol"):
        methods.fit("circle.levenberg_marquardt", pts, xtol=-1)


@pytest.mark.parametrize("method_id", CIRCLE_IDS)
def test_result_contract(method_id):
    pts = circle_points((3.0, -2.0), 5.0, 40) + np.random.default_rng(1).normal(0, 1e-3, (40, 2))
    res = methods.fit(method_id, pts)
    assert isinstance(res, methods.CircleFit)
    assert res.method == method_id and res.converged, res.message
    assert len(res.center) == 2 and res.radius > 0
    assert res.residuals.shape == (40,)
    r = np.hypot(pts[:, 0] - res.center[0], pts[:, 1] - res.center[1])
    np.testing.assert_allclose(res.residuals, r - res.radius, atol=1e-12)
    assert res.form_error == pytest.approx(r.max() - r.min(), abs=1e-12)
    assert res.runtime_s > 0 and isinstance(res.message, str) and res.message
    assert res.params == {**methods.get(method_id).defaults}
    kind = methods.get(method_id).kind
    if kind == "iterative":
        assert res.nfev and res.nfev > 0 and len(res.history) > 0
        assert res.history[-1] <= res.history[0] * (1 + 1e-12)
    d = res.to_dict()
    json.dumps(d)  # JSON-ready
    for key in ("method", "center", "radius", "form_error", "residuals", "converged", "iterations",
                "nfev", "history", "message", "runtime_s"):
        assert key in d
    assert "residuals" not in res.to_dict(residuals=False)


def test_decorated_function_is_the_registered_method():
    from methods.circle.gauss_newton import gauss_newton
    pts = circle_points((1, 2), 3, 12)
    assert gauss_newton is methods.get("circle.gauss_newton")
    a, b = gauss_newton(pts), methods.fit("circle.gauss_newton", pts)
    assert a.center == b.center and a.radius == b.radius


def test_register_rejects_bad_ids_and_kinds():
    with pytest.raises(ValueError, match="family.name"):
        methods.register("nodot", summary="s", reference="r", kind="iterative")
    with pytest.raises(ValueError, match="kind"):
        methods.register("x.y", summary="s", reference="r", kind="magic")
