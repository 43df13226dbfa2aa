"""Exact data must give the exact answer, also for machine-tool coordinates far from the origin."""
import numpy as np
import pytest

import methods
from datasets.synthetic import circle_points
from method_ids import method_ids

ALL = method_ids("circle")
CASES = [
    ((0.0, 0.0), 1.0, (0, 2 * np.pi)),
    ((1200.0, 650.0), 299.0, (0, 2 * np.pi)),          # the LOLA HBG 130 test of the circle/ellipse paper
    ((1200.0, 650.0), 299.0, (0.3, 0.3 + np.pi / 2)),  # a quadrant arc
    ((1e6, -1e6), 299.0, (0, 2 * np.pi)),              # a centre 10^6 away
    ((-3.0, 7.0), 1e-3, (0, 2 * np.pi)),               # a micrometre-sized circle
]


# An arc's MIC does not exist and its MCC is not its circle: tests/test_zone.py covers those.
EXACT = [(m, *case) for m in ALL for case in CASES
         if not (m in ("circle.max_inscribed", "circle.min_circumscribed") and case[2][1] - case[2][0] < 2 * np.pi)]


@pytest.mark.parametrize("method_id, center, radius, arc", EXACT)
def test_exact_circle_recovered(method_id, center, radius, arc):
    pts = circle_points(center, radius, 60, arc=arc)
    res = methods.fit(method_id, pts)
    assert res.converged, res.message
    # 1e-7 mm or better (relative for the micrometre circle: the data themselves are rounded to
    # float64, whose spacing at 10^6 is 1.2e-10).
    tol = 1e-7 if radius > 1 else 1e-7 * radius
    if method_id == "circle.nelder_mead":
        tol *= 10 if abs(arc[1] - arc[0]) < np.pi else 1  # a short arc flattens S_CG: see README
    assert np.abs(np.array(res.center) - center).max() <= tol
    assert abs(res.radius - radius) <= tol
    assert res.form_error <= 4 * tol


@pytest.mark.parametrize("backend", ["scipy", "nlopt"])
def test_nelder_mead_paper_settings_on_exact_circle(backend):
    """Table 2 of the circle/ellipse paper: s1S = (0, 0, 299), lambda = 0.001 mm, on a circle near it."""
    pts = circle_points((-0.01184, 0.00981), 299.0132, 3358)
    res = methods.fit("circle.nelder_mead", pts, backend=backend, start=(0.0, 0.0, 299.0), step=(0.001,) * 3)
    assert res.converged, res.message
    assert np.abs(np.array(res.center) - (-0.01184, 0.00981)).max() < 1e-7
    assert abs(res.radius - 299.0132) < 1e-7


def test_powell_hybrid_paper_settings():
    """Table 1 of the circle/ellipse paper: p_s = (0, 0, 299), epsilon = 1e-8."""
    pts = circle_points((-0.01184, 0.00981), 299.0132, 3358)
    res = methods.fit("circle.powell_hybrid", pts, start=(0.0, 0.0, 299.0), xtol=1e-8)
    assert np.abs(np.array(res.center) - (-0.01184, 0.00981)).max() < 1e-7
    assert abs(res.radius - 299.0132) < 1e-7
    # The paper's epsilon stops MINPACK ~1e-10 mm (4e-13 of the radius) from the exact root: near the
    # 1024-ulp resolution of the stationarity check, so either verdict may be right; it must be stated.
    assert "stationary" in res.message
    res = methods.fit("circle.powell_hybrid", pts, start=(0.0, 0.0, 299.0))
    assert res.converged, res.message
    assert np.abs(np.array(res.center) - (-0.01184, 0.00981)).max() < 1e-9


@pytest.mark.parametrize("stop", ["objective", "step", "gradient"])
def test_gauss_newton_stopping_criteria(stop, rng):
    pts = circle_points((1200, 650), 299, 500, noise=0.005, rng=rng)
    ref = methods.fit("circle.levenberg_marquardt", pts)
    res = methods.fit("circle.gauss_newton", pts, stop=stop)
    assert res.converged and res.extra["stop"] == stop
    assert np.abs(np.array(res.center) - ref.center).max() < 1e-9
    # the paper's own setting (step below 1e-4 mm, i.e. 1e-4/scale in the unit frame) stops earlier
    loose = methods.fit("circle.gauss_newton", pts, xtol=1e-4)
    assert loose.iterations <= res.iterations or stop != "step"


def test_gauss_newton_reports_non_convergence():
    pts = circle_points((0, 0), 1, 50, arc=(0, 0.5), noise=0.05, rng=np.random.default_rng(3))
    res = methods.fit("circle.gauss_newton", pts, max_iter=1)
    assert not res.converged and "max_iter=1" in res.message


@pytest.mark.parametrize("method_id", ALL)
@pytest.mark.parametrize("n", [3, 4])
def test_minimal_point_sets_give_the_circle_through_them(method_id, n):
    """Three points (and four concyclic ones) determine the circle: every method must return it
    (MIC and MCC need points around the centre, hence the wider spread of angles for them)."""
    arc = (0.1, 4.0) if method_id not in ("circle.max_inscribed", "circle.min_circumscribed") else (0.1, 0.1 + 2 * np.pi * (n - 1) / n)
    pts = circle_points((1200.0, 650.0), 299.0, n, arc=arc, endpoint=True)
    res = methods.fit(method_id, pts)
    assert res.converged, res.message
    assert np.abs(np.array(res.center) - (1200.0, 650.0)).max() <= 1e-7
    assert abs(res.radius - 299.0) <= 1e-7


def test_powell_hybrid_reports_minpack_stops_in_its_words():
    pts = circle_points((3.0, 4.0), 2.0, 50, noise=0.01, rng=np.random.default_rng(0))
    res = methods.fit("circle.powell_hybrid", pts, maxfev=3)
    assert not res.converged and "maxfev = 3" in res.message


def test_powell_hybrid_at_the_root_of_exact_data_is_converged():
    """MINPACK may say 'not making good progress' at the exact root (its steps are rounding noise);
    the equations are then satisfied to rounding and the result says so."""
    pts = circle_points((-600.5, -428.7), 169.46, 360)
    res = methods.fit("circle.powell_hybrid", pts)
    assert res.converged, res.message
    assert np.abs(np.array(res.center) - (-600.5, -428.7)).max() < 1e-9
