"""Algebraic circle fits: Kåsa, Pratt, Taubin and Hyper (closed form).

The circle is written as A(x^2 + y^2) + Bx + Cy + D = 0 and the algebraic residuals are
minimised under a normalisation constraint a^T N a = 1 (Chernov, *Circular and Linear
Regression*, 2010, ch. 5-7). Pratt, Taubin and Hyper are generalised eigenproblems
M a = eta N a with M = Z^T Z, Z = [z, x, y, 1].

Speed and accuracy: every fit reads the data once more after validation, for the 4x4 moment
matrix M / N of the centred, scaled (unit-frame) data, then solves a 3x3 or 4x4 problem; the residuals
and form error are one more sweep. Through ``methods.fit`` that is three sweeps over the points in all
(compiled path, ``methods/circle/_ckernels.c``; the NumPy reference path computes the same quantities):

1. validation + frame: ``frame_stats`` (finite, centroid, scale, collinearity; ``methods._validation``);
2. the moments of the centred, scaled data: ``moments`` (:func:`methods.circle._frame.compiled_moment_means`);
3. residuals r_i - R, form error max r - min r: ``radial`` (:func:`methods.circle.results.circle_result`).
Between the sweeps the compiled path stays in plain floats (the sums, the 3x3 or 4x4 problem solved by
``solve3`` / ``eigen_fit`` in C, the circle mapped to data units): about 7 µs of Python per fit at N = 3358.
In the unit frame M is as well conditioned as the circle's shape allows (no offset, no unit), so the
squared condition number of the moments costs nothing measurable: tests/test_algebraic_moments.py
compares every fit with an SVD of Z on the NIST sets and on ill-conditioned exact circles.
"""
from __future__ import annotations

import math

import numpy as np

from methods._registry import register
from methods.circle.results import circle_result
from methods.circle._frame import Frame, compiled_frame, compiled_moment_means, kasa_moments, kasa_sums, moments

# Compiled path: the fits below read the compiled passes' sums as plain floats and map the unit-frame
# circle to data units in plain floating point (the same IEEE operations as NumPy's on 2-element arrays, so the
# same bits as the NumPy reference path's own arithmetic), without building matrices or frames in between.


def _to_data(cx: float, cy: float, scale: float, xc: float, yc: float, r: float):
    """The unit-frame circle (xc, yc, R) in data units: as :meth:`Frame.circle_to_data` (center, radius)."""
    return (xc * scale + cx, yc * scale + cy), abs(r) * scale


_KASA_NO_CIRCLE = "Kåsa system gives R^2 <= 0: no real circle fits these points"


@register("circle.kasa", kind="closed form",
          summary="Kåsa algebraic least squares: linear system of roundness-paper eq. 7",
          reference="Pınar & Güllü, roundness paper, eq. 5-7; Kåsa, IEEE Trans. Instrum. Meas. 25 (1976) 8-14")
def kasa(points):
    """Minimise S_CA = sum((x_i - xc)^2 + (y_i - yc)^2 - R^2)^2 (circle/ellipse paper eq. 5) by
    solving the linear least-squares system of roundness-paper eq. 7 for (xc, yc, w)."""
    compiled = compiled_frame(points)
    if compiled is not None:
        ck, kf = compiled
        kf, (_, zx, zy, xx, yy, xy, sx, sy, sz) = compiled_moment_means(points, ck, kf)
        xc, yc, r = kasa_sums(zx, zy, sz, xx, xy, sx, yy, sy, 1.0, ck)
        if not (math.isfinite(xc) and math.isfinite(yc) and math.isfinite(r)):
            return circle_result(points, (np.nan, np.nan), np.nan, converged=False, message=_KASA_NO_CIRCLE)
        center, radius = _to_data(kf.cx, kf.cy, kf.scale, xc, yc, r)
        return circle_result(points, center, radius, converged=True, message="closed-form solution")
    frame = Frame.of(points)  # the NumPy reference path
    p = kasa_moments(moments(frame.x, frame.y))
    if not all(map(math.isfinite, p.tolist())):
        return circle_result(points, (np.nan, np.nan), np.nan, converged=False, message=_KASA_NO_CIRCLE)
    center, radius = frame.circle_to_data(p)
    del frame  # the result's residual sweep does not need the unit-frame copy
    return circle_result(points, center, radius, converged=True, message="closed-form solution")


_EIGEN_MESSAGES = ("closed-form solution (generalised eigenvector)",
                   "points lie on a circle to rounding (algebraic residuals at the moments' resolution)",
                   "no positive generalised eigenvalue: the constraint admits no circle")


def _eigen_fit(m: np.ndarray, constraint: np.ndarray) -> tuple[np.ndarray, str]:
    """Solve min a^T M a s.t. a^T N a = 1 (smallest positive eigenvalue of M a = eta N a), M = Z^T Z / N.

    With M = V S^2 V^T (its eigendecomposition, S^2 >= 0), put a = V S^-1 b: then K b = (1/eta) b with
    K = S^-1 V^T N V S^-1 symmetric; the wanted a comes from the largest positive eigenvalue of K.
    When the smallest eigenvalue of M is at its rounding level (points on a circle to ~1e-7 of
    its size), a is the null vector of M: every constraint then gives the same circle. (The compiled path
    makes the same computation in C: ``methods/circle/_ckernels.c`` eigen_fit, cyclic Jacobi.)
    """
    lam, v = np.linalg.eigh(m)
    lam, v = lam[::-1], v[:, ::-1]  # largest first
    if lam[-1] <= 64 * np.finfo(float).eps * lam[0]:
        return v[:, -1], _EIGEN_MESSAGES[1]
    s = np.sqrt(lam)
    K = (v.T @ constraint @ v) / np.outer(s, s)
    mu, b = np.linalg.eigh(K)
    j = int(np.argmax(mu))
    if not mu[j] > 0:
        return np.full(4, np.nan), _EIGEN_MESSAGES[2]
    return v @ (b[:, j] / s), _EIGEN_MESSAGES[0]


def _circle_from_conic(points, to_data, a: list, message: str):
    """The circle of the conic A(x^2 + y^2) + Bx + Cy + D = 0, ``a`` = [A, B, C, D] (plain floats, unit frame),
    as a result; ``to_data(xc, yc, R)`` -> (center, radius) in data units."""
    A, B, C, D = a
    finite = all(map(math.isfinite, a))
    disc = B * B + C * C - 4 * A * D if finite else math.nan
    if not finite or abs(A) <= 1e-14 * math.sqrt(disc if disc > 0 else 1.0):
        return circle_result(points, (np.nan, np.nan), np.nan, converged=False,
                             message=message if not finite
                             else "best algebraic fit is a straight line (A = 0): the radius is unbounded")
    if disc <= 0:
        return circle_result(points, (np.nan, np.nan), np.nan, converged=False,
                             message="algebraic solution has B^2 + C^2 - 4AD <= 0: no real circle")
    center, radius = to_data(-B / (2 * A), -C / (2 * A), math.sqrt(disc) / (2 * abs(A)))
    return circle_result(points, center, radius, converged=True, message=message,
                         extra={"algebraic_parameters_unit_frame": a})


_PRATT = np.array([[0, 0, 0, -2], [0, 1, 0, 0], [0, 0, 1, 0], [-2, 0, 0, 0]], dtype=float)


def _constraint(kind: str, zbar: float) -> np.ndarray:
    return np.array(_constraint_entries(kind, zbar)).reshape(4, 4)


def _constraint_entries(kind: str, zbar: float) -> tuple:
    """The constraint matrix N (row major, 16 floats) of ``kind`` for data centred in the unit frame with
    mean(z) = ``zbar``."""
    if kind == "pratt":
        return _PRATT_ENTRIES
    z4 = 4 * zbar  # Taubin: diag(4 mean(z), 1, 1, 0) (data centred: the A*B and A*C terms vanish); Hyper: 2 N_T - N_P
    if kind == "taubin":
        return (z4, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    return (2 * z4, 0.0, 0.0, 2.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 2.0, 0.0, 0.0, 0.0)


_PRATT_ENTRIES = tuple(_PRATT.ravel().tolist())


def _constrained_fit(points, kind: str):
    compiled = compiled_frame(points)
    if compiled is not None:  # passes 1 (validation) and 2 (moments), the 4x4 problem in C, pass 3 (residuals)
        ck, kf = compiled
        kf, (zz, zx, zy, xx, yy, xy, sx, sy, sz) = compiled_moment_means(points, ck, kf)
        status, *a = ck.eigen_fit((zz, zx, zy, sz, zx, xx, xy, sx, zy, xy, yy, sy, sz, sx, sy, 1.0),
                                  _constraint_entries(kind, sz))
        cx, cy, scale = kf.cx, kf.cy, kf.scale
        return _circle_from_conic(points, lambda xc, yc, r: _to_data(cx, cy, scale, xc, yc, r), a,
                                  _EIGEN_MESSAGES[status])
    frame = Frame.of(points)  # the NumPy reference path
    m = moments(frame.x, frame.y)
    a, message = _eigen_fit(m, _constraint(kind, float(m[0, 3])))
    frame = Frame(shift=frame.shift, scale=frame.scale, x=np.empty(0), y=np.empty(0))  # release the unit-frame
    # copy before the residual sweep
    return _circle_from_conic(points, lambda xc, yc, r: frame.circle_to_data(np.array([xc, yc, r])),
                              [float(v) for v in a], message)


@register("circle.pratt", kind="closed form",
          summary="Pratt algebraic fit: constraint B^2 + C^2 - 4AD = 1",
          reference="Pratt, Computer Graphics 21(4) (1987) 145-152; Chernov (2010) sec. 5.5")
def pratt(points):
    """Minimise sum (A z_i + B x_i + C y_i + D)^2 subject to B^2 + C^2 - 4AD = 1 (Pratt 1987)."""
    return _constrained_fit(points, "pratt")


@register("circle.taubin", kind="closed form",
          summary="Taubin algebraic fit: residuals normalised by the mean squared gradient",
          reference="Taubin, IEEE Trans. PAMI 13 (1991) 1115-1138; Chernov (2010) sec. 5.9")
def taubin(points):
    """Minimise sum F_i^2 / mean |grad F_i|^2 for F = A z + B x + C y + D (Taubin 1991), i.e.
    the constraint 4 A^2 mean(z) + 4AB mean(x) + 4AC mean(y) + B^2 + C^2 = 1."""
    return _constrained_fit(points, "taubin")


@register("circle.hyper", kind="closed form",
          summary="Hyper (hyperaccurate) algebraic fit: constraint 2 N_Taubin - N_Pratt",
          reference="Al-Sharadqah & Chernov, Electron. J. Stat. 3 (2009) 886-911, sec. 7")
def hyper(points):
    """Algebraic fit with the constraint matrix N_H = 2 N_T - N_P that removes the essential
    second-order bias (Al-Sharadqah & Chernov 2009); smallest positive eigenvalue of M a = eta N_H a."""
    return _constrained_fit(points, "hyper")
