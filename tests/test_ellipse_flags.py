"""Ellipse flags are promises (issues 15, 16, 17): converged = a stationary, non-degenerate ellipse,
checked against an independent local solver (scipy.optimize.least_squares started at the returned point);
statuses that do not depend on the last bit; distinct points; every size from 1e-150 to 1e150."""
import warnings

import numpy as np
import pytest
from scipy.optimize import least_squares

import methods
from datasets.synthetic import ellipse_points
from ellipse_reference_data import (OPENCV_ISSUE_5, OPENCV_ISSUE_5_DIRECT, OPENCV_ISSUE_6, OPENCV_ISSUE_6_DIRECT,
                                    skimage_far_shifted)
from methods.ellipse._checks import stationarity_probe
from methods.ellipse._geometry import orthogonal_residuals, to_local

ITERATIVE = ["ellipse.orthogonal", "ellipse.geometric_nm", "ellipse.algebraic_nm"]
ALL = ["ellipse.fitzgibbon", "ellipse.halir_flusser", *ITERATIVE]


def hard_ellipses(k, seed):
    """Short arcs (0.3 to 2 rad) of ellipses with a/b = 10 to 100, noise 1e-3 b."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(k):
        a = 10 ** rng.uniform(0, 2)
        b = a / 10 ** rng.uniform(1, 2)
        t0, span = rng.uniform(0, 2 * np.pi), rng.uniform(0.3, 2.0)
        out.append(ellipse_points(tuple(rng.uniform(-50, 50, 2)), (a, b), rng.uniform(0, np.pi),
                                  int(rng.integers(10, 60)), arc=(t0, t0 + span), noise=1e-3 * b, rng=rng))
    return out


def own_objective_and_point(res, pts):
    """The method's own objective as residuals (the published one) and its returned point."""
    if res.method == "ellipse.algebraic_nm":
        pp = res.extra["paper_parameters"]
        q = np.array([pp["p_x"], pp["p_y"], pp["gamma"], pp["x_C"], pp["y_C"]])

        def r(q):
            px, py, g, xc, yc = q
            u, v = to_local(pts[:, 0], pts[:, 1], (xc, yc, px, py, g))
            return py * py * u * u + px * px * v * v - px * px * py * py
        return r, q

    def d(p):
        if not (p[2] > 0 and p[3] > 0):
            return np.full(len(pts), 1e3 * np.ptp(pts))
        return orthogonal_residuals(pts[:, 0], pts[:, 1], p, with_phi=False)[0]
    return d, np.array([*res.center, *res.semi_axes, res.angle])


def assert_promise_kept(res, pts):
    """converged=True => scipy's least_squares started at the returned point lowers the objective by at
    most 1e-9 relative (and the ellipse is not collapsed)."""
    if not res.converged:
        assert res.message
        return
    r, q = own_objective_and_point(res, pts)
    f0 = float(r(q) @ r(q))
    ref = least_squares(r, q, method="trf", x_scale="jac", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=3000)
    assert 2 * ref.cost >= f0 * (1 - 1e-9), (res.method, res.message, f0, 2 * ref.cost)
    assert min(res.semi_axes) > 1e-6 * np.sqrt(np.mean(np.sum((pts - pts.mean(0)) ** 2, axis=1)))


@pytest.mark.parametrize("method_id", ITERATIVE)
def test_converged_means_no_local_solver_can_lower_the_objective(method_id):
    sets = hard_ellipses(24 if method_id == "ellipse.orthogonal" else 7, seed=15)
    for pts in sets:
        assert_promise_kept(methods.fit(method_id, pts), pts)


def test_geometric_nm_stalled_in_a_valley_says_so():
    """A short arc (a/b ~ 40) where Nelder–Mead stalls at 2800x the orthogonal fit's sum of squares:
    before, 'Optimization terminated successfully' and converged; now converged=False with the reason."""
    pts = hard_ellipses(7, seed=0)[6]
    res = methods.fit("ellipse.geometric_nm", pts)
    best = methods.fit("ellipse.orthogonal", pts)
    assert best.converged
    if np.sum(res.residuals ** 2) > 1.01 * np.sum(best.residuals ** 2):
        assert not res.converged and "not a stationary point" in res.message
        assert res.extra["stationarity"]["relative_decrease"] > 1e-10
    assert_promise_kept(res, pts)


@pytest.mark.parametrize("pts", [OPENCV_ISSUE_5, OPENCV_ISSUE_6, skimage_far_shifted()[0]],
                         ids=["opencv-issue5", "opencv-issue6", "skimage-far-shifted"])
def test_algebraic_nm_collapse_is_reported_degenerate(pts):
    """Eq. 16 is 0 at p_x = p_y = 0; on these sets Nelder–Mead follows it there: degenerate, not converged."""
    res = methods.fit("ellipse.algebraic_nm", pts)
    assert not res.converged
    assert "degenerate" in res.message and "collapsed" in res.extra["degenerate"]
    for method_id in ("ellipse.geometric_nm", "ellipse.orthogonal", "ellipse.halir_flusser"):
        other = methods.fit(method_id, pts)
        assert other.converged, (method_id, other.message)
        if method_id in ITERATIVE:
            assert_promise_kept(other, pts)


@pytest.mark.parametrize("method_id", ["ellipse.fitzgibbon", "ellipse.halir_flusser"])
@pytest.mark.parametrize("pts, want", [(OPENCV_ISSUE_5, OPENCV_ISSUE_5_DIRECT), (OPENCV_ISSUE_6, OPENCV_ISSUE_6_DIRECT)],
                         ids=["issue5", "issue6"])
def test_direct_fits_give_opencv_fitEllipseDirect(method_id, pts, want):
    """OpenCV's expected fitEllipseDirect results (printed to 6 digits): centre and full axes within 0.01."""
    res = methods.fit(method_id, pts)
    assert res.converged, res.message
    (cx, cy), (w, h), _ = want
    np.testing.assert_allclose(res.center, (cx, cy), atol=0.01)
    np.testing.assert_allclose(sorted(2 * np.array(res.semi_axes)), sorted((w, h)), atol=0.01)


def test_skimage_far_shifted_exact_ellipse():
    pts, (xc, yc, a, b, theta) = skimage_far_shifted()
    for method_id in ("ellipse.halir_flusser", "ellipse.orthogonal", "ellipse.geometric_nm"):
        res = methods.fit(method_id, pts)
        assert res.converged, res.message
        # coordinates of 2e6 carry 4.7e-10 of rounding; the axes are 0.5 and 0.1
        np.testing.assert_allclose(res.center, (xc, yc), rtol=0, atol=1e-7)
        np.testing.assert_allclose(res.semi_axes, (a, b), rtol=0, atol=1e-7)


@pytest.mark.parametrize("noise", [0.0, 1e-6])
def test_fitzgibbon_on_exact_data_is_right_or_says_why(noise):
    """Exact or nanometre-noise data of the paper's near-circle make S singular: Fitzgibbon's eigenvalue is
    zero to rounding, so whether the original selection rule (a positive eigenvalue) finds it depends on
    the last bit (it differs between CPUs). What must hold on any CPU: that eigenvalue is zero to rounding;
    a found ellipse is the right one; a lost one is reported; Halir & Flusser always recover the ellipse."""
    paper = dict(center=(1200.0, 650.0), semi_axes=(299.0243, 299.0022), angle=np.radians(32.04))
    pts = ellipse_points(n=3358, noise=noise, rng=np.random.default_rng(0), **paper)
    orig = methods.fit("ellipse.fitzgibbon", pts)
    if orig.converged:
        assert abs(orig.extra["eigenvalue"]) <= 1e-6 * len(pts) * max(noise / 299.0, 1e-7) ** 0 * 1e-3
        np.testing.assert_allclose(orig.center, paper["center"], atol=1e-6 + 10 * noise)
        np.testing.assert_allclose(orig.semi_axes, paper["semi_axes"], atol=1e-6 + 10 * noise)
    else:
        assert "no positive finite eigenvalue" in orig.message and "halir_flusser" in orig.message
    mod = methods.fit("ellipse.halir_flusser", pts)
    assert mod.converged, mod.message
    np.testing.assert_allclose(mod.center, paper["center"], atol=1e-8 + 10 * noise)
    np.testing.assert_allclose(mod.semi_axes, paper["semi_axes"], atol=1e-8 + 10 * noise)


@pytest.mark.parametrize("method_id", ALL)
def test_duplicates_do_not_count_toward_the_five_point_minimum(method_id):
    four = np.array([[0.0, 0.0], [2.0, 0.5], [1.0, 2.0], [-1.0, 1.0]])
    with pytest.raises(methods.InvalidInputError, match="5 distinct points, got 4 distinct among 12"):
        methods.fit(method_id, np.vstack([four, four, four]))
    five = ellipse_points((1.0, 2.0), (3.0, 1.0), 0.4, 5)
    res = methods.fit(method_id, np.vstack([five, five[:3]]))  # five distinct points determine the conic
    if method_id == "ellipse.algebraic_nm" and not res.converged:  # eq. 16 may collapse (see above): said so
        assert "degenerate" in res.message
    elif method_id != "ellipse.fitzgibbon":  # the original's eigenvalue is zero to rounding (see above)
        assert res.converged, res.message
        np.testing.assert_allclose(res.semi_axes, (3.0, 1.0), rtol=1e-6)


@pytest.mark.parametrize("method_id", ALL)
@pytest.mark.parametrize("size", [1e-150, 1e-100, 1e-20, 1.0, 1e20, 1e100, 1e150])
def test_every_size_from_1e_150_to_1e150(method_id, size):
    """Through methods.fit (the shared validation is scale-free): an exact ellipse of any size is
    recovered to 1e-8 relative, or (Fitzgibbon only, exact data) its lost eigenvalue is reported;
    no overflow/underflow warning escapes."""
    pts = ellipse_points((3 * size, -2 * size), (2 * size, size), 0.3, 40)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = methods.fit(method_id, pts)
    if method_id == "ellipse.fitzgibbon" and not res.converged:
        assert "no positive finite eigenvalue" in res.message
        return
    assert res.converged, res.message
    np.testing.assert_allclose(res.center, (3 * size, -2 * size), rtol=0, atol=1e-8 * size)
    np.testing.assert_allclose(res.semi_axes, (2 * size, size), rtol=1e-8)
    assert np.all(np.abs(res.residuals) <= 1e-8 * size) and res.form_error <= 1e-8 * size


@pytest.mark.parametrize("method_id", ALL)
def test_coordinates_of_1e300(method_id):
    """No traceback at coordinates of 1e300; an ellipse of size 1e299 there is found."""
    pts = ellipse_points((1e300, -1e300), (2e299, 1e299), 0.3, 40)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the shared validation is scale-free: no overflow warning
        res = methods.fit(method_id, pts)
    if method_id == "ellipse.fitzgibbon" and not res.converged:
        return
    # the points themselves are rounded to 1.5e-15 of the size here; Nelder–Mead ends in that noise, where
    # the probe may still find the data's least-squares ellipse lower (then it says so)
    assert res.converged or (method_id.endswith("_nm") and "not a stationary point" in res.message), res.message
    np.testing.assert_allclose(res.semi_axes, (2e299, 1e299), rtol=1e-8)
    assert np.isnan(res.conic).all() and "not representable" in res.extra["conic"]


@pytest.mark.parametrize("method_id", ["ellipse.algebraic_nm", "ellipse.geometric_nm"])
def test_nelder_mead_status_does_not_depend_on_the_last_bit(method_id):
    """The scaling study's setting (the paper's ellipse, table 3 start): the data moved by one ulp give the
    same status, far from the evaluation budget, and the same ellipse to the objective's resolution."""
    paper = dict(center=(1200.0, 650.0), semi_axes=(299.0243, 299.0022), angle=np.radians(32.04))
    kw = dict(start=(299.0, 299.0, 0.0, 1200.0, 650.0), step=(0.001, 0.001, 0.01, 0.001, 0.001))
    for n in (10, 100, 1000):
        pts = ellipse_points(n=n, noise=0.005, rng=np.random.default_rng(n), **paper)
        a = methods.fit(method_id, pts, **kw)
        b = methods.fit(method_id, np.nextafter(pts, np.inf), **kw)
        assert a.converged and b.converged, (a.message, b.message)
        assert max(a.nfev, b.nfev) < 50000 / 5
        np.testing.assert_allclose(a.center, b.center, atol=1e-5)


def test_nelder_mead_budget_is_reported():
    pts = ellipse_points((1.0, 2.0), (3.0, 1.0), 0.4, 50, noise=1e-3, rng=np.random.default_rng(1))
    res = methods.fit("ellipse.geometric_nm", pts, max_fev=30)
    assert not res.converged and ("budget" in res.message or "not a stationary point" in res.message)


def test_stationarity_probe_on_a_known_problem():
    """Rosenbrock as least squares r = (10 (y - x^2), 1 - x): stationary at (1, 1) only."""
    def r(q):
        return np.array([10 * (q[1] - q[0] ** 2), 1 - q[0]])

    def J(q):
        return np.array([[-20 * q[0], 10.0], [-1.0, 0.0]])

    noise = lambda r_, q: 1e-30  # noqa: E731
    assert stationarity_probe(r, J, np.array([1.0, 1.0]), noise=noise).stationary
    for q in ([-1.2, 1.0], [0.5, 0.25], [1.0 + 1e-4, 1.0 + 2e-4]):
        probe = stationarity_probe(r, J, np.array(q), noise=noise)
        assert not probe.stationary and probe.decrease > 0


def test_probe_from_a_triangular_factor_decides_as_from_the_jacobian():
    """``triangular=`` (the R of a QR of [J r], as ellipse.orthogonal's kernel and triangular_by_blocks give it)
    reaches the decisions of the Jacobian route on Rosenbrock as least squares, over many blocks of rows (the
    residuals repeated, scaled): stationary at (1, 1), not elsewhere, with the same decrease to rounding."""
    from methods.ellipse._checks import triangular_by_blocks
    reps = 3000
    w = np.linspace(0.5, 1.5, reps)

    def r(q, part=slice(None)):
        base = np.array([10 * (q[1] - q[0] ** 2), 1 - q[0]])
        return (w[:, None] * base[None, :]).ravel()[part]

    def J(q, part=slice(None)):
        base = np.array([[-20 * q[0], 10.0], [-1.0, 0.0]])
        return (w[:, None, None] * base[None, :, :]).reshape(-1, 2)[part]

    noise = lambda r_, q: 1e-30  # noqa: E731
    tri = triangular_by_blocks(J, r, 2 * reps, block=256)
    assert stationarity_probe(r, None, np.array([1.0, 1.0]), noise=noise, triangular=tri).stationary
    for q in ([-1.2, 1.0], [0.5, 0.25], [1.0 + 1e-4, 1.0 + 2e-4]):
        a = stationarity_probe(r, J, np.array(q), noise=noise)
        b = stationarity_probe(r, None, np.array(q), noise=noise, triangular=tri)
        assert not a.stationary and not b.stationary
        assert b.decrease == pytest.approx(a.decrease, rel=1e-9)


def test_blocked_noise_bound_is_the_formula():
    """sum_of_squares_noise, taken in blocks of NOISE_BLOCK points (small temporaries), equals 2 sum |r_i| dr_i +
    sum dr_i^2, dr_i = 4 eps size_i, to rounding, whether the sizes are a scalar, an array or a function of a
    slice."""
    from methods.ellipse import _checks
    rng = np.random.default_rng(3)
    eps = np.finfo(float).eps
    for n in (1, 100, _checks.NOISE_BLOCK, 3 * _checks.NOISE_BLOCK + 17):
        r = rng.standard_normal(n) * 1e-3
        size = rng.uniform(0.5, 3.0, n)
        dr = 4 * eps * size
        want = 2 * np.sum(np.abs(r) * dr) + np.sum(dr * dr)
        assert _checks.sum_of_squares_noise(r, size) == pytest.approx(want, rel=1e-12)
        assert _checks.sum_of_squares_noise(r, lambda part: size[part]) == pytest.approx(want, rel=1e-12)
        dr1 = 4 * eps * 2.0
        assert _checks.sum_of_squares_noise(r, 2.0) == pytest.approx(2 * np.sum(np.abs(r)) * dr1 + n * dr1 * dr1,
                                                                        rel=1e-12)


def test_a_converged_claim_with_a_nan_ellipse_is_an_invalid_row():
    """A method building its result with ``ellipse_result`` from a NaN ellipse and claiming converged=True broke its
    promise: the row is ``invalid`` with the gate's reason, as for circles (tests/test_result_gate.py); the builder
    downgraded it to "not converged" ("no valid ellipse"). An ellipse that is infinite without NaN (a fit
    overflowing float64 in data units) is still downgraded, saying so and keeping the method's own words."""
    from experiments.rows import fit_row
    from methods._registry import _REGISTRY
    from methods.results import ellipse_result

    nan, inf = float("nan"), float("inf")
    claims = {"all": [nan] * 5, "semi_axis_b": [3.0, -2.0, 2.0, nan, 0.3], "center_x": [nan, -2.0, 2.0, 1.0, 0.3],
              "overflow": [inf, -2.0, 2.0, 1.0, 0.3]}

    @methods.register("ellipse.test_gate_nan", kind="closed form", summary="a NaN ellipse, converged",
                      reference="gate test")
    def nan_ellipse(points, *, which="all"):
        return ellipse_result(points, claims[which], converged=True, message="closed form")

    pts = ellipse_points((3.0, -2.0), (2.0, 1.0), 0.3, 40)
    task = {"study": "gate", "dataset": {"label": "ellipse"}, "repetition": 0, "seed": 1, "stream": (0,),
            "method": "ellipse.test_gate_nan", "params": {}}
    truth = {"center": (3.0, -2.0), "semi_axes": (2.0, 1.0), "angle": 0.3}
    try:
        for which, reason in (("all", "center_x = nan is not finite in a converged result"),
                              ("semi_axis_b", "semi_axis_b = nan is not finite in a converged result"),
                              ("center_x", "center_x = nan is not finite in a converged result")):
            res = methods.get("ellipse.test_gate_nan").unchecked(pts, which=which)
            assert res.converged and reason in methods.check_result(res, pts)
            row = fit_row({**task, "params": {"which": which}}, pts, truth)
            assert row["status"] == "invalid" and reason in row["message"], row
        res = methods.get("ellipse.test_gate_nan").unchecked(pts, which="overflow")
        assert not res.converged and methods.check_result(res, pts) is None
        assert "not representable in float64" in res.message and "centre (inf, -2)" in res.message
        assert res.message.endswith("the method said: closed form")
        row = fit_row({**task, "params": {"which": "overflow"}}, pts, truth)
        assert row["status"] == "not converged" and "float64" in row["message"], row
    finally:
        _REGISTRY.pop("ellipse.test_gate_nan", None)
