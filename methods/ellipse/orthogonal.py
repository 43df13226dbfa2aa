"""Orthogonal-distance (geometric) least-squares ellipse fit."""
from __future__ import annotations

import math

import numpy as np

from methods._compiled import kernels
from methods._frame import dot
from methods._registry import register
from methods._validation import check_positive, check_vector
from methods.ellipse._checks import degenerate_reason, stationarity_probe, sum_of_squares_noise
from methods.ellipse._geometry import Frame, canonical, orthogonal_residuals
from methods.ellipse.results import ellipse_result, failed, history_to_data
from methods.ellipse._validation import check_distinct_points
from methods.ellipse.direct import halir_flusser_unit


def distance_jacobian(x, y, p, phi):
    """d d_i / d(xc, yc, a, b, theta) at the closest points phi_i: by the envelope theorem the closest
    point may be held fixed, so d_i = n_i . (P_i - X(phi_i)) gives -n_i . dX/dp (Ahn et al. 2001,
    Gander, Golub & Strebel 1994), with X(phi) = c + R(theta) [a cos phi, b sin phi] and n_i the
    outward unit normal."""
    xc, yc, a, b, t = p
    c, s = np.cos(t), np.sin(t)
    cp, sp_ = np.cos(phi), np.sin(phi)
    # outward normal in the ellipse frame ~ (cos phi / a, sin phi / b), rotated to the data frame
    nx_l, ny_l = cp / a, sp_ / b
    norm = np.hypot(nx_l, ny_l)
    nx_l, ny_l = nx_l / norm, ny_l / norm
    nx, ny = c * nx_l - s * ny_l, s * nx_l + c * ny_l
    J = np.empty((len(x), 5))
    J[:, 0] = -nx
    J[:, 1] = -ny
    J[:, 2] = -(nx * c * cp + ny * s * cp)          # dX/da = R [cos phi, 0]
    J[:, 3] = -(-nx * s * sp_ + ny * c * sp_)       # dX/db = R [0, sin phi]
    lx, ly = a * cp, b * sp_                         # dX/dtheta = R' [a cos phi, b sin phi]
    J[:, 4] = -(nx * (-s * lx - c * ly) + ny * (c * lx - s * ly))
    return J


#: MINPACK's info -> scipy.optimize.least_squares' status, and its messages (the values this fit reported when it
#: called least_squares(method="lm"); info 6-8 cannot occur with tolerances >= eps)
_FROM_MINPACK = {0: -1, 1: 2, 2: 3, 3: 4, 4: 1, 5: 0}
_MESSAGES = {-1: "Improper input parameters status returned from `leastsq`",
             0: "The maximum number of function evaluations is exceeded.",
             1: "`gtol` termination condition is satisfied.",
             2: "`ftol` termination condition is satisfied.",
             3: "`xtol` termination condition is satisfied.",
             4: "Both `ftol` and `xtol` termination conditions are satisfied."}


@register("ellipse.orthogonal", kind="iterative",
          summary="Orthogonal-distance least squares: damped Gauss–Newton (MINPACK lmder), analytic Jacobian",
          reference="Gander, Golub & Strebel, BIT 34 (1994) 558-578; Ahn, Rauh & Warnecke, Pattern Recogn. 34 (2001) "
                    "2283-2303 (circle/ellipse paper refs. 1, 4)")
def orthogonal(points, *, start=None, xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=500):
    """Minimise the sum of squared orthogonal distances d_i from the points to the ellipse
    p = (xc, yc, a, b, theta) (circle/ellipse paper eq. 22, S_EG) by MINPACK's Levenberg–Marquardt
    with the analytic Jacobian of :func:`distance_jacobian`. Every evaluation solves the closest points of all
    points once and reduces [J d] (N x 6) to the R of its QR in the same sweep (compiled:
    methods/ellipse/_ckernels.c distances_qr); MINPACK gets the equivalent 6-row problem f = (q, rho), R1 (see
    ``fun`` below), so no N x 5 Jacobian is ever stored. Start: ``start`` = (xc, yc, a, b, theta) in data units,
    default Halir & Flusser's direct fit. In the unit frame; tolerances are MINPACK's. ``converged`` needs
    MINPACK's success, a stationary point for the Levenberg–Marquardt probe of :mod:`methods.ellipse._checks`
    (on the same R) and a non-degenerate ellipse."""
    name = "ellipse.orthogonal"
    for key, val in (("xtol", xtol), ("ftol", ftol), ("gtol", gtol)):
        check_positive(key, val, name)
    max_nfev = int(check_positive("max_nfev", max_nfev, name))
    p_start = check_vector("start", start, 5, name)
    check_distinct_points(points, 5, name)
    frame = Frame.of(points)
    x, y = frame.x, frame.y
    if p_start is None:
        p0, why = halir_flusser_unit(frame)
        if p0 is None:
            return failed(points, f"no start: the direct fit failed ({why}); pass start=")
    else:
        p0 = frame.params_to_unit(p_start)
        if not (np.isfinite(p0).all() and p0[2] > 0 and p0[3] > 0):
            return failed(points, f"start {p_start.tolist()} is not an ellipse representable in the data's frame "
                                  f"(RMS radius {frame.scale:.3g}); give positive semi-axes near the data")
    history = []
    cache = []   # the last two evaluations, newest first: MINPACK's answer is often the one before its last trial
    n = len(x)
    ck = kernels("methods.ellipse._ckernels")

    def lookup(p):
        for e in cache:
            if np.array_equal(e["p"], p):
                return e
        return None

    def evaluate(p, with_qr=True):
        """The distances d at p, their sum of squares S and (``with_qr``) the 6 x 6 R of the QR of [J d], once per p
        (MINPACK's function and Jacobian share them). Compiled: one sweep computing d and folding the rows of
        [J d] into R as it goes (methods/ellipse/_ckernels.c distances_qr: the N x 5 Jacobian is never stored);
        without R (the probe's trial points), the distances alone (orthogonal(), the same bits). NumPy reference
        path (FITBENCH_KERNELS=numpy), and any p that is not a finite ellipse with positive semi-axes: the closest
        points' phi, the Jacobian of :func:`distance_jacobian` and LAPACK's QR. Returns the cache entry."""
        e = lookup(p)
        if e is not None and (e["R"] is not None or not with_qr):
            return e
        if e is not None:  # distances-only evaluation at p: again, with R
            cache.remove(e)
        xc, yc, a, b, t = (float(v) for v in p)
        R = None
        if ck is not None and a > 0 and b > 0 and all(map(math.isfinite, (xc, yc, a, b, t))):
            d = np.empty(n)
            if with_qr:
                R = np.empty((6, 6))
                S = ck.distances_qr(x, y, xc, yc, math.cos(t), math.sin(t), a, b, 60, d, R)
            else:
                ck.orthogonal(x, y, xc, yc, math.cos(t), math.sin(t), a, b, 60, d)
                S = dot(d, d)
        else:
            d, phi = orthogonal_residuals(x, y, p)
            S = dot(d, d)
            if with_qr:
                A = np.empty((n, 6), order="F")
                A[:, :5] = distance_jacobian(x, y, p, phi)
                A[:, 5] = d
                R = np.linalg.qr(A, mode="r") if np.isfinite(A).all() else np.full((6, 6), np.nan)
        e = {"p": p.copy(), "d": d, "S": float(S), "R": R, "f": None}
        cache.insert(0, e)
        del cache[2:]
        return e

    def fun(p):
        """MINPACK's residual vector at p: f = (q, rho) with R = [[R1, q], [0, rho]], rho = sqrt(S - |q|^2), so that
        |f|^2 = S = sum d_i^2 (taken directly, to its own rounding) and f's Jacobian R1 gives MINPACK the same
        Levenberg-Marquardt subproblem as the N distances would (|J dp + d|^2 = |R1 dp + q|^2 + rho^2): MINPACK
        works on 6 x 5 instead of N x 5."""
        e = evaluate(p)
        if e["f"] is None:
            R, S = e["R"], e["S"]
            f = np.full(6, np.inf)
            if math.isfinite(S) and np.isfinite(R).all():
                f[:5] = R[:5, 5]
                f[5] = math.sqrt(max(S - dot(f[:5], f[:5]), 0.0))
            e["f"] = f
        return e["f"]

    def minpack_jac(p):
        e = evaluate(p)
        history.append(e["S"])
        J = np.zeros((6, 5))
        J[:5] = e["R"][:5, :5]
        return J

    eps = np.finfo(float).eps
    from scipy.optimize import leastsq  # imported on first use (light import)

    # MINPACK's lmder, as scipy's least_squares(method="lm", x_scale="jac") calls it (diag None, factor 100),
    # without least_squares' wrappers. leastsq first calls fun and Dfun once at p0 to check their shapes (the cache
    # answers both); the history keeps MINPACK's own Jacobian evaluations: the objective at each accepted iterate.
    q, _, info, _, ier = leastsq(fun, np.array(p0, dtype=np.float64), Dfun=minpack_jac, full_output=True,
                                 ftol=max(ftol, eps), xtol=max(xtol, eps), gtol=max(gtol, eps),
                                 maxfev=max_nfev, factor=100.0, diag=None)
    njev, nfev = int(info.get("njev", 0)), int(info["nfev"])
    history = history[1:1 + njev]
    status = _FROM_MINPACK.get(int(ier), -1)
    converged, message = bool(status > 0 and np.isfinite(q).all()), _MESSAGES.get(status, f"MINPACK info {ier}")
    extra = {"status": int(status)}
    why = degenerate_reason(abs(q[2]), abs(q[3])) if np.isfinite(q).all() else "the solution is not finite"
    if why is not None:
        converged, message = False, f"{why} ({message})"
        extra["degenerate"] = why
    elif converged:
        def residuals(p):
            return evaluate(p, with_qr=False)["d"] if p[2] > 0 and p[3] > 0 else np.full(n, np.inf)

        def triangular(p):
            return evaluate(p)["R"] if p[2] > 0 and p[3] > 0 else np.full((6, 6), np.nan)

        def noise(r, p):
            c = abs(p[0]) + abs(p[1]) + max(abs(p[2]), abs(p[3]))
            return sum_of_squares_noise(r, lambda part: np.abs(x[part]) + np.abs(y[part]) + c)

        probe = stationarity_probe(residuals, None, q, noise=noise, triangular=triangular)
        extra["stationarity"] = probe.as_dict()
        if not probe.stationary:
            converged, message = False, f"{probe.reason()} (MINPACK: {message})"
    p = canonical(frame.params_to_data(q))
    residuals = None
    if np.isfinite(q).all() and min(abs(q[2]), abs(q[3])) > 0:
        # the closest points of an evaluation at q (MINPACK's answer, then the probe, evaluate there)
        e = lookup(q)
        d_unit = e["d"] if e is not None else orthogonal_residuals(x, y, canonical(q), with_phi=False)[0]
        residuals = np.multiply(d_unit, frame.scale, out=d_unit)  # the evaluation's own array: no copy
    hist = history_to_data(history, frame.scale, 2)
    if hist is None:
        hist, extra["history_units"] = history, "unit frame (the data-unit values, length^2, overflow)"
    return ellipse_result(points, p, converged=converged, message=message, iterations=njev,
                          nfev=nfev, history=hist, extra=extra,
                          residuals=residuals)
