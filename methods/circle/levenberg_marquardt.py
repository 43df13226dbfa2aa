"""Levenberg–Marquardt geometric circle fit (damped Gauss–Newton)."""
from __future__ import annotations

import math

import numpy as np

from methods._frame import dot

from methods._registry import register
from methods.circle.results import circle_result
from methods._validation import check_positive, check_vector
from methods.circle import _stationarity as stationarity
from methods.circle._frame import geometric_normal_equations, geometric_setup, solve_linear


def _reduction(arrays, h):
    """F(p) - F(p + h) (``arrays`` = (c, s, r, d) at p, dx = c r, dy = s r) without cancellation: d' - d = (r'^2 - r^2) / (r' + r) - h_R, with
    r'^2 - r^2 = -h_x (2 dx - h_x) - h_y (2 dy - h_y); F - F' = -sum (d' - d)(d' + d)."""
    c, s, r, d = arrays
    dx, dy = c * r, s * r
    ndx, ndy = dx - h[0], dy - h[1]
    rn = np.sqrt(ndx * ndx + ndy * ndy)
    delta = (-h[0] * (2 * dx - h[0]) - h[1] * (2 * dy - h[1])) / (rn + r) - h[2]
    return -dot(delta, 2 * d + delta)


@register("circle.levenberg_marquardt", kind="iterative",
          summary="Levenberg–Marquardt geometric least squares (Marquardt scaling, Nielsen damping update)",
          reference="Marquardt, SIAM J. Appl. Math. 11 (1963) 431-441; Madsen, Nielsen & Tingleff (2004) alg. 3.16; "
                    "objective: circle/ellipse paper eq. 8-9")
def levenberg_marquardt(points, *, xtol=1e-14, gtol=1e-14, tau=1e-3, max_iter=200, start=None):
    """Minimise S_CG = sum d_i^2, d_i = r_i - R (circle/ellipse paper eq. 8-9), from Kåsa's start
    (or ``start`` = (xc, yc, R) in data units).

    Each iteration solves (J^T J + mu diag(J^T J)) h = -J^T d (Marquardt's scaled damping); a step
    is accepted when F decreases, and mu is updated from the gain ratio rho by Nielsen's rule
    (mu *= max(1/3, 1 - (2 rho - 1)^3) on success, mu *= nu, nu *= 2 on failure), mu_0 = tau max diag.
    Stops when |h| <= xtol (|p| + xtol) or |J^T d|_inf / N <= gtol, in the unit frame. The gain
    ratio's actual reduction F(p) - F(p + h) is computed from residual differences, free of the
    cancellation that would otherwise reject good steps near the optimum.

    MINPACK's lmder (scipy ``method='lm'``) was used first; its ftol test stops when the relative
    reduction of F falls below ftol >= eps, which bounds the parameters' accuracy near
    sqrt(eps F) and left up to 8e-10 mm on the NIST reference sets: hence this direct implementation.
    """
    name = "circle.levenberg_marquardt"
    for key, val in (("xtol", xtol), ("gtol", gtol), ("tau", tau)):
        check_positive(key, val, name)
    max_iter = int(check_positive("max_iter", max_iter, name))
    p_start = check_vector("start", start, 3, name)
    frame, p, sweep, coordinates, ck = geometric_setup(points, p_start)
    solve = solve_linear(ck)
    n = len(points)
    if coordinates is None:  # compiled: the one sweep at p + h also gives the actual reduction from p
        def trial_state(p, h, arrays):
            return sweep(p + h, p)
    else:  # NumPy reference: a fresh workspace per state (the accepted state's arrays give the reduction)
        x, y = coordinates
        sweep = lambda q: geometric_normal_equations(x, y, q)  # noqa: E731

        def trial_state(p, h, arrays):
            trial = sweep(p + h)
            return trial, (_reduction(arrays, h) if trial is not None else None)
    state = sweep(p)
    if state is None:
        p = p + np.array([1e-6, 1e-6, 0.0])  # start on a data point: nudge it off
        state = sweep(p)
    f, jtj, jtd, arrays = state
    dj = jtj.diagonal().copy()  # (the same IEEE operations as np.diag/np.linalg.norm below, less overhead)
    mu, nu = tau * float(dj.max()), 2.0
    history, nfev = [f], 1
    converged, message = False, f"no convergence within max_iter={max_iter} iterations"
    it = 0
    for it in range(1, max_iter + 1):
        if max(map(abs, jtd.tolist())) / n <= gtol:
            converged, message = True, f"|J^T d|_inf / N <= gtol={gtol:g}"
            break
        try:
            damped = jtj.copy()
            damped.flat[::4] += mu * dj  # J^T J + mu diag(J^T J)
            h = solve(damped, -jtd)
        except np.linalg.LinAlgError:
            message = "singular damped system"
            break
        if math.sqrt(dot(h, h)) <= xtol * (math.sqrt(dot(p, p)) + xtol):
            converged, message = True, f"|h| <= xtol={xtol:g} (|p| + xtol)"
            break
        trial, reduction = trial_state(p, h, arrays)
        nfev += 1
        if trial is None:
            mu, nu = mu * nu, 2 * nu
            continue
        predicted = dot(h, mu * dj * h - jtd)  # L(0) - L(h), times 2
        rho = reduction / predicted if predicted > 0 else -1.0
        if rho > 0:
            p = p + h
            f, jtj, jtd, arrays = trial
            dj = jtj.diagonal().copy()
            history.append(f)
            mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            nu = 2.0
        else:
            mu, nu = mu * nu, 2 * nu
    extra = {"final_damping": mu}
    if converged:  # a flag is a promise: check first-order optimality of S_CG at the returned point
        check = stationarity.geometric_from_state(p, (f, jtj, jtd, arrays), frame.ulp, ck,
                                                  stationarity.unit_coordinates(points, frame, coordinates))
        converged = check.ok
        message = f"{message}; {check.text}"
        extra.update(check.extra(frame.power(2)))
    center, radius = frame.circle_to_data(p)
    return circle_result(points, center, radius, converged=converged, message=message, iterations=it,
                         nfev=nfev, history=[v * frame.power(2) for v in history], extra=extra)
