"""One result interface across families: the metrics and the CLI read every result through
FitResult.geometry / truth_errors / report_lines, never by testing which attributes it has."""
import ast
from pathlib import Path

import numpy as np
import pytest

import methods
from experiments.metrics import metrics
from methods.results import FitResult

REPO = Path(__file__).resolve().parents[1]
RNG = np.random.default_rng(14)
T = RNG.uniform(0, 2 * np.pi, 60)
CIRCLE = np.c_[3 + 2 * np.cos(T), -1 + 2 * np.sin(T)] + RNG.normal(0, 1e-3, (60, 2))
ELLIPSE = np.c_[3 + 2 * np.cos(T) * np.cos(0.3) - np.sin(T) * np.sin(0.3),
                -1 + 2 * np.cos(T) * np.sin(0.3) + np.sin(T) * np.cos(0.3)]


@pytest.mark.parametrize("source", ["experiments/metrics.py",
                                    *sorted(p.relative_to(REPO).as_posix() for p in (REPO / "fitbench" / "cli").glob("*.py"))])
def test_no_attribute_sniffing(source):
    tree = ast.parse((REPO / source).read_text())
    sniffing = [n.lineno for n in ast.walk(tree) if isinstance(n, ast.Call) and getattr(n.func, "id", "") == "hasattr"]
    assert not sniffing, f"{source} tests result attributes at lines {sniffing}: use the FitResult interface"


def test_circle_row_columns_and_truth_errors():
    res = methods.fit("circle.gauss_newton", CIRCLE)
    row = metrics(res, {"center": (3.0, -1.0), "radius": 2.0})
    assert list(row) == ["form_error", "residual_rms", "center_x", "center_y", "radius",
                         "center_error_x", "center_error_y", "center_error", "radius_error"]
    assert row["center_error"] == pytest.approx(np.hypot(res.center[0] - 3.0, res.center[1] + 1.0), rel=1e-15)
    assert row["radius_error"] == res.radius - 2.0 and row["radius"] == res.radius
    assert row["residual_rms"] == pytest.approx(np.sqrt(np.mean(res.residuals ** 2)), rel=1e-15)


def test_zone_row_adds_the_zone_radii():
    res = methods.fit("circle.minimum_zone", CIRCLE)
    row = metrics(res, None)
    assert list(row)[2:] == ["center_x", "center_y", "radius", "inner_radius", "outer_radius"]
    assert row["outer_radius"] - row["inner_radius"] == pytest.approx(res.form_error, abs=1e-15)


def test_ellipse_row_columns_and_angle_error_wraps():
    res = methods.fit("ellipse.halir_flusser", ELLIPSE)
    row = metrics(res, {"center": (3.0, -1.0), "semi_axes": (2.0, 1.0), "angle": 0.3 + np.pi})  # same ellipse
    assert list(row)[2:7] == ["center_x", "center_y", "semi_axis_a", "semi_axis_b", "angle"]
    assert abs(row["angle_error"]) < 1e-9 and abs(row["semi_axis_a_error"]) < 1e-9


def test_a_family_without_geometry_gives_only_the_shared_columns():
    res = FitResult(converged=True, form_error=0.5, residuals=np.array([3.0, 4.0]))
    assert metrics(res, {"center": (0, 0)}) == {"form_error": 0.5, "residual_rms": pytest.approx(np.sqrt(12.5))}
    assert res.geometry() == {} and res.truth_errors({"radius": 1}) == {} and res.report_lines() == []


@pytest.mark.parametrize("method_id,data", [("circle.kasa", CIRCLE), ("circle.max_inscribed", CIRCLE),
                                            ("ellipse.fitzgibbon", ELLIPSE)])
def test_report_lines_carry_units(method_id, data):
    lines = methods.fit(method_id, data).report_lines()
    assert lines and all(("mm" in text or "rad" in text or "point indices" in text) for _, text in lines), lines


def test_circular_test_evaluation_is_a_fit_result():
    """ISO 230-4: the evaluation is a FitResult (form_error = G(b), residuals = radial deviations F about the
    stated centre), its figures checked against an independent least-squares centre and a direct F."""
    from datasets.circular_test import MachineErrors, TestConditions, circular_test
    from methods.results import CircularTestFit
    from methods.circular_test import evaluate

    cond = TestConditions(nominal_radius=150.0, nominal_center=(300.0, 200.0), feed_mm_min=1000.0)
    cw, ccw, _ = circular_test(cond, MachineErrors(noise=0.0005, squareness=20e-6), seed=3)
    ev = evaluate(cw, ccw, 150.0, (300.0, 200.0))
    assert isinstance(ev, FitResult) and isinstance(ev, CircularTestFit) and ev.converged
    both = np.vstack([cw, ccw])
    assert ev.form_error == ev.figures["G_b"]
    assert list(ev.figures) == list(CircularTestFit.FIGURES)
    # F about the nominal centre, computed directly
    dev = np.hypot(both[:, 0] - 300.0, both[:, 1] - 200.0) - 150.0
    np.testing.assert_allclose(ev.residuals, dev, rtol=0, atol=1e-12)
    assert ev.figures["F_max"] == pytest.approx(dev.max(), abs=1e-12)
    # G(b) about an independent least-squares centre of both runs (linear Kasa start, then scipy least_squares)
    from scipy.optimize import least_squares
    A = np.c_[2 * both, np.ones(len(both))]
    c0 = np.linalg.lstsq(A, (both ** 2).sum(1), rcond=None)[0][:2]
    c = least_squares(lambda c: np.hypot(*(both - c).T) - np.hypot(*(both - c).T).mean(), c0, xtol=1e-15,
                      ftol=1e-15, gtol=1e-15).x
    r = np.hypot(*(both - c).T)
    assert ev.figures["G_b"] == pytest.approx(r.max() - r.min(), abs=1e-9)
    row = metrics(ev, {"center": (300.0, 200.0)})
    assert list(row) == ["form_error", "residual_rms", "center_x", "center_y", "center_error_x", "center_error_y",
                         "center_error"]
    lines = dict(ev.report_lines("mm"))
    assert lines["G(b)"].endswith(" mm") and "nominal centre" in lines["F max / F min"]
    d = ev.to_dict(residuals=False)
    assert list(d)[:9] == ["method", *CircularTestFit.FIGURES, "center"] and "residuals" not in d
