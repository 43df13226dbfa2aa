"""The result gate solves a converged ellipse's orthogonal residuals again from the data (as it recomputes a circle's
radial ones): a plugin claiming zero residuals, hence zero form error and residual RMS, for any ellipse was stored
``ok``; every built-in ellipse method's result still passes, at every size and far from the origin."""
import numpy as np
import pytest

import methods
from experiments.rows import fit_row
from methods import check_result, results
from plugin_methods import registered

T = np.linspace(0.0, 2 * np.pi, 60, endpoint=False)
CENTER, AXES, ANGLE = (1200.0, 650.0), (299.0243, 299.0022), np.radians(32.04)   # the paper's ellipse, mm


def ellipse(center=CENTER, axes=AXES, angle=ANGLE, noise=1e-3, t=T, seed=4):
    c, s = np.cos(angle), np.sin(angle)
    x, y = axes[0] * np.cos(t), axes[1] * np.sin(t)
    pts = np.column_stack([center[0] + c * x - s * y, center[1] + s * x + c * y])
    return pts + np.random.default_rng(seed).normal(scale=noise, size=pts.shape)


PTS = ellipse()
TRUTH = {"center": CENTER, "semi_axes": AXES, "angle": ANGLE}


def _forged(points, *, lie="zeros"):
    """halir_flusser's ellipse, its residuals replaced (what review's ellipse.perfect plugin returned)."""
    fit = methods.fit("ellipse.halir_flusser", points)
    p = (*fit.center, *fit.semi_axes, fit.angle)
    honest = results.ellipse_result(points, p, converged=True, message="closed form")
    residuals = {"zeros": np.zeros(len(points)), "halved": honest.residuals / 2,
                 "one point off": honest.residuals + np.eye(len(points))[5] * 1e-4,
                 "honest": None}[lie]
    return results.ellipse_result(points, p, converged=True, message="closed form", residuals=residuals)


@pytest.fixture
def forging_plugin():
    methods.list_methods()
    with registered({"ellipse.test_gate_forged": _forged}, kind="closed form", summary="forged residuals",
                    reference="gate test"):
        yield "ellipse.test_gate_forged"


@pytest.mark.parametrize("lie", ["zeros", "halved", "one point off"])
def test_forged_residuals_are_an_invalid_row(forging_plugin, lie):
    res = methods.get(forging_plugin).unchecked(PTS, lie=lie)
    problem = check_result(res, PTS)
    assert problem is not None and "residuals are not the orthogonal distances" in problem and "\n" not in problem
    if lie == "one point off":
        assert "point 5:" in problem, problem
    task = {"study": "gate", "dataset": {"label": "ellipse"}, "repetition": 0, "seed": 1, "stream": (0,),
            "method": forging_plugin, "params": {"lie": lie}}
    row = fit_row(task, PTS, TRUTH)
    assert row["status"] == "invalid" and "orthogonal distances" in row["message"], row
    assert "form_error" not in row and "residual_rms" not in row


def test_honest_residuals_pass_and_match_the_built_in_row(forging_plugin):
    res = methods.get(forging_plugin).unchecked(PTS, lie="honest")
    assert check_result(res, PTS) is None
    task = {"study": "gate", "dataset": {"label": "ellipse"}, "repetition": 0, "seed": 1, "stream": (0,),
            "method": forging_plugin, "params": {"lie": "honest"}}
    row = fit_row(task, PTS, TRUTH)
    own = fit_row({**task, "method": "ellipse.halir_flusser", "params": {}}, PTS, TRUTH)
    assert row["status"] == "ok" == own["status"]
    assert row["form_error"] == pytest.approx(own["form_error"], rel=1e-9)
    assert row["residual_rms"] == pytest.approx(own["residual_rms"], rel=1e-9)


ELLIPSE_METHODS = [s.id for s in methods.list_methods("ellipse") if s.builtin]
CASES = {
    "paper's ellipse": PTS,
    "a 60-degree arc": ellipse(t=np.linspace(0.3, 1.35, 40)),
    "near-circle": ellipse(axes=(299.0243, 299.0238)),
    "exact points": ellipse(noise=0.0),
    "size 1e-150": ellipse((3e-150, -2e-150), (2e-150, 1e-150), 0.3, noise=1e-153),
    "size 1e150": ellipse((3e150, -2e150), (2e150, 1e150), 0.3, noise=1e147),
    "2 um, 1e9 from the origin": ellipse((1e9, -1e9), (2e-3, 1e-3), 0.3, noise=1e-6),
}


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("method_id", ELLIPSE_METHODS)
def test_every_built_in_ellipse_passes_the_solved_residuals(method_id, case):
    pts = methods.immutable(CASES[case])
    res = methods.get(method_id).unchecked(pts)
    assert check_result(res, pts) is None
