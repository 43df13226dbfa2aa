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


# ---- ellipse.orthogonal's per-iteration kernel: distances and the R of [J d] in one sweep --------------------

def _unit(points, p):
    """Points and ellipse in the unit frame ellipse.orthogonal calls the kernel in (centred, unit RMS radius)."""
    frame = geometry.Frame.of(points)
    return frame.x, frame.y, frame.params_to_unit(p)


def _kernel_qr(x, y, p):
    ck = kernels("methods.ellipse._ckernels")
    assert ck is not None, "the ellipse kernel must be built for this test"
    xc, yc, a, b, t = (float(v) for v in p)
    d, R = np.empty(len(x)), np.empty((6, 6))
    S = ck.distances_qr(x, y, xc, yc, float(np.cos(t)), float(np.sin(t)), a, b, 60, d, R)
    return d, R, S


@pytest.mark.parametrize("name,points,p", list(cases()), ids=[c[0] for c in cases()])
def test_distances_qr_matches_the_residual_kernel_and_lapack(monkeypatch, name, points, p):
    """distances_qr's d is orthogonal()'s, bit for bit (the same closest points), its sum of squares is sum d^2 to
    (64 + log2 N) eps, and its R is the R of a QR of [J d] with J = methods.ellipse.orthogonal.distance_jacobian at
    the NumPy reference's closest points: upper triangular, and R^T R = [J d]^T [J d] to 64 eps w_i w_j per entry,
    w_j = |A_j| + sqrt(N) s_j covering the two Jacobians' own rounding (backward stability; Householder's R is
    unique only up to the signs of its rows). Where [J d] has full,
    moderate condition and entries well above their rounding, the least-squares step -R1^-1 q equals LAPACK's lstsq(J, -d) to 1e4 eps cond. Every case in
    the unit frame, as ellipse.orthogonal calls it (the QR is unscaled: entries must stay below ~1e150 / sqrt N)."""
    from methods.ellipse.orthogonal import distance_jacobian

    x, y, pu = _unit(points, p)
    d, R, S = _kernel_qr(x, y, pu)
    ck = kernels("methods.ellipse._ckernels")
    d_kernel = np.empty(len(x))
    ck.orthogonal(x, y, *pu[:2], float(np.cos(pu[4])), float(np.sin(pu[4])), *pu[2:4], 60, d_kernel)
    assert np.array_equal(d, d_kernel)
    assert abs(S - float(np.dot(d, d))) <= (64 + np.log2(len(d))) * EPS * float(np.dot(d, d)) + 1e-300
    assert np.array_equal(R, np.triu(R)) and np.isfinite(R).all()
    monkeypatch.setenv("FITBENCH_KERNELS", "numpy")
    d_ref, phi_ref = geometry.orthogonal_residuals(x, y, pu)
    well_defined = np.abs(d_ref) < 0.5 * min(pu[2], pu[3])  # away from the centre's ambiguous closest points
    if not well_defined.all():
        return  # a different closest point (both exact) changes J's rows: only the kernel's own consistency above
    A = np.column_stack([distance_jacobian(x, y, pu, phi_ref), d])
    norms = np.sqrt(np.einsum("ij,ij->j", A, A))
    # the two Jacobians differ per entry by up to 64 eps s_j (s = 1, and max(1, a, b) for theta, whose entries
    # cancel on near-circles; d is the same): |A_i| + sqrt(N) s_i bounds what each column contributes
    s = np.array([1.0, 1.0, 1.0, 1.0, max(1.0, pu[2], pu[3]), 0.0])
    w = norms + np.sqrt(len(d)) * s
    assert np.all(np.abs(R.T @ R - A.T @ A) <= 64 * EPS * np.outer(w, w) + 1e-300)
    J = A[:, :5]
    cond = np.linalg.cond(J / norms[:5])
    if cond < 1e8 and np.all(np.sqrt(len(d)) * s[:5] <= 1e6 * norms[:5]):  # (the near circle's theta column is
        # below its entries' own rounding, eps max(a, b): the two Jacobians disagree there before any QR)
        step = np.linalg.solve(R[:5, :5], -R[:5, 5])
        ref = np.linalg.lstsq(J, -d, rcond=None)[0]
        scale = np.abs(ref).max() + np.linalg.norm(d) / norms[:5].min()
        assert np.all(np.abs(step - ref) <= 1e4 * EPS * cond * scale), (np.abs(step - ref).max(), cond)


@pytest.mark.parametrize("n", [1, 2, 15, 16, 17, 63, 64, 65, 129, 1000, 4097])
def test_distances_qr_blocks_and_tails(n):
    """Every partition of the sweep (16-point blocks, single points at the tail, 64-point leaves and their pairwise
    merges): R^T R = [J d]^T [J d] to rounding and d bitwise the one-point solver's, for N around the block sizes."""
    from methods.ellipse.orthogonal import distance_jacobian

    rng = np.random.default_rng(n)
    t = rng.uniform(0, 2 * np.pi, n)
    x, y = 1.3 * np.cos(t) + 1e-3 * rng.standard_normal(n), 0.7 * np.sin(t) + 1e-3 * rng.standard_normal(n)
    p = np.array([0.01, -0.02, 1.3, 0.7, 0.3])
    d, R, S = _kernel_qr(x, y, p)
    for i in range(0, n, max(1, n // 7)):
        d1, _, S1 = _kernel_qr(x[i:i + 1], y[i:i + 1], p)
        assert d1[0] == d[i] and S1 == d[i] * d[i]
    _, phi = geometry.orthogonal_residuals(x, y, p)
    A = np.column_stack([distance_jacobian(x, y, p, phi), d])
    norms = np.sqrt(np.einsum("ij,ij->j", A, A))
    assert np.array_equal(R, np.triu(R))
    assert np.all(np.abs(R.T @ R - A.T @ A) <= 64 * EPS * np.outer(norms, norms))


def test_distances_qr_refuses_bad_buffers():
    ck = kernels("methods.ellipse._ckernels")
    x = np.zeros(4)
    with pytest.raises(ValueError, match=r"\(6, 6\)"):
        ck.distances_qr(x, x, 0.0, 0.0, 1.0, 0.0, 2.0, 1.0, 60, np.empty(4), np.empty((5, 6)))
    with pytest.raises((ValueError, BufferError), match="C-contiguous"):
        ck.distances_qr(x, x, 0.0, 0.0, 1.0, 0.0, 2.0, 1.0, 60, np.empty(4), np.empty((6, 12))[:, ::2])
    with pytest.raises(ValueError, match="semi-axes"):
        ck.distances_qr(x, x, 0.0, 0.0, 1.0, 0.0, 2.0, 0.0, 60, np.empty(4), np.empty((6, 6)))


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
    """ellipse.orthogonal with the fused kernel against the NumPy reference path (phi, the Jacobian, LAPACK's QR):
    the same minimum to 1e-9 of the data's size (both paths stop at MINPACK's xtol = 1e-15 relative; their Jacobians
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


def _build_without_clones(tmp_path):
    """The ellipse kernel compiled as setup.py compiles it, plus -DFITBENCH_NO_CLONES (no AVX clone: SSE2 only)."""
    import ast
    import importlib.util
    import pathlib
    import sysconfig

    from setuptools import Distribution, Extension

    root = pathlib.Path(__file__).resolve().parents[1]
    tree = ast.parse((root / "setup.py").read_text())
    flags = next(ast.literal_eval(node.value) for node in tree.body if isinstance(node, ast.Assign)
                 and getattr(node.targets[0], "id", "") == "COMPILE_ARGS")
    ext = Extension("_ckernels", [str(root / "methods/ellipse/_ckernels.c")],
                    extra_compile_args=[*flags, "-DFITBENCH_NO_CLONES"])
    dist = Distribution({"ext_modules": [ext], "script_name": "setup.py"})
    cmd = dist.get_command_obj("build_ext")
    cmd.build_lib, cmd.build_temp = str(tmp_path / "lib"), str(tmp_path / "tmp")
    cmd.ensure_finalized()
    cmd.run()
    path = tmp_path / "lib" / ("_ckernels" + sysconfig.get_config_var("EXT_SUFFIX"))
    spec = importlib.util.spec_from_file_location("_ckernels", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_sse2_only_build_gives_the_same_bits(tmp_path):
    """The closest-point solver and the QR of distances_qr run in 4-lane vectors: AVX instructions where the CPU
    has AVX (load-time clones), SSE2 pairs elsewhere. Lane-wise IEEE operations in the same order give the same
    bits: the SSE2-only build (-DFITBENCH_NO_CLONES) against the installed one, orthogonal() (distances and phi,
    points on the axes and at the centre included, 1 to 60 Newton steps) and distances_qr, on awkward sizes and a
    10^5-point near circle (on a CPU with AVX this compares the two instruction sets; on one without, both builds
    run SSE2)."""
    ck = kernels("methods.ellipse._ckernels")
    assert ck is not None, "the ellipse kernel must be built for this test"
    sse2 = _build_without_clones(tmp_path)
    rng = np.random.default_rng(7)
    for n, axes in ((1, (2.0, 1.0)), (63, (2.0, 1.0)), (1000, (1.0, 3.0)), (100_000, (1.0, 1.0 - 1e-5))):
        t = rng.uniform(0, 2 * np.pi, n)
        x = axes[0] * np.cos(t) + 1e-3 * rng.standard_normal(n)
        y = axes[1] * np.sin(t) + 1e-3 * rng.standard_normal(n)
        args = (x, y, 0.01, -0.02, float(np.cos(0.3)), float(np.sin(0.3)), axes[0], axes[1], 60)
        outs = []
        for module in (ck, sse2):
            d, R = np.empty(n), np.empty((6, 6))
            S = module.distances_qr(*args, d, R)
            outs.append((d, R, S))
        assert np.array_equal(outs[0][0], outs[1][0]) and np.array_equal(outs[0][1], outs[1][1]), n
        assert outs[0][2] == outs[1][2]
    for iterations in (1, 3, 60):
        pts = np.vstack([rng.standard_normal((250, 2)) * 3, [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1e-9, 1e-9]]])
        x, y = np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1])
        for a, b in ((3.0, 1.0), (1.0, 3.0), (2.0, 2.0 * (1 - 1e-9)), (10.0, 0.1)):
            res = []
            for module in (ck, sse2):
                d, phi = np.empty(len(x)), np.empty(len(x))
                module.orthogonal(x, y, 0.3, -0.1, float(np.cos(0.4)), float(np.sin(0.4)), a, b, iterations, d, phi)
                res.append((d, phi))
            assert np.array_equal(res[0][0], res[1][0]) and np.array_equal(res[0][1], res[1][1]), (a, b, iterations)
