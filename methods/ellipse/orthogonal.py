"""Orthogonal-distance (geometric) least-squares ellipse fit."""
from __future__ import annotations

import numpy as np

from methods._registry import register
from methods._validation import check_positive, check_vector
from methods.ellipse._checks import degenerate_reason, stationarity_probe, sum_of_squares_noise
from methods.ellipse._geometry import Frame, canonical, orthogonal_residuals
from methods.ellipse._result import ellipse_result, failed, history_to_data
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


@register("ellipse.orthogonal", kind="iterative",
          summary="Orthogonal-distance least squares: damped Gauss–Newton (MINPACK lmder), analytic Jacobian",
          reference="Gander, Golub & Strebel, BIT 34 (1994) 558-578; Ahn, Rauh & Warnecke, Pattern Recogn. 34 (2001) "
                    "2283-2303 (circle/ellipse paper refs. 1, 4)")
def orthogonal(points, *, start=None, xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=500):
    """Minimise the sum of squared orthogonal distances d_i from the points to the ellipse
    p = (xc, yc, a, b, theta) (circle/ellipse paper eq. 22, S_EG) by MINPACK's Levenberg–Marquardt
    with the analytic Jacobian of :func:`distance_jacobian`; every evaluation solves the closest
    points of all points at once, once (the Jacobian reuses them). Start: ``start`` = (xc, yc, a, b,
    theta) in data units, default Halir & Flusser's direct fit. In the unit frame; tolerances are
    MINPACK's. ``converged`` needs MINPACK's success, a stationary point for the Levenberg–Marquardt probe of
    :mod:`methods.ellipse._checks` and a non-degenerate ellipse."""
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
    cache = {}

    def solve(p):
        """Closest points of every point for p, once per p (fun and jac share them)."""
        if "p" not in cache or not np.array_equal(cache["p"], p):
            d, phi = orthogonal_residuals(x, y, p)
            cache["p"], cache["d"], cache["phi"] = p.copy(), d, phi
        return cache["d"], cache["phi"]

    def fun(p):
        return solve(p)[0]

    def jac(p):
        d, phi = solve(p)
        history.append(float(d @ d))
        return distance_jacobian(x, y, p, phi)

    eps = np.finfo(float).eps
    from scipy.optimize import least_squares  # imported on first use (light import)

    res = least_squares(fun, p0, jac=jac, method="lm", xtol=max(xtol, eps), ftol=max(ftol, eps),
                        gtol=max(gtol, eps), max_nfev=max_nfev, x_scale="jac")
    q = res.x
    converged, message = bool(res.status > 0 and np.isfinite(q).all()), str(res.message)
    extra = {"status": int(res.status)}
    why = degenerate_reason(abs(q[2]), abs(q[3])) if np.isfinite(q).all() else "the solution is not finite"
    if why is not None:
        converged, message = False, f"{why} ({message})"
        extra["degenerate"] = why
    elif converged:
        def residuals(p):
            return fun(p) if p[2] > 0 and p[3] > 0 else np.full(len(x), np.inf)

        probe = stationarity_probe(residuals, lambda p: jac(p) if p[2] > 0 and p[3] > 0 else np.full((len(x), 5), np.nan),
                                   q, noise=lambda r, p: sum_of_squares_noise(r, np.abs(x) + np.abs(y) + abs(p[0]) +
                                                                              abs(p[1]) + max(abs(p[2]), abs(p[3]))))
        history = history[:int(res.njev or 0)]
        extra["stationarity"] = probe.as_dict()
        if not probe.stationary:
            converged, message = False, f"{probe.reason()} (MINPACK: {message})"
    p = canonical(frame.params_to_data(q))
    residuals = None
    if np.isfinite(q).all() and min(abs(q[2]), abs(q[3])) > 0:
        # the closest points of the last evaluation when it was at q (MINPACK's answer usually is)
        d_unit = cache["d"] if np.array_equal(cache.get("p"), q) else \
            orthogonal_residuals(x, y, canonical(q), with_phi=False)[0]
        residuals = d_unit * frame.scale
    hist = history_to_data(history, frame.scale, 2)
    if hist is None:
        hist, extra["history_units"] = history, "unit frame (the data-unit values, length^2, overflow)"
    return ellipse_result(points, p, converged=converged, message=message, iterations=int(res.njev or 0),
                          nfev=int(res.nfev), history=hist, extra=extra,
                          residuals=residuals)
