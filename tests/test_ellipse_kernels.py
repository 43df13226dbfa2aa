"""The compiled orthogonal residuals (methods/ellipse/_ckernels.c) against the NumPy reference path
(methods/ellipse/_geometry.py, FITBENCH_KERNELS=numpy) and against an independent dense search.

Both paths solve the same first-quadrant root (Eberly); the reference stops Newton when a whole block of
points has converged, the kernel point by point, so they agree to the solver's rounding: the distance is a
difference of coordinates of size L = max(|u|, |v|, a), each correct to a few eps, so 64 eps L bounds the
difference (measured: below 2 eps L). phi agrees to 64 eps rad where the closest point is well defined."""
import numpy as np
import pytest

from methods._compiled import kernels
from methods.ellipse import _geometry as geometry

EPS = np.finfo(float).eps


def both_paths(monkeypatch, x, y, p, with_phi=True):
    monkeypatch.delenv("FITBENCH_KERNELS", raising=False)
    compiled = geometry.orthogonal_residuals(x, y, p, with_phi=with_phi)
    monkeypatch.setenv("FITBENCH_KERNELS", "numpy")
    reference = geometry.orthogonal_residuals(x, y, p, with_phi=with_phi)
    monkeypatch.delenv("FITBENCH_KERNELS")
    return compiled, reference


def cases():
    rng = np.random.default_rng(20)
    t = rng.uniform(0, 2 * np.pi, 4000)
    ring = np.c_[np.cos(t), np.sin(t)]
    yield "noisy 299 mm", ring * (299.0243, 299.0022) + rng.normal(0, 0.005, (4000, 2)) + (1200, 650), \
        (1200.0, 650.0, 299.0243, 299.0022, 0.0)
    yield "elongated 10:1", ring * (10.0, 1.0) * rng.uniform(0.2, 3.0, (4000, 1)), (0.0, 0.0, 10.0, 1.0, 0.3)
    yield "b > a", ring * (1.0, 4.0) * rng.uniform(0.0, 2.0, (4000, 1)), (0.0, 0.0, 1.0, 4.0, -1.1)
    yield "near circle", ring * (5.0, 5.0 * (1 - 1e-9)) * rng.uniform(0.5, 1.5, (4000, 1)), (0.0, 0.0, 5.0, 5.0 * (1 - 1e-9), 2.0)
    yield "partial arc", ring[t < 1.0] * (3.0, 2.0) + rng.normal(0, 0.01, ((t < 1.0).sum(), 2)), (0.0, 0.0, 3.0, 2.0, 0.0)
    grid = np.array([(u, v) for u in (-3.0, -1.0, 0.0, 0.5, 1.0, 2.9, 3.0, 4.0) for v in (-2.0, 0.0, 1e-300, 0.5, 2.0)])
    yield "axes, centre, evolute", grid, (0.0, 0.0, 3.0, 2.0, 0.0)
    yield "scale 1e-150", ring * (3e-150, 2e-150) * rng.uniform(0.5, 1.5, (4000, 1)), (0.0, 0.0, 3e-150, 2e-150, 0.7)
    yield "scale 1e150", ring * (3e150, 2e150) * rng.uniform(0.5, 1.5, (4000, 1)), (0.0, 0.0, 3e150, 2e150, 0.7)


@pytest.mark.parametrize("name,points,p", list(cases()), ids=[c[0] for c in cases()])
def test_compiled_residuals_match_the_numpy_reference(monkeypatch, name, points, p):
    assert kernels("methods.ellipse._ckernels") is not None, "the ellipse kernel must be built for this test"
    x, y = points[:, 0], points[:, 1]  # strided columns, as the result builder passes them
    (d, phi), (d_ref, phi_ref) = both_paths(monkeypatch, x, y, p)
    size = np.maximum(np.hypot(x - p[0], y - p[1]), max(p[2], p[3]))
    assert np.all(np.isfinite(d)) and np.all(np.isfinite(phi))
    assert np.all(np.abs(d - d_ref) <= 64 * EPS * size), np.max(np.abs(d - d_ref) / size) / EPS
    well_defined = np.abs(d_ref) < 0.5 * min(p[2], p[3])  # away from the centre's ambiguous closest points
    dphi = np.abs((phi - phi_ref + np.pi) % (2 * np.pi) - np.pi)
    assert np.all(dphi[well_defined] <= 64 * EPS * 2 * np.pi)


def test_compiled_distances_are_the_minimum_over_a_dense_search():
    """Independent check: |d| equals the smallest distance to 2^20 points of the ellipse to the search's
    resolution: with samples h apart along the curve, the nearest sample lies within h/2 of the closest
    point, so the sampled distance exceeds the true one by at most min(h/2, (h/2)^2 / (2 d)); a factor 2
    margin covers the curvature term. The sign says inside/outside."""
    rng = np.random.default_rng(7)
    a, b, theta, xc, yc = 3.0, 1.2, 0.4, 0.5, -0.2
    pts = rng.uniform(-5, 5, (300, 2))
    d, _ = geometry.orthogonal_residuals(pts[:, 0], pts[:, 1], (xc, yc, a, b, theta), with_phi=False)
    s = np.linspace(0, 2 * np.pi, 2 ** 20, endpoint=False)
    c, sn = np.cos(theta), np.sin(theta)
    ex = xc + a * np.cos(s) * c - b * np.sin(s) * sn
    ey = yc + a * np.cos(s) * sn + b * np.sin(s) * c
    step = 2 * np.pi * a / 2 ** 20
    for (px, py), di in zip(pts, d):
        best = np.sqrt(np.min((ex - px) ** 2 + (ey - py) ** 2))
        assert best - min(step / 2, step ** 2 / (4 * best)) - 1e-12 <= abs(di) <= best + 1e-12
        inside = ((px - xc) * c + (py - yc) * sn) ** 2 / a ** 2 + (-(px - xc) * sn + (py - yc) * c) ** 2 / b ** 2 < 1
        assert (di < 0) == inside


def test_bad_buffers_are_refused_with_a_message():
    ck = kernels("methods.ellipse._ckernels")
    x = np.zeros(4)
    with pytest.raises(ValueError, match="same length"):
        ck.orthogonal(x, np.zeros(3), 0.0, 0.0, 1.0, 0.0, 2.0, 1.0, 60, np.empty(4))
    with pytest.raises(TypeError, match="1-D float64"):
        ck.orthogonal(x.astype(np.float32), x, 0.0, 0.0, 1.0, 0.0, 2.0, 1.0, 60, np.empty(4))
    with pytest.raises(ValueError, match="semi-axes"):
        ck.orthogonal(x, x, 0.0, 0.0, 1.0, 0.0, -2.0, 1.0, 60, np.empty(4))


@pytest.mark.parametrize("scale", [1e-150, 1.0, 1e150])
def test_compiled_distances_scale_with_the_data(scale):
    """On-axis points inside the evolute (closed form X = a^2 u / (a^2 - b^2)) and general points give the
    unit-size distances times the scale: no overflow of a^2 u at 1e150, no underflow at 1e-150 (on both the
    compiled and the NumPy path)."""
    pts = np.array([[1.0, 0.0], [-1.5, 0.0], [0.3, 0.0], [4.0, 1.0], [-0.2, 0.7]])
    unit, _ = geometry.orthogonal_residuals(pts[:, 0], pts[:, 1], (0.0, 0.0, 3.0, 2.0, 0.0), with_phi=False)
    scaled, _ = geometry.orthogonal_residuals(pts[:, 0] * scale, pts[:, 1] * scale,
                                              (0.0, 0.0, 3.0 * scale, 2.0 * scale, 0.0), with_phi=False)
    assert unit[0] == pytest.approx(-np.hypot(1.0 - 1.8, 1.6), rel=1e-14)  # X = 9/5, Y = 2 sqrt(1 - 0.36)
    assert np.all(np.abs(scaled / scale - unit) <= 64 * EPS * 4.0)


@pytest.mark.parametrize("iterations", [1, 3, 50])
def test_four_points_at_a_time_gives_the_bits_of_one_at_a_time(iterations):
    """The kernel solves LANES (16) points per block (packed steps) and the remainder one by one: every point's
    distance and parameter are bitwise those of the one-point solver (a length-1 call), points on the axes,
    near the centre (bisection) and far away included."""
    ck = kernels("methods.ellipse._ckernels")
    assert ck is not None, "the ellipse kernel must be built for this test"
    rng = np.random.default_rng(iterations)
    for a, b in ((3.0, 1.0), (1.0, 3.0), (2.0, 2.0 * (1 - 1e-9)), (10.0, 0.1)):
        pts = np.vstack([rng.standard_normal((61, 2)) * 3, [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1e-9, 1e-9]]])
        pts = pts[rng.permutation(len(pts))]  # the special points anywhere in a block (or in the remainder)
        x, y = np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1])
        c, s = np.cos(0.4), np.sin(0.4)
        d, phi = np.empty(len(x)), np.empty(len(x))
        ck.orthogonal(x, y, 0.3, -0.1, c, s, a, b, iterations, d, phi)
        for i in range(len(x)):
            d1, p1 = np.empty(1), np.empty(1)
            ck.orthogonal(x[i:i + 1], y[i:i + 1], 0.3, -0.1, c, s, a, b, iterations, d1, p1)
            assert d1[0] == d[i] and p1[0] == phi[i], (a, b, i)


# ---- ellipse.orthogonal's per-iteration kernel: distances and Jacobian in one sweep ----------------------------

@pytest.mark.parametrize("name,points,p", list(cases()), ids=[c[0] for c in cases()])
def test_distances_jacobian_match_the_residual_kernel_and_the_numpy_jacobian(monkeypatch, name, points, p):
    """distances_jacobian's d is orthogonal()'s, bit for bit (the same closest points); its Jacobian (transposed,
    (5, N)) is methods.ellipse.orthogonal.distance_jacobian at the reference phi to rounding: every entry is a
    product of unit-size factors (normal components, cos/sin phi) and, for theta, the semi-axes, so 64 eps
    max(1, a, b) bounds the difference where the closest point is well defined (away from the centre's ambiguous
    closest points, where phi itself is ill-conditioned)."""
    from methods.ellipse.orthogonal import distance_jacobian

    ck = kernels("methods.ellipse._ckernels")
    assert ck is not None, "the ellipse kernel must be built for this test"
    x, y = points[:, 0], points[:, 1]
    xc, yc, a, b, t = p
    d, Jt = np.empty(len(x)), np.empty((5, len(x)))
    ck.distances_jacobian(x, y, xc, yc, float(np.cos(t)), float(np.sin(t)), a, b, 60, d, Jt)
    d_kernel = np.empty(len(x))
    ck.orthogonal(x, y, xc, yc, float(np.cos(t)), float(np.sin(t)), a, b, 60, d_kernel)
    assert np.array_equal(d, d_kernel)
    monkeypatch.setenv("FITBENCH_KERNELS", "numpy")
    d_ref, phi_ref = geometry.orthogonal_residuals(x, y, p)
    J_ref = distance_jacobian(x, y, p, phi_ref)
    well_defined = np.abs(d_ref) < 0.5 * min(a, b)
    assert np.all(np.isfinite(Jt))
    err = np.abs(Jt.T - J_ref)[well_defined] / np.array([1, 1, 1, 1, max(1.0, a, b)])
    assert np.all(err <= 64 * EPS), err.max() / EPS


def test_distances_jacobian_refuses_bad_buffers():
    ck = kernels("methods.ellipse._ckernels")
    x = np.zeros(4)
    with pytest.raises(ValueError, match=r"\(5, N\)"):
        ck.distances_jacobian(x, x, 0.0, 0.0, 1.0, 0.0, 2.0, 1.0, 60, np.empty(4), np.empty((4, 5)))
    with pytest.raises(ValueError, match="semi-axes"):
        ck.distances_jacobian(x, x, 0.0, 0.0, 1.0, 0.0, 2.0, 0.0, 60, np.empty(4), np.empty((5, 4)))


def _orthogonal_cases():
    rng = np.random.default_rng(2020)
    t = rng.uniform(0, 2 * np.pi, 3358)
    yield "paper near-circle", np.c_[299.0243 * np.cos(t), 299.0022 * np.sin(t)] @ np.array(
        [[np.cos(0.56), np.sin(0.56)], [-np.sin(0.56), np.cos(0.56)]]) + (1200.0, 650.0) + rng.normal(0, 0.005, (3358, 2))
    s = rng.uniform(0.2, 1.4, 500)
    yield "short arc 3:1 far away", np.c_[3.0 * np.cos(s), np.sin(s)] + (1e6, -2e6) + rng.normal(0, 1e-3, (500, 2))
    u = rng.uniform(0, 2 * np.pi, 800)
    yield "10:1 at 1e-150", (np.c_[10.0 * np.cos(u), np.sin(u)] + rng.normal(0, 0.05, (800, 2))) * 1e-150
    yield "5:4 at 1e150", (np.c_[5.0 * np.cos(u), 4.0 * np.sin(u)] + rng.normal(0, 0.05, (800, 2))) * 1e150


@pytest.mark.parametrize("name,points", list(_orthogonal_cases()), ids=[c[0] for c in _orthogonal_cases()])
def test_orthogonal_fit_compiled_matches_the_numpy_path(monkeypatch, name, points):
    """ellipse.orthogonal with the fused kernel against the NumPy reference path (phi, then the Jacobian): the
    same minimum to 1e-9 of the data's size (both paths stop at MINPACK's xtol = 1e-15 relative; their Jacobians
    differ by rounding, so the iterates do too), the same flags and a stationary point on both."""
    import methods

    monkeypatch.delenv("FITBENCH_KERNELS", raising=False)
    fast = methods.fit("ellipse.orthogonal", points)
    monkeypatch.setenv("FITBENCH_KERNELS", "numpy")
    ref = methods.fit("ellipse.orthogonal", points)
    size = float(np.ptp(points, axis=0).max())
    assert fast.converged and ref.converged, (fast.message, ref.message)
    assert fast.extra["stationarity"]["stationary"] and ref.extra["stationarity"]["stationary"]
    assert np.allclose(fast.center, ref.center, rtol=0, atol=1e-9 * size)
    assert np.allclose(fast.semi_axes, ref.semi_axes, rtol=0, atol=1e-9 * size)
    assert abs((fast.angle - ref.angle + np.pi / 2) % np.pi - np.pi / 2) <= 1e-9 * size / min(ref.semi_axes)
    assert np.allclose(fast.residuals, ref.residuals, rtol=0, atol=1e-9 * size)
    assert len(fast.history) == fast.iterations and fast.nfev >= fast.iterations


@pytest.mark.parametrize("n", [5, 255, 256, 257, 3358, 100_000])
def test_compiled_scatter_matches_the_numpy_moments(n, monkeypatch):
    """The direct fits' 6 x 6 scatter from one compiled sweep (blocked pairwise sums) against NumPy's
    products and pairwise sums: equal to a few ulps of each moment's scale (sum of |terms|)."""
    from methods.ellipse import direct
    rng = np.random.default_rng(n)
    t = rng.uniform(0, 2.0, n)
    pts = np.c_[3 * np.cos(t), np.sin(t)] + 1e-3 * rng.standard_normal((n, 2))
    frame = geometry.Frame.of(pts)
    compiled = direct.scatter(frame.x, frame.y)
    monkeypatch.setenv("FITBENCH_KERNELS", "numpy")
    reference = direct.scatter(frame.x, frame.y)
    absolute = direct.scatter(np.abs(frame.x), np.abs(frame.y))
    assert np.all(np.abs(compiled - reference) <= 64 * np.finfo(float).eps * absolute + 1e-300)


def _hard_scatter_cases():
    rng = np.random.default_rng(150)
    s = rng.uniform(0.0, 0.3, 2000)  # a short arc (0.3 rad) of a 3:1 ellipse
    arc = np.c_[3.0 * np.cos(s), np.sin(s)] + 1e-6 * rng.standard_normal((2000, 2))
    yield "short arc at 1e6", arc + 1e6
    yield "short arc at 1e-150", arc * 1e-150
    yield "short arc at 1e150, centre 1e152", arc * 1e150 + 1e152
    t = rng.uniform(0, 2 * np.pi, 100_001)
    yield "near circle 1e5 points at 1e6", np.c_[299.0243 * np.cos(t), 299.0022 * np.sin(t)] + 1e6 + \
        0.005 * rng.standard_normal((100_001, 2))


@pytest.mark.parametrize("name,points", list(_hard_scatter_cases()), ids=[c[0] for c in _hard_scatter_cases()])
def test_compiled_scatter_on_hard_data(monkeypatch, name, points):
    """The compiled scatter of the unit-frame coordinates against NumPy's on far-away, short-arc and extreme-scale
    data: within 64 eps of each moment's scale (the same moments of |x|, |y|). Halir-Flusser's ellipse from either
    path: the same to 1e-9 of its size on the well-conditioned full ring; on the 0.3 rad arcs the fit itself
    amplifies the moments' last-bit differences (measured: the two paths' centres differ by ~1.3e-9 of the size at
    1e+-150), so there only the flags are compared."""
    from methods.ellipse import direct
    import methods

    frame = geometry.Frame.of(points)
    compiled = direct.scatter(frame.x, frame.y)
    monkeypatch.setenv("FITBENCH_KERNELS", "numpy")
    reference = direct.scatter(frame.x, frame.y)
    absolute = direct.scatter(np.abs(frame.x), np.abs(frame.y))
    assert np.all(np.abs(compiled - reference) <= 64 * EPS * absolute + 1e-300)
    ref_fit = methods.fit("ellipse.halir_flusser", points)
    monkeypatch.delenv("FITBENCH_KERNELS")
    fit = methods.fit("ellipse.halir_flusser", points)
    size = float(np.ptp(points, axis=0).max())
    assert fit.converged == ref_fit.converged
    if fit.converged and not name.startswith("short arc"):
        assert np.allclose(fit.center, ref_fit.center, rtol=0, atol=1e-9 * max(size, np.abs(fit.semi_axes).max()))
        assert np.allclose(fit.semi_axes, ref_fit.semi_axes, rtol=1e-9, atol=0)
