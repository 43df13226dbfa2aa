"""Direct least-squares ellipse fits (program FED of the circle/ellipse paper): Fitzgibbon's
original method and Halir & Flusser's numerically stable modification.

Both work in the unit frame (centred on the centroid, unit RMS radius) from the 6 x 6 scatter matrix
S = D^T D of the design D = [x^2, xy, y^2, x, y, 1], computed from the 15 moments of the points in one
sweep (no N x 6 design matrix is formed). Centring and scaling keep S well conditioned for any position
and size of the data.
"""
from __future__ import annotations

import math

import numpy as np

from methods._registry import register
from methods._compiled import kernels
from methods._frame import dot, solve3_columns
from methods.ellipse._geometry import Frame, conic_to_params, normalise_conic
from methods.ellipse.results import ellipse_result, failed, residuals_from_unit
from methods.ellipse._validation import check_distinct_points
from methods._lazy import lazy_module

sla = lazy_module("scipy.linalg")


def _ellipse_kernels():
    return kernels("methods.ellipse._ckernels")


#: Fitzgibbon's constraint matrix: a^T C a = 4AC - B^2
C6 = np.zeros((6, 6))
C6[0, 2] = C6[2, 0] = 2.0
C6[1, 1] = -1.0
#: Relative size of the second-smallest singular value of the reduced scatter below which the conic is
#: not determined by the data (a family of conics fits them equally well).
ILL_POSED_RTOL = 1e-10


def scatter(x, y) -> np.ndarray:
    """S = D^T D for D = [x^2, xy, y^2, x, y, 1] from the moments sum x^p y^q, p + q <= 4 (S[i, j] depends only on
    the sum of the monomials' exponents): one compiled sweep (``methods/ellipse/_ckernels.c`` ``scatter``,
    blocked pairwise sums), or on the NumPy path three products and twelve sums of products."""
    ck = _ellipse_kernels()
    if ck is not None:
        m40, m31, m22, m13, m04, m30, m21, m12, m03, m20, m11, m02, m10, m01 = ck.scatter(x, y)
        return _scatter_matrix(m40, m31, m22, m13, m04, m30, m21, m12, m03, m20, m11, m02, m10, m01, float(len(x)))
    xx, xy, yy = x * x, x * y, y * y   # sums of products by methods._frame.dot: never BLAS, the same bits on every CPU
    m40, m31, m22, m13, m04 = dot(xx, xx), dot(xx, xy), dot(xx, yy), dot(xy, yy), dot(yy, yy)
    m30, m21, m12, m03 = dot(xx, x), dot(xx, y), dot(yy, x), dot(yy, y)
    m20, m11, m02 = dot(x, x), dot(x, y), dot(y, y)
    m10, m01, m00 = x.sum(), y.sum(), float(len(x))
    return _scatter_matrix(m40, m31, m22, m13, m04, m30, m21, m12, m03, m20, m11, m02, m10, m01, m00)


def _scatter_matrix(m40, m31, m22, m13, m04, m30, m21, m12, m03, m20, m11, m02, m10, m01, m00) -> np.ndarray:
    return np.array([[m40, m31, m22, m30, m21, m20],
                     [m31, m22, m13, m21, m12, m11],
                     [m22, m13, m04, m12, m03, m02],
                     [m30, m21, m12, m20, m11, m10],
                     [m21, m12, m03, m11, m02, m01],
                     [m20, m11, m02, m10, m01, m00]])


def _finish(points, frame, k_unit, message, extra):
    """Geometric parameters from the unit-frame conic, then shifted and scaled to data units: the
    data-unit conic of a far-away ellipse has huge, cancelling coefficients (F ~ |centre|^2)."""
    try:
        params = conic_to_params(normalise_conic(k_unit))
    except ValueError:
        return failed(points, "the solution is not an ellipse (4AC - B^2 <= 0)", extra=extra)
    if params is None:
        return failed(points, "the solution conic has no real points (an imaginary or degenerate ellipse)", extra=extra)
    return ellipse_result(points, frame.params_to_data(params), converged=True, message=message, extra=extra,
                          residuals=residuals_from_unit(frame, params))


_ggev = {}


def generalized_eig(a, b):
    """scipy.linalg.eig(a, b) for real a, b (LAPACK's QZ, dggev, with scipy's workspace query, eigenvalue
    division and column normalisation: the same bits) without its per-call validation and dispatch (~40 us of a
    fit at N = 3358); complex eigenvalues take scipy.linalg.eig itself (tests/test_ellipse_small_algebra.py)."""
    if "f" not in _ggev:
        from scipy.linalg import get_blas_funcs, get_lapack_funcs
        _ggev["f"], = get_lapack_funcs(("ggev",), (a, b))
        _ggev["nrm2"] = get_blas_funcs("nrm2", dtype=np.float64, ilp64="preferred")  # scipy.linalg.norm's, 1-D
    ggev, nrm2 = _ggev["f"], _ggev["nrm2"]
    lwork = ggev(a, b, lwork=-1)[-2][0].real.astype(np.int_)
    alphar, alphai, beta, _, vr, _, info = ggev(a, b, 0, 1, lwork, 0, 0)
    if info != 0 or not np.all(alphai == 0.0) or not np.isfinite(vr).all():
        return sla.eig(a, b)  # its errors and complex eigenvectors
    alpha = alphar + 1j * alphai
    w = np.empty_like(alpha)  # as scipy.linalg._decomp._make_eigvals
    nz = beta != 0
    w[nz] = alpha[nz] / beta[nz]
    w[~(alpha == 0) & ~nz] = np.inf
    w[(alpha == 0) & ~nz] = np.nan
    for i in range(vr.shape[0]):
        vr[:, i] /= nrm2(vr[:, i])
    return w, vr


@register("ellipse.fitzgibbon", kind="closed form",
          summary="FED original: direct LS with 4AC - B^2 = 1, generalised eigenproblem S a = lambda C a",
          reference="Fitzgibbon, Pilu & Fisher, ICPR 1996 / IEEE PAMI 21 (1999) 476-480; circle/ellipse paper ref. 3 (program FED)")
def fitzgibbon(points):
    """Minimise |D a|^2 subject to a^T C a = 4AC - B^2 = 1 (design matrix D = [x^2, xy, y^2, x, y, 1]):
    the generalised eigenproblem S a = lambda C a with S = D^T D, solved as published: QZ on (S, C)
    and the eigenvector of the positive finite eigenvalue (unique for noisy data). For exact or
    near-exact data S is singular and that eigenvalue is 0 up to rounding: its sign, hence whether the
    original selection rule finds it, is a rounding accident (it can differ between CPUs). Either way the
    result is honest: a found ellipse is the exact one (to rounding), a lost eigenvalue is reported with
    the eigenvalues. Halir & Flusser removed this instability (ellipse.halir_flusser)."""
    check_distinct_points(points, 5, "ellipse.fitzgibbon")
    frame = Frame.of(points)
    S = scatter(frame.x, frame.y)
    w, V = generalized_eig(S, C6)
    w = w.real
    V = V.real
    positive = np.flatnonzero(np.isfinite(w) & (w > 0))
    if positive.size == 0:
        finite = np.sort(w[np.isfinite(w)])
        return failed(points, "no positive finite eigenvalue of S a = lambda C a (the original method's "
                              f"selection rule; finite eigenvalues {np.array2string(finite, precision=3)}): "
                              "(near-)exact data make S singular; use ellipse.halir_flusser")
    j = positive[np.argmin(w[positive])]
    return _finish(points, frame, V[:, j], "closed-form solution (generalised eigenvector)",
                   {"eigenvalue": float(w[j])})


def halir_flusser_unit(frame):
    """Halir & Flusser's fit in the unit frame: (xc, yc, a, b, theta) there, or (None, reason)."""
    k, _, why = _halir_flusser_conic(frame)
    if k is None:
        return None, why
    try:
        p = conic_to_params(normalise_conic(k))
    except ValueError:
        return None, "the solution is not an ellipse (4AC - B^2 <= 0)"
    return (p, "") if p is not None else (None, "the solution conic has no real points")


def _halir_flusser_conic(frame):
    S = scatter(frame.x, frame.y).tolist()
    return halir_flusser_conic(S)


def halir_flusser_conic(S):
    """Halir & Flusser's conic from the 6 x 6 scatter ``S`` (nested lists): (k, eigenvalue, "") or
    (None, None, reason). Every step is 3 x 3 and done in plain floating point, never LAPACK/BLAS (whose
    kernels are chosen per CPU and round differently): T = -S3^-1 S2^T by :func:`solve3` column by column;
    M = S1 + S2 T; the pencil M a = lambda C1 a from the roots of det(M - lambda C1), a cubic, each polished by
    Newton's method, and its eigenvector as the null vector of the symmetric M - lambda C1 (the largest cross
    product of two of its rows)."""
    S1 = [row[:3] for row in S[:3]]
    S2 = [row[3:] for row in S[:3]]
    S3 = [row[3:] for row in S[3:]]
    s3 = [v for row in S3 for v in row]
    cols = solve3_columns(s3, S2)  # column c of S3^-1 S2^T: S3^-1 times row c of S2
    if cols is None:
        return None, None, "the linear part of the scatter is singular (degenerate data)"
    T = [[-cols[c][r] for c in range(3)] for r in range(3)]              # T[r][c] = -(S3^-1 S2^T)[r][c]
    M = [[S1[i][j] + (S2[i][0] * T[0][j] + S2[i][1] * T[1][j] + S2[i][2] * T[2][j]) for j in range(3)]
         for i in range(3)]
    M = [[0.5 * (M[i][j] + M[j][i]) for j in range(3)] for i in range(3)]
    ev = symmetric_eigenvalues3(M)
    sv = sorted((abs(v) for v in ev), reverse=True)
    if not sv[1] > ILL_POSED_RTOL * sv[0]:
        return None, None, (f"ill-posed: the reduced scatter has two (near-)zero singular values {sv}; "
                            "a family of conics fits these points (too few distinct points in general position)")
    best = None
    for lam in pencil_eigenvalues(M):
        a = null_vector3([[M[0][0], M[0][1], M[0][2] - 2.0 * lam],
                          [M[1][0], M[1][1] + lam, M[1][2]],
                          [M[2][0] - 2.0 * lam, M[2][1], M[2][2]]])
        if a is None or not 4.0 * a[0] * a[2] - a[1] * a[1] > 0:
            continue
        if best is None or abs(lam) < abs(best[0]):
            best = (lam, a)
    if best is None:
        return None, None, "no eigenvector satisfies 4AC - B^2 > 0 (the data determine no ellipse)"
    lam, a1 = best
    a2 = [T[r][0] * a1[0] + T[r][1] * a1[1] + T[r][2] * a1[2] for r in range(3)]
    return np.array([*a1, *a2]), float(lam), ""


def _cubic_roots(c3, c2, c1, c0):
    """Real roots of c3 x^3 + c2 x^2 + c1 x + c0 (c3 != 0): the trigonometric / Cardano formulas, then two
    Newton steps each (plain floats: the same bits on every CPU with IEEE double and the same libm)."""
    b, c, d = c2 / c3, c1 / c3, c0 / c3
    p = c - b * b / 3.0
    q = 2.0 * b * b * b / 27.0 - b * c / 3.0 + d
    disc = (q / 2.0) ** 2 + (p / 3.0) ** 3
    if disc > 0:  # one real root
        sq = math.sqrt(disc)
        u, v = -q / 2.0 + sq, -q / 2.0 - sq
        roots = [math.copysign(abs(u) ** (1 / 3), u) + math.copysign(abs(v) ** (1 / 3), v) - b / 3.0]
    elif p == 0.0:
        roots = [-b / 3.0]
    else:  # three real roots
        m = 2.0 * math.sqrt(-p / 3.0)
        arg = max(-1.0, min(1.0, 3.0 * q / (p * m)))
        t = math.acos(arg) / 3.0
        roots = [m * math.cos(t - 2.0 * math.pi * k / 3.0) - b / 3.0 for k in range(3)]
    out = []
    for x in roots:
        for _ in range(2):
            f = ((c3 * x + c2) * x + c1) * x + c0
            g = (3.0 * c3 * x + 2.0 * c2) * x + c1
            if g == 0.0 or not math.isfinite(f / g):
                break
            x = x - f / g
        out.append(x)
    return out


def pencil_eigenvalues(M):
    """Real eigenvalues lambda of M a = lambda C1 a (C1 of Fitzgibbon's constraint 4AC - B^2, 3 x 3 block): the
    roots of det(M - lambda C1) = -4 l^3 + 4 (m02 - m11) l^2 + (m00 m22 - 4 m01 m12 + 4 m11 m02 - m02^2) l + det M."""
    (m00, m01, m02), (_, m11, m12), (_, _, m22) = M
    det = (m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02) + m02 * (m01 * m12 - m11 * m02))
    return _cubic_roots(-4.0, 4.0 * (m02 - m11), m00 * m22 - 4.0 * m01 * m12 + 4.0 * m11 * m02 - m02 * m02, det)


def symmetric_eigenvalues3(M):
    """Eigenvalues of a symmetric 3 x 3 matrix (the roots of its characteristic polynomial; absolute error
    about eps ||M||, enough for :data:`ILL_POSED_RTOL`)."""
    (m00, m01, m02), (_, m11, m12), (_, _, m22) = M
    tr = m00 + m11 + m22
    minors = m00 * m11 - m01 * m01 + m00 * m22 - m02 * m02 + m11 * m22 - m12 * m12
    det = (m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02) + m02 * (m01 * m12 - m11 * m02))
    return _cubic_roots(1.0, -tr, minors, -det)


def null_vector3(A):
    """A unit vector spanning the null space of a (numerically) rank-2 symmetric 3 x 3 matrix: the largest of
    the cross products of two of its rows; None if every cross product vanishes."""
    r0, r1, r2 = A
    best, norm = None, 0.0
    for u, v in ((r0, r1), (r0, r2), (r1, r2)):
        c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        n = math.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
        if n > norm:
            best, norm = c, n
    if best is None or not math.isfinite(norm):
        return None
    return [best[0] / norm, best[1] / norm, best[2] / norm]


@register("ellipse.halir_flusser", kind="closed form",
          summary="FED modified: Halir–Flusser's reduced 3x3 eigenproblem of the direct LS ellipse fit",
          reference="Halir & Flusser, WSCG 1998, 125-132; circle/ellipse paper ref. 5 (program FED)")
def halir_flusser(points):
    """Fitzgibbon's direct fit reformulated by Halir & Flusser: with the scatter blocks S1 (quadratic),
    S2 (mixed) and S3 (linear), the linear part is eliminated, a2 = T a1 with T = -S3^-1 S2^T, and a1 is
    the eigenvector of M = C1^-1 (S1 + S2 T) with 4 a1[0] a1[2] - a1[1]^2 > 0. The reduced scatter
    S1 + S2 T must have rank >= 2, else the conic is not determined (reported as ill-posed)."""
    check_distinct_points(points, 5, "ellipse.halir_flusser")
    frame = Frame.of(points)
    k, w, why = _halir_flusser_conic(frame)
    if k is None:
        return failed(points, why)
    return _finish(points, frame, k, "closed-form solution (3x3 eigenvector)", {"eigenvalue": w})
