"""The closed-form circle fits from one sweep of unit-frame moments lose nothing against an
independent solution from the SVD of the full design matrix (no moments, no unit frame shared with the
method): NIST Circle2d sets and ill-conditioned exact circles (short arcs, far centres, tiny circles)."""
import json

import numpy as np
import pytest

import methods
from conftest import nist_dir
from datasets.synthetic import circle_points

ALGEBRAIC = ["circle.kasa", "circle.pratt", "circle.taubin", "circle.hyper"]


def reference_fit(method_id, pts):
    """Kåsa by lstsq of [2x 2y -1][xc yc w] = x^2 + y^2; Pratt/Taubin/Hyper as the generalised
    eigenproblem of Z^T Z and N through the SVD of Z = [z, x, y, 1] (Chernov 2010, ch. 7), all on the
    data shifted by their first point and divided by their max extent (nothing shared with the method)."""
    o = pts[0]
    s = np.abs(pts - o).max()
    q = (pts - o) / s
    x, y = q[:, 0], q[:, 1]
    z = x * x + y * y
    if method_id == "circle.kasa":
        sol = np.linalg.lstsq(np.column_stack([2 * x, 2 * y, -np.ones_like(x)]), z, rcond=None)[0]
        xc, yc, w = sol
        return np.array([xc, yc]) * s + o, np.sqrt(xc * xc + yc * yc - w) * s
    Z = np.column_stack([z, x, y, np.ones_like(x)])
    if len(Z) < 4:  # three points: a zero row keeps Z^T Z and gives the 4th singular value, 0
        Z = np.vstack([Z, np.zeros((4 - len(Z), 4))])
    _, sv, vt = np.linalg.svd(Z, full_matrices=False)
    mx, my, mz = x.mean(), y.mean(), z.mean()
    pratt = np.array([[0, 0, 0, -2], [0, 1, 0, 0], [0, 0, 1, 0], [-2, 0, 0, 0]], float)
    taubin = np.array([[4 * mz, 2 * mx, 2 * my, 0], [2 * mx, 1, 0, 0], [2 * my, 0, 1, 0], [0, 0, 0, 0]])
    N = {"circle.pratt": pratt, "circle.taubin": taubin, "circle.hyper": 2 * taubin - pratt}[method_id]
    if sv[-1] <= 1e-14 * sv[0]:
        a = vt[-1]
    else:
        v = vt.T
        K = (v.T @ N @ v) / np.outer(sv, sv)
        mu, b = np.linalg.eigh(K)
        a = v @ (b[:, np.argmax(mu)] / sv)
    A, B, C, D = a
    return np.array([-B / (2 * A), -C / (2 * A)]) * s + o, np.sqrt(B * B + C * C - 4 * A * D) / (2 * abs(A)) * s


def _exact_sets():
    yield "full circle at (1200, 650)", circle_points((1200.0, 650.0), 299.0, 3358)
    yield "quadrant arc 10^6 away", circle_points((1e6, -1e6), 299.0, 200, arc=(0.3, 0.3 + np.pi / 2))
    yield "10 degree arc", circle_points((5.0, -2.0), 100.0, 100, arc=(1.0, 1.0 + np.deg2rad(10)))
    yield "micrometre circle", circle_points((-3.0, 7.0), 1e-3, 60)
    yield "three points", circle_points((1200.0, 650.0), 299.0, 3, arc=(0.1, 4.0), endpoint=True)
    yield "5 um noise, 10^5 points", circle_points((1200.0, 650.0), 299.0, 100_000, noise=0.005,
                                                   rng=np.random.default_rng(3358))


def _nist_sets():
    folder = nist_dir()
    if folder is None:
        return
    for path in sorted(folder.glob("nist_cir2d_*.csv")):
        yield path.stem, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


SETS = list(_exact_sets()) + list(_nist_sets())


@pytest.mark.parametrize("method_id", ALGEBRAIC)
@pytest.mark.parametrize("name, pts", SETS, ids=[s[0] for s in SETS])
def test_moments_agree_with_the_svd_of_the_design_matrix(method_id, name, pts):
    res = methods.fit(method_id, pts)
    assert res.converged, res.message
    center, radius = reference_fit(method_id, pts)
    # agreement to 1e-9 of the radius plus the rounding of the coordinates themselves
    tol = 1e-9 * radius + 1e-13 * np.abs(pts).max()
    assert np.abs(np.array(res.center) - center).max() <= tol, (np.array(res.center) - center, tol)
    assert abs(res.radius - radius) <= tol
