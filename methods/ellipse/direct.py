"""Direct least-squares ellipse fits (program FED of the circle/ellipse paper): Fitzgibbon's
original method and Halir & Flusser's numerically stable modification."""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from methods._registry import register
from methods.ellipse._geometry import Frame, conic_to_params, normalise_conic
from methods.ellipse._result import ellipse_result, failed

#: Fitzgibbon's constraint matrix: a^T C a = 4AC - B^2
C6 = np.zeros((6, 6))
C6[0, 2] = C6[2, 0] = 2.0
C6[1, 1] = -1.0


def design(x, y):
    return np.column_stack([x * x, x * y, y * y, x, y, np.ones_like(x)])


def _finish(points, frame, k_unit, message, extra):
    """Geometric parameters from the unit-frame conic, then shifted and scaled to data units: the
    data-unit conic of a far-away ellipse has huge, cancelling coefficients (F ~ |centre|^2)."""
    try:
        params = conic_to_params(normalise_conic(k_unit))
    except ValueError:
        return failed(points, "the solution is not an ellipse (4AC - B^2 <= 0)")
    if params is None:
        return failed(points, "the solution conic has no real points")
    return ellipse_result(points, frame.params_to_data(params), converged=True, message=message, extra=extra)


@register("ellipse.fitzgibbon", kind="closed form",
          summary="FED original: direct LS with 4AC - B^2 = 1, generalised eigenproblem S a = lambda C a",
          reference="Fitzgibbon, Pilu & Fisher, ICPR 1996 / IEEE PAMI 21 (1999) 476-480; circle/ellipse paper ref. 3 (program FED)")
def fitzgibbon(points):
    """Minimise |D a|^2 subject to a^T C a = 4AC - B^2 = 1 (design matrix D = [x^2, xy, y^2, x, y, 1]):
    the generalised eigenproblem S a = lambda C a with S = D^T D, solved as published: QZ on (S, C)
    and the eigenvector of the positive finite eigenvalue (unique for noisy data). For exact or
    near-exact data S is singular and that eigenvalue is 0, so rounding can make it negative or
    pick a wrong eigenvector: the original method then fails (reported, with the eigenvalues), the
    instability that Halir & Flusser removed (ellipse.halir_flusser)."""
    frame = Frame.of(points)
    S = design(frame.x, frame.y)
    S = S.T @ S
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


@register("ellipse.halir_flusser", kind="closed form",
          summary="FED modified: Halir–Flusser's reduced 3x3 eigenproblem of the direct LS ellipse fit",
          reference="Halir & Flusser, WSCG 1998, 125-132; circle/ellipse paper ref. 5 (program FED)")
def halir_flusser(points):
    """Fitzgibbon's direct fit reformulated by Halir & Flusser: with D = [D1 | D2] (quadratic and
    linear parts), S1 = D1^T D1, S2 = D1^T D2, S3 = D2^T D2, the linear part is eliminated,
    a2 = T a1 with T = -S3^-1 S2^T, and a1 is the eigenvector of M = C1^-1 (S1 + S2 T) with
    4 a1[0] a1[2] - a1[1]^2 > 0. S3 is solved through the QR factor of D2 (no squaring)."""
    frame = Frame.of(points)
    x, y = frame.x, frame.y
    # One QR of [D2 | D1]: R11 T = -R12 eliminates the linear part, and R22^T R22 = S1 + S2 T is the
    # Gram matrix of D1's residual after projecting out D2 (no scatter matrix is ever squared).
    aug = np.empty((len(x), 6))
    aug[:, 0], aug[:, 1], aug[:, 2] = x, y, 1.0
    aug[:, 3], aug[:, 4], aug[:, 5] = x * x, x * y, y * y
    R = np.linalg.qr(aug, mode="r")
    if R.shape[0] < 6:
        R = np.vstack([R, np.zeros((6 - R.shape[0], 6))])
    T = -np.linalg.solve(R[:3, :3], R[:3, 3:])
    M = R[3:, 3:].T @ R[3:, 3:]  # = S1 + S2 T
    C1inv = np.array([[0.0, 0.0, 0.5], [0.0, -1.0, 0.0], [0.5, 0.0, 0.0]])
    w, V = np.linalg.eig(C1inv @ M)
    V = V.real
    cond = 4 * V[0] * V[2] - V[1] ** 2
    ok = np.flatnonzero(cond > 0)
    if ok.size == 0:
        return failed(points, "no eigenvector satisfies 4AC - B^2 > 0 (degenerate data)")
    j = ok[np.argmin(np.abs(w.real[ok]))] if ok.size > 1 else ok[0]
    a1 = V[:, j]
    return _finish(points, frame, np.concatenate([a1, T @ a1]), "closed-form solution (3x3 eigenvector)",
                   {"eigenvalue": float(w.real[j])})
