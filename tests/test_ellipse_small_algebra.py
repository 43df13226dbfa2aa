"""The ellipse fits' 2 x 2 and 3 x 3 algebra in plain floating point (the same bits on every CPU, never
LAPACK/BLAS) against LAPACK as the independent reference: Halir & Flusser's reduced eigenproblem and the
conic -> (centre, axes, angle) conversion, on random ellipses (short arcs, 100:1, near-circles to b/a = 1 - 1e-8,
exact and noisy data, far from the origin)."""
import numpy as np
import pytest

from methods.ellipse import direct
from methods.ellipse._geometry import Frame, canonical, conic_to_params, params_to_conic


def _lapack_halir_flusser(S):
    S1, S2, S3 = S[:3, :3], S[:3, 3:], S[3:, 3:]
    T = -np.linalg.solve(S3, S2.T)
    M = S1 + S2 @ T
    M = 0.5 * (M + M.T)
    w, V = np.linalg.eig(np.array([[0, 0, 0.5], [0, -1, 0], [0.5, 0, 0]]) @ M)
    V = V.real
    ok = np.flatnonzero(4 * V[0] * V[2] - V[1] ** 2 > 0)
    j = ok[np.argmin(np.abs(w.real[ok]))]
    k = np.concatenate([V[:, j], T @ V[:, j]])
    return k / np.linalg.norm(k) * np.sign(k[0]), w.real[j]


def _random_ellipse_points(rng):
    n = int(rng.integers(6, 400))
    t = rng.uniform(0, rng.uniform(0.5, 2 * np.pi), n)
    a = rng.uniform(1, 10)
    b = a * (rng.uniform(0.01, 1) if rng.random() < 0.5 else 1 - 10 ** rng.uniform(-8, -1))
    th = rng.uniform(0, np.pi)
    noise = rng.choice([0.0, 1e-6, 1e-3, 1e-1]) * a
    x, y = a * np.cos(t), b * np.sin(t)
    pts = np.c_[np.cos(th) * x - np.sin(th) * y, np.sin(th) * x + np.cos(th) * y]
    return pts + rng.uniform(-1e3, 1e3, 2) + noise * rng.standard_normal((n, 2))


@pytest.mark.parametrize("seed", range(4))
def test_halir_flusser_conic_agrees_with_lapack(seed):
    rng = np.random.default_rng(seed)
    for _ in range(250):
        frame = Frame.of(_random_ellipse_points(rng))
        S = direct.scatter(frame.x, frame.y)
        k, lam, why = direct.halir_flusser_conic(S.tolist())
        ref, lam_ref = _lapack_halir_flusser(S)
        assert k is not None, why
        k = k / np.linalg.norm(k) * np.sign(k[0])
        # both carry the rounding of an eigenvector whose condition reaches 1e6 on the near-circles
        np.testing.assert_allclose(k, ref, rtol=0, atol=1e-8)
        assert lam == pytest.approx(lam_ref, rel=1e-6, abs=1e-9)  # a zero eigenvalue (exact data) is rounding


def test_cubic_roots_and_null_vector():
    assert sorted(direct._cubic_roots(1.0, -6.0, 11.0, -6.0)) == pytest.approx([1.0, 2.0, 3.0], rel=1e-15)
    assert direct._cubic_roots(2.0, 0.0, 0.0, -16.0) == pytest.approx([2.0], rel=1e-15)
    A = np.diag([1.0, 2.0, 0.0])
    assert np.abs(direct.null_vector3(A.tolist())) == pytest.approx([0.0, 0.0, 1.0])
    assert direct.null_vector3(np.zeros((3, 3)).tolist()) is None


def test_conic_to_params_as_accurate_as_lapack():
    rng = np.random.default_rng(3)
    worst, worst_lapack = 0.0, 0.0
    for _ in range(5000):
        a = rng.uniform(0.1, 10)
        b = a * (rng.uniform(0.01, 1) if rng.random() < 0.5 else 1 - 10 ** rng.uniform(-12, -1))
        p = np.array([rng.uniform(-5, 5), rng.uniform(-5, 5), a, b, rng.uniform(0, np.pi)])
        k = params_to_conic(p)
        A, B, C, D, E, F = k
        M = np.array([[A, B / 2], [B / 2, C]])
        xc, yc = np.linalg.solve(M, [-D / 2, -E / 2])
        w, V = np.linalg.eigh(M)
        axes = np.sqrt(-(F + 0.5 * (D * xc + E * yc)) / w)
        ref = canonical([xc, yc, axes[0], axes[1], np.arctan2(V[1, 0], V[0, 0])])
        got = conic_to_params(k)
        worst = max(worst, np.abs(got[:4] - p[:4]).max() / a)
        worst_lapack = max(worst_lapack, np.abs(ref[:4] - p[:4]).max() / a)
        if b / a < 0.999:
            assert abs((got[4] - p[4] + np.pi / 2) % np.pi - np.pi / 2) < 1e-12
    assert worst <= 2 * worst_lapack + 1e-15, (worst, worst_lapack)


def test_solve3_columns_gives_the_bits_of_separate_solves():
    """Halir-Flusser's T = -S3^-1 S2^T: one elimination for the three right-hand sides, bitwise the same as three
    solves by the circle kernel's compiled solve3 (an independent implementation of the same elimination, which
    the Python one claims to match bit for bit) on random, badly scaled, pivoting and singular systems."""
    from methods._compiled import kernels
    from methods._frame import solve3, solve3_columns

    ck = kernels("methods.circle._ckernels")
    assert ck is not None, "the circle kernel must be built for this test"

    rng = np.random.default_rng(33)
    for trial in range(2000):
        a = rng.standard_normal(9) * 10.0 ** rng.integers(-150, 150, 9) if trial % 3 == 0 else rng.standard_normal(9)
        if trial % 7 == 0:
            a[3:6] = a[0:3] * 2.0  # singular
        rhs = [list(rng.standard_normal(3)) for _ in range(3)]
        got = solve3_columns(list(a), rhs)
        want = [ck.solve3(tuple(a), tuple(b)) for b in rhs]
        if any(w is None for w in want):
            assert got is None and solve3(list(a), rhs[0]) is None
        else:
            assert got is not None and all(list(g) == list(w) for g, w in zip(got, want)), trial
            assert solve3(list(a), rhs[0]) == got[0]


def test_generalized_eig_gives_the_bits_of_scipy_eig():
    """ellipse.fitzgibbon's direct dggev call against scipy.linalg.eig(S, C): bitwise equal eigenvalues and
    eigenvectors on scatter matrices of random ellipses (exact and noisy, short arcs) and random symmetric S."""
    import scipy.linalg as sla
    from methods.ellipse.direct import C6, generalized_eig, scatter
    from methods.ellipse._geometry import Frame

    rng = np.random.default_rng(66)
    for trial in range(300):
        t = rng.uniform(0, rng.uniform(0.3, 2 * np.pi), 200)
        a, b = rng.uniform(0.5, 5, 2)
        pts = np.c_[a * np.cos(t), b * np.sin(t)] + rng.uniform(-10, 10, 2)
        if trial % 2:
            pts = pts + rng.normal(0, 10.0 ** rng.uniform(-8, -1), pts.shape)
        f = Frame.of(pts)
        S = scatter(f.x, f.y) if trial % 5 else (lambda m: m @ m.T)(rng.standard_normal((6, 6)))
        w, V = generalized_eig(S, C6)
        w_ref, V_ref = sla.eig(S, C6)
        assert np.array_equal(w, w_ref, equal_nan=True) and np.array_equal(V, V_ref), trial
