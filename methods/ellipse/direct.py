"""Direct least-squares ellipse fits (program FED of the circle/ellipse paper): Fitzgibbon's
original method and Halir & Flusser's numerically stable modification.

Both work in the unit frame (centred on the centroid, unit RMS radius) from the 6 x 6 scatter matrix
S = D^T D of the design D = [x^2, xy, y^2, x, y, 1], computed from the 15 moments of the points in one
sweep (no N x 6 design matrix is formed). Centring and scaling keep S well conditioned for any position
and size of the data.
"""
from __future__ import annotations

import numpy as np

from methods._registry import register
from methods.ellipse._geometry import Frame, conic_to_params, normalise_conic
from methods.ellipse._result import ellipse_result, failed, residuals_from_unit
from methods.ellipse._validation import check_distinct_points
from methods._lazy import lazy_module

sla = lazy_module("scipy.linalg")


#: Fitzgibbon's constraint matrix: a^T C a = 4AC - B^2
C6 = np.zeros((6, 6))
C6[0, 2] = C6[2, 0] = 2.0
C6[1, 1] = -1.0
#: Relative size of the second-smallest singular value of the reduced scatter below which the conic is
#: not determined by the data (a family of conics fits them equally well).
ILL_POSED_RTOL = 1e-10


def scatter(x, y) -> np.ndarray:
    """S = D^T D for D = [x^2, xy, y^2, x, y, 1] from the moments sum x^p y^q, p + q <= 4 (one sweep of
    three products and twelve dot products; S[i, j] depends only on the sum of the monomials' exponents)."""
    xx, xy, yy = x * x, x * y, y * y
    m40, m31, m22, m13, m04 = xx @ xx, xx @ xy, xx @ yy, xy @ yy, yy @ yy
    m30, m21, m12, m03 = xx @ x, xx @ y, yy @ x, yy @ y
    m20, m11, m02 = x @ x, x @ y, y @ y
    m10, m01, m00 = x.sum(), y.sum(), float(len(x))
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
    w, V = sla.eig(S, C6)
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
    S = scatter(frame.x, frame.y)
    S1, S2, S3 = S[:3, :3], S[:3, 3:], S[3:, 3:]
    try:
        T = -np.linalg.solve(S3, S2.T)          # a2 = T a1 eliminates the linear part
    except np.linalg.LinAlgError:
        return None, None, "the linear part of the scatter is singular (degenerate data)"
    M = S1 + S2 @ T                              # reduced scatter, symmetric positive semi-definite
    M = 0.5 * (M + M.T)
    sv = np.linalg.svd(M, compute_uv=False)
    if not sv[1] > ILL_POSED_RTOL * sv[0]:
        return None, None, (f"ill-posed: the reduced scatter has two (near-)zero singular values {sv.tolist()}; "
                            "a family of conics fits these points (too few distinct points in general position)")
    C1inv = np.array([[0.0, 0.0, 0.5], [0.0, -1.0, 0.0], [0.5, 0.0, 0.0]])
    w, V = np.linalg.eig(C1inv @ M)
    V = V.real
    cond = 4 * V[0] * V[2] - V[1] ** 2
    ok = np.flatnonzero(cond > 0)
    if ok.size == 0:
        return None, None, "no eigenvector satisfies 4AC - B^2 > 0 (the data determine no ellipse)"
    j = ok[np.argmin(np.abs(w.real[ok]))] if ok.size > 1 else ok[0]
    a1 = V[:, j]
    return np.concatenate([a1, T @ a1]), float(w.real[j]), ""


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
