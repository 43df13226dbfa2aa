"""Each method minimises what its docstring says (scikit-image #5186 is the cautionary tale).

Checks are independent of the implementations: objectives are evaluated directly in data units,
perturbations are random, and the second algorithm is SciPy's generalised eigensolver.
"""
import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import minimize

import methods
from datasets.synthetic import circle_points


@pytest.fixture
def data(rng):
    # 40 points on a 120-degree arc of a 299 mm circle at machine coordinates, 5 µm noise
    return circle_points((1200.0, 650.0), 299.0, 40, arc=(0.2, 0.2 + 2 * np.pi / 3), noise=0.005, rng=rng)


def s_cg(points, p):
    """Geometric sum of squares S_CG (circle/ellipse paper eq. 9)."""
    d = np.hypot(points[:, 0] - p[0], points[:, 1] - p[1]) - p[2]
    return float(d @ d)


def s_ca(points, p):
    """Algebraic sum of squares S_CA (circle/ellipse paper eq. 5)."""
    e = (points[:, 0] - p[0]) ** 2 + (points[:, 1] - p[1]) ** 2 - p[2] ** 2
    return float(e @ e)


def no_better_nearby(objective, p, scales, rng, rel=1e-12, trials=400):
    f0 = objective(p)
    for scale in scales:
        steps = rng.normal(size=(trials, 3)) * scale
        values = np.array([objective(p + dp) for dp in steps])
        assert values.min() >= f0 * (1 - rel), f"a perturbation of size {scale} lowers the objective"


@pytest.mark.parametrize("method_id", ["circle.gauss_newton", "circle.levenberg_marquardt", "circle.nelder_mead"])
def test_geometric_methods_minimise_s_cg(method_id, data, rng):
    res = methods.fit(method_id, data)
    p = np.array([*res.center, res.radius])
    rel = 1e-9 if method_id == "circle.nelder_mead" else 1e-12
    no_better_nearby(lambda q: s_cg(data, q), p, [1e-2, 1e-4, 1e-6], rng, rel=rel)
    # and an independent optimiser started elsewhere finds no lower value
    other = minimize(lambda q: s_cg(data, q), p + [0.5, -0.5, 0.3], method="BFGS", options={"gtol": 1e-10})
    assert s_cg(data, p) <= other.fun * (1 + rel)


@pytest.mark.parametrize("method_id", ["circle.kasa", "circle.powell_hybrid"])
def test_kasa_and_powell_minimise_the_same_algebraic_objective(method_id, data, rng):
    """Kåsa's linear system (roundness eq. 7) and FCA's grad S_CA = 0 (circle/ellipse eq. 6) are the
    same function in other coordinates (w = xc^2 + yc^2 - R^2): both give the minimiser of S_CA."""
    res = methods.fit(method_id, data)
    p = np.array([*res.center, res.radius])
    no_better_nearby(lambda q: s_ca(data, q), p, [1e-2, 1e-4, 1e-6], rng)
    other = methods.fit("circle.powell_hybrid" if method_id == "circle.kasa" else "circle.kasa", data)
    assert np.abs(np.array(res.center) - other.center).max() < 1e-8
    assert abs(res.radius - other.radius) < 1e-8


def _algebraic(points, res):
    """Circle (xc, yc, R) -> algebraic vector a = (A, B, C, D) with A = 1, centred design matrix."""
    m = points.mean(axis=0)
    u = points - m
    xc, yc = np.array(res.center) - m
    a = np.array([1.0, -2 * xc, -2 * yc, xc * xc + yc * yc - res.radius ** 2])
    z = np.einsum("ij,ij->i", u, u)
    Z = np.column_stack([z, u, np.ones(len(u))])
    return a, Z, z.mean()


def test_pratt_minimises_its_ratio(data, rng):
    """Pratt: min sum (A z + B x + C y + D)^2 / (B^2 + C^2 - 4AD)."""
    res = methods.fit("circle.pratt", data)
    a, Z, _ = _algebraic(data, res)

    def ratio(v):
        den = v[1] ** 2 + v[2] ** 2 - 4 * v[0] * v[3]
        return float(np.sum((Z @ v) ** 2) / den) if den > 0 else np.inf  # constraint region: real circles

    f0 = ratio(a)
    for scale in (1e-2, 1e-4, 1e-6):
        trial = a + rng.normal(size=(400, 4)) * scale * np.abs(a).max()
        assert min(ratio(v) for v in trial) >= f0 * (1 - 1e-12)


def test_taubin_minimises_its_ratio(data, rng):
    """Taubin: min sum F_i^2 / sum |grad F_i|^2 with F = A z + B x + C y + D."""
    res = methods.fit("circle.taubin", data)
    a, Z, _ = _algebraic(data, res)
    m = data.mean(axis=0)
    u = data - m

    def ratio(v):
        gx = 2 * v[0] * u[:, 0] + v[1]
        gy = 2 * v[0] * u[:, 1] + v[2]
        return float(np.sum((Z @ v) ** 2) / np.sum(gx * gx + gy * gy))

    f0 = ratio(a)
    for scale in (1e-2, 1e-4, 1e-6):
        trial = a + rng.normal(size=(400, 4)) * scale * np.abs(a).max()
        assert min(ratio(v) for v in trial) >= f0 * (1 - 1e-12)


@pytest.mark.parametrize("kind", ["pratt", "taubin", "hyper"])
def test_algebraic_fits_match_scipy_generalised_eigensolver(kind, data):
    """Second algorithm: scipy.linalg.eig(M, N) directly, smallest positive eigenvalue."""
    res = methods.fit(f"circle.{kind}", data)
    a, Z, zbar = _algebraic(data, res)
    n_pratt = np.array([[0, 0, 0, -2], [0, 1, 0, 0], [0, 0, 1, 0], [-2, 0, 0, 0]], float)
    n_taubin = np.diag([4 * zbar, 1, 1, 0.0])
    N = {"pratt": n_pratt, "taubin": n_taubin, "hyper": 2 * n_taubin - n_pratt}[kind]
    w, V = sla.eig(Z.T @ Z, N)
    w = w.real
    ok = np.flatnonzero(np.isfinite(w) & (w > 0))
    v = V[:, ok[np.argmin(w[ok])]].real
    v = v / v[0]
    np.testing.assert_allclose(v, a, rtol=1e-7, atol=1e-7 * np.abs(a).max())
