"""The compiled circle kernels (methods/circle/_ckernels.c) against the NumPy reference path
(FITBENCH_KERNELS=numpy), on NIST-like, noisy and ill-conditioned data.

Why the two paths may differ at all, and by how much (the tolerance of :func:`_tolerance`): they compute the
same quantities in a different order. (i) The frame's shift and scale come from blocked, pairwise sums
instead of NumPy's (a few ulps of the coordinates: |dX| <= 4 eps max|X|); (ii) the moments and normal
equations are summed per block and pairwise (error <= (BLOCK/2 + log2 N) eps of the sum of |terms|);
(iii) the 3x3 solve and the 4x4 eigenproblems are backward stable in both paths (Gaussian elimination /
cyclic Jacobi vs LAPACK). Each is a relative perturbation of the data or of the moments of order 1e3 eps;
the fitted circle moves by that times the fit's condition number, which for an arc of angle theta grows
like 1/theta^2 (the centre is fixed by the sagitta R (1 - cos(theta/2)) ~ R theta^2 / 8) and, for data away
from the origin, by max|X| / R. So the paths must agree to C eps (max|X| + R) max(1, 8/theta^2) with C = 100 (the largest
ratio measured on these sets is 1.5, Hyper on NIST set 30; GN/LM <= 0.6): a real difference between the
paths (a wrong sum, a lost term, a wrong lane) is a relative error of 1e-3 or more and fails by 1e9.
"""
import importlib
import math
import os

import numpy as np
import pytest

import methods
from conftest import nist_dir
from datasets.synthetic import circle_points
from methods._compiled import kernels
from methods._errors import InvalidInputError

EPS = float(np.finfo(float).eps)
CIRCLE_LSQ = ["circle.kasa", "circle.pratt", "circle.taubin", "circle.hyper", "circle.gauss_newton",
              "circle.levenberg_marquardt"]
ck = importlib.import_module("methods.circle._ckernels")  # not built: an ImportError, never a skip


def _noisy(center, radius, n, arc=(0.0, 2 * np.pi), noise=0.0, seed=3358):
    return circle_points(center, radius, n, arc=arc, noise=noise, rng=np.random.default_rng(seed))


def _sets():
    """(name, points, arc angle in radians, radius)."""
    yield "3358 points, 5 um noise at (1200, 650)", _noisy((1200.0, 650.0), 299.0, 3358, noise=0.005), 2 * np.pi, 299.0
    yield "10^5 points, 5 um noise", _noisy((1200.0, 650.0), 299.0, 100_000, noise=0.005), 2 * np.pi, 299.0
    for n in (3, 4, 5, 257, 513):  # odd counts: the lanes' tail; 257, 513: a block with one point
        yield f"{n} points on a half circle", _noisy((-4.0, 9.0), 3.0, n, arc=(0.2, 0.2 + np.pi), noise=0.01), np.pi, 3.0
    yield "10 degree arc, 10^6 away, noise 1e-4 R", _noisy((1e6, -1e6), 50.0, 200, arc=(1.0, 1.0 + np.deg2rad(10)),
                                                           noise=5e-3), np.deg2rad(10), 50.0
    yield "quadrant arc 10^6 away, exact", circle_points((1e6, -1e6), 299.0, 200, arc=(0.3, 0.3 + np.pi / 2)), np.pi / 2, 299.0
    for size in (1e-150, 1e150):
        yield (f"radius {size:g} about (2, -1) x radius", _noisy((2 * size, -size), size, 40, noise=1e-3 * size),
               2 * np.pi, size)
    folder = nist_dir()
    if folder is not None:
        for path in sorted(folder.glob("nist_cir2d_*.csv")):
            pts = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
            ref = methods.fit("circle.levenberg_marquardt", pts)
            # the arc each NIST set covers, from the angles about the reference centre
            ang = np.unwrap(np.sort(np.arctan2(pts[:, 1] - ref.center[1], pts[:, 0] - ref.center[0])))
            gaps = np.diff(np.concatenate([ang, [ang[0] + 2 * np.pi]]))
            yield path.stem, pts, float(2 * np.pi - gaps.max()), ref.radius


SETS = list(_sets())


def _tolerance(pts, arc, radius):
    return 100 * EPS * (np.abs(pts).max() + radius) * max(1.0, 8.0 / arc ** 2)


def _both(monkeypatch, method_id, pts):
    monkeypatch.setenv("FITBENCH_KERNELS", "numpy")
    reference = methods.fit(method_id, pts.copy())
    monkeypatch.setenv("FITBENCH_KERNELS", "compiled")
    compiled = methods.fit(method_id, pts.copy())
    return reference, compiled


@pytest.mark.parametrize("method_id", CIRCLE_LSQ)
@pytest.mark.parametrize("name, pts, arc, radius", SETS, ids=[s[0] for s in SETS])
def test_compiled_path_agrees_with_numpy_path(monkeypatch, method_id, name, pts, arc, radius):
    ref, com = _both(monkeypatch, method_id, pts)
    assert com.converged == ref.converged, (com.message, ref.message)
    tol = _tolerance(pts, arc, radius)
    assert abs(com.radius - ref.radius) <= tol, (com.radius - ref.radius, tol)
    assert np.abs(np.subtract(com.center, ref.center)).max() <= tol, (np.subtract(com.center, ref.center), tol)
    # the residuals of nearly the same circle: they differ by the circles' difference only
    assert np.abs(com.residuals - ref.residuals).max() <= 3 * tol
    assert abs(com.form_error - ref.form_error) <= 4 * tol
    assert com.message.split(";")[0].split("(")[0] == ref.message.split(";")[0].split("(")[0] or "stationary" in com.message


@pytest.mark.parametrize("name, pts, arc, radius", SETS, ids=[s[0] for s in SETS])
def test_residual_sweep_gives_the_same_bits(monkeypatch, name, pts, arc, radius):
    """For the same circle the compiled residual sweep does NumPy's operations: identical results."""
    from methods.circle.results import circle_result

    center, r = (float(pts[:, 0].mean()), float(pts[:, 1].mean())), radius
    monkeypatch.setenv("FITBENCH_KERNELS", "numpy")
    ref = circle_result(pts, center, r, converged=True, message="")
    monkeypatch.setenv("FITBENCH_KERNELS", "compiled")
    com = circle_result(pts, center, r, converged=True, message="")
    assert np.array_equal(com.residuals, ref.residuals) and com.form_error == ref.form_error


def test_frame_and_moments_match_numpy_and_sums_stay_accurate():
    from methods._frame import kernel_frame, unit_frame
    from methods.circle._frame import compiled_moments, moments

    pts = _noisy((1e6, -2e6), 299.0, 1_000_001, noise=0.005)  # odd N: every lane tail and a partial block
    kf = kernel_frame(pts, ck)
    shift, scale, x, y = unit_frame(pts)
    assert np.abs(kf.shift - shift).max() <= 4 * EPS * np.abs(pts).max()
    assert abs(kf.scale / scale - 1) <= 1e-13
    _, m = compiled_moments(pts, ck, kf)
    assert np.abs(m - moments(x, y)).max() <= 1e-12 * np.abs(m).max()
    # the blocked pairwise sums against exactly rounded sums (math.fsum) of the same unit-frame terms
    u = (pts[:, 0] - kf.cx) / kf.scale
    v = (pts[:, 1] - kf.cy) / kf.scale
    z = u * u + v * v
    n = len(u)
    bound = (128 + math.log2(n)) * EPS  # BLOCK/2 lanes in a block, then pairwise: not N eps
    for got, terms in ((m[1, 3], u), (m[2, 3], v), (m[0, 0], z * z), (m[0, 1], z * u), (m[1, 2], u * v)):
        exact = math.fsum(terms) / n
        assert abs(got - exact) <= bound * float(np.abs(terms).sum()) / n + 4 * EPS * abs(exact), (got, exact)


def test_geometric_sweep_matches_numpy_normal_equations():
    from methods._frame import kernel_frame
    from methods.circle._frame import compiled_geometric, geometric_normal_equations

    pts = _noisy((1200.0, 650.0), 299.0, 4097, noise=0.005)
    kf = kernel_frame(pts, ck)
    x = (pts[:, 0] - kf.cx) / kf.scale
    y = (pts[:, 1] - kf.cy) / kf.scale
    p = np.array([0.01, -0.02, 1.3])
    f, jtj, jtd, arrays = geometric_normal_equations(x, y, p)
    (f2, jtj2, jtd2, _), _ = compiled_geometric(pts, ck, kf, p, p)
    assert abs(f2 - f) <= 1e-13 * f
    assert np.abs(jtj2 - jtj).max() <= 1e-13 * np.abs(jtj).max()
    assert np.abs(jtd2 - jtd).max() <= 1e-13 * np.abs(jtj).max()
    # the LM reduction F(p) - F(q) by the fused sweep, against F(p) - F(q) computed in exact sums
    q = p + np.array([1e-3, -2e-3, 5e-4])
    (fq, *_), reduction = compiled_geometric(pts, ck, kf, q, p)
    dq = np.hypot(x - q[0], y - q[1]) - q[2]
    d = arrays[3]
    exact = math.fsum(d * d) - math.fsum(dq * dq)
    assert abs(reduction - exact) <= 1e-10 * abs(exact)


def test_points_changed_after_validation_are_refitted(monkeypatch):
    """The frame validation computed is used only for the very data it was computed from (token)."""
    monkeypatch.setenv("FITBENCH_KERNELS", "compiled")
    from methods._validation import validate_points

    for method_id in CIRCLE_LSQ:
        pts = _noisy((1200.0, 650.0), 299.0, 500, noise=0.005)
        arr = validate_points(pts, method=method_id)
        arr += 1000.0  # same array object, other data
        res = methods.get(method_id).func(arr)
        expected = methods.fit(method_id, arr.copy())
        assert np.allclose(res.center, expected.center, rtol=0, atol=1e-9) and abs(res.radius - expected.radius) < 1e-9


@pytest.mark.parametrize("bad, text", [
    (np.array([[0.0, 0.0], [1.0, np.nan], [2.0, 1.0]]), "contain NaN or inf"),
    (np.array([[1.0, 2.0]] * 5), "identical"),
    (np.column_stack([np.arange(6.0), 2 * np.arange(6.0)]), "straight line"),
    (np.array([[0.0, 0.0], [1.0, 1.0]]), "at least 3 points"),
    (np.array([[1e308, 0.0], [-1e308, 1.0], [0.0, 1e308]]), None),
])
def test_bad_input_gives_the_same_message_on_both_paths(monkeypatch, bad, text):
    outcome = {}
    for path in ("numpy", "compiled"):
        monkeypatch.setenv("FITBENCH_KERNELS", path)
        try:
            outcome[path] = ("ok", methods.fit("circle.kasa", bad).radius)
        except InvalidInputError as exc:
            outcome[path] = ("error", str(exc))
    assert outcome["numpy"] == outcome["compiled"]
    if text is not None:
        assert outcome["numpy"][0] == "error" and text in outcome["numpy"][1]


def test_kernels_refuse_wrong_buffers_with_a_message():
    with pytest.raises(TypeError, match="float64"):
        ck.frame_stats(np.zeros((4, 2), dtype=np.float32))
    with pytest.raises(ValueError, match="x, y pairs"):
        ck.frame_stats(np.zeros(5))
    with pytest.raises(ValueError, match="N numbers"):
        ck.radial(np.zeros((4, 2)), 0.0, 0.0, 1.0, np.empty(3))
    with pytest.raises((TypeError, ValueError, BufferError)):
        ck.frame_stats(np.zeros((4, 2))[::2])  # not contiguous
    if os.environ.get("FITBENCH_KERNELS", "compiled") != "numpy":
        assert kernels("methods.circle._ckernels") is ck


def test_stationarity_pseudo_inverse_matches_lstsq():
    """The compiled g^T pinv(J^T J) g (Jacobi eigenvalues, cut-off 3 eps max) against np.linalg.lstsq's: both are
    backward stable, so they agree to ~cond(J^T J) eps (1e-7 relative up to cond 1e8, tested)."""
    rng = np.random.default_rng(20)
    for _ in range(500):
        jac = rng.normal(size=(40, 3)) * 10.0 ** rng.uniform(-2, 2, size=3)
        a = jac.T @ jac
        if np.linalg.cond(a) > 1e8:
            continue
        g = rng.normal(size=3)
        ref = float(g @ np.linalg.lstsq(a, g, rcond=None)[0])
        assert abs(ck.psd_decrease(tuple(a.ravel()), tuple(g)) - ref) <= 1e-7 * abs(ref)
    # exactly rank-deficient: the null direction is dropped, as lstsq drops it
    a = np.diag([2.0, 1.0, 0.0])
    assert ck.psd_decrease(tuple(a.ravel()), (2.0, 1.0, 5.0)) == pytest.approx(2.0 * 2.0 / 2.0 + 1.0)


def test_each_kernel_carries_the_sha256_of_the_source_it_was_built_from():
    """setup.py builds the SHA-256 of each C source into its kernel (``source_sha256``): the rows' cache keys hash
    that source, so the binary that runs must be the one built from it."""
    import hashlib
    from pathlib import Path

    from methods._compiled import kernels
    for module in ("methods.circle._ckernels", "methods.ellipse._ckernels"):
        mod = kernels(module)
        source = Path(mod.__file__).with_name("_ckernels.c")
        assert mod.source_sha256 == hashlib.sha256(source.read_bytes()).hexdigest(), module


def test_a_kernel_built_from_another_version_of_its_source_is_refused(tmp_path, monkeypatch):
    """A C kernel edited (or pulled) but not rebuilt ran the old binary under the new source's cache keys: rows of the
    old code were stored as the new code's and served as current after the rebuild. Now the kernel is refused, with
    the rebuild command, as a kernel not built is (rows 'unavailable', recomputed by the next run)."""
    import hashlib
    import sys
    import types

    from methods import _compiled
    source = tmp_path / "_ckernels.c"
    source.write_text("/* version 2 */\n")
    fake = types.ModuleType("fitbench_test_pkg._ckernels")
    fake.__file__ = str(tmp_path / "_ckernels.cpython-311-x86_64-linux-gnu.so")
    fake.source_sha256 = hashlib.sha256(b"/* version 1 */\n").hexdigest()
    monkeypatch.setitem(sys.modules, "fitbench_test_pkg._ckernels", fake)
    monkeypatch.setattr(_compiled, "_CHECKED", {})
    with pytest.raises(_compiled.KernelsNotBuiltError, match=r"compiled kernel fitbench_test_pkg\._ckernels is stale: .*"
                                                              r"build_ext --inplace"):
        _compiled.kernels("fitbench_test_pkg._ckernels")
    fake.source_sha256 = hashlib.sha256(source.read_bytes()).hexdigest()   # rebuilt from the source beside it
    assert _compiled.kernels("fitbench_test_pkg._ckernels") is fake
    source.unlink()   # an installed package without its sources: nothing to be stale against
    monkeypatch.setattr(_compiled, "_CHECKED", {})
    fake.source_sha256 = ""
    assert _compiled.kernels("fitbench_test_pkg._ckernels") is fake
