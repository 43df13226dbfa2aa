"""The result gate catches what a plugin's result claims without the means to back it: a family no result class
declares, a certificate of optimality (checked by fitbench's own methods only) and a converged result whose residual
RMS is not a number."""
import math

import numpy as np
import pytest

import methods
from experiments.metrics import residual_rms
from methods import ResultContractError
from methods.results import check_result, circle_result, zone_result
from plugin_methods import registered


def circle(n=40, radius=5.0, noise=0.001, seed=0):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[100 + radius * np.cos(t), -30 + radius * np.sin(t)] + rng.normal(0, noise, (n, 2))


def centroid_fit(points):
    c = points.mean(axis=0)
    return c, float(np.hypot(*(points - c).T).mean())


def _torus(points):
    c, r = centroid_fit(points)
    return circle_result(points, c, r, converged=True, message="ok")


def _fake_mz(points):
    c = points.mean(axis=0) + 0.002
    r = np.hypot(*(points - c).T)
    return zone_result(points, c, float((r.max() + r.min()) / 2), {"outer": [int(r.argmax())], "inner": [int(r.argmin())]},
                       converged=True, message="certified global", extra={"certified": "global", "global_bound": 0.0})


@pytest.fixture
def plugin_methods():
    """The methods of a plugin, registered from this module (not methods.*) for one test only."""
    with registered({"torus.test_gate_fit": _torus, "circle.test_gate_fake_mz": _fake_mz},
                    kind="closed form", summary="gate test", reference="a test"):
        yield


def refused(method_id, words):
    with pytest.raises(ResultContractError) as info:
        methods.fit(method_id, circle())
    assert words in str(info.value), str(info.value)


def test_a_family_no_result_class_declares_is_refused(plugin_methods):
    refused("torus.test_gate_fit", "no result class declares FAMILY = 'torus'")


def test_a_plugin_certificate_is_refused_and_a_built_in_one_passes(plugin_methods):
    refused("circle.test_gate_fake_mz", "extra['certified'] = str 'global' is a certificate only fitbench's own")
    pts = circle()
    mz = methods.fit("circle.minimum_zone", pts)
    assert mz.extra["certified"] == "global" and check_result(mz, pts) is None
    honest = _fake_mz(pts)
    honest.method, honest.extra = "circle.test_gate_fake_mz", {"certified": False}
    assert check_result(honest, pts) is None


@pytest.mark.parametrize("scale, passes", [(1e140, True), (1e300, False)])
def test_a_converged_result_whose_residual_rms_overflows_is_refused(scale, passes):
    """radius 1e300 with noise 1e300 (a study the config accepts) gave ok rows with an empty residual_rms."""
    pts = circle(radius=scale, noise=scale / 5)
    c, r = centroid_fit(pts)
    res = circle_result(pts, c, r, converged=True, message="ok")
    res.method = "circle.kasa"
    with np.errstate(over="ignore"):
        problem = check_result(res, pts)
    if passes:
        assert problem is None and math.isfinite(residual_rms(res.residuals))
    else:
        with np.errstate(over="ignore"):
            assert not math.isfinite(residual_rms(res.residuals))
        assert problem.startswith("the residual RMS overflows float64"), problem

