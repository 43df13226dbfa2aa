"""Levenberg–Marquardt geometric circle fit (MINPACK lmder through scipy)."""
from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from methods._registry import register
from methods._result import circle_result
from methods._validation import check_positive
from methods.circle._frame import Frame, kasa_xy


@register("circle.levenberg_marquardt", kind="iterative",
          summary="Levenberg–Marquardt geometric least squares (MINPACK lmder), analytic Jacobian",
          reference="Moré, LNM 630 (1978) 105-116; objective: circle/ellipse paper eq. 8-9, roundness paper eq. 3-4")
def levenberg_marquardt(points, *, xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=1000):
    """Minimise S_CG = sum d_i^2, d_i = r_i - R (circle/ellipse paper eq. 8-9) by damped Gauss–Newton
    (MINPACK's trust-region Levenberg–Marquardt) from Kåsa's algebraic start, in the unit frame.
    Tolerances are MINPACK's (relative); each iteration evaluates the Jacobian once."""
    name = "circle.levenberg_marquardt"
    for key, val in (("xtol", xtol), ("ftol", ftol), ("gtol", gtol)):
        check_positive(key, val, name)
    max_nfev = int(check_positive("max_nfev", max_nfev, name))
    frame = Frame.of(points)
    x, y = frame.x, frame.y
    p0 = kasa_xy(x, y)
    if not np.isfinite(p0).all():
        p0 = np.array([0.0, 0.0, 1.0])
    history = []

    def fun(p):
        return np.hypot(x - p[0], y - p[1]) - p[2]

    def jac(p):
        dx, dy = x - p[0], y - p[1]
        r = np.hypot(dx, dy)
        d = r - p[2]
        history.append(float(d @ d))  # objective at each accepted iterate
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.column_stack([-dx / r, -dy / r, -np.ones_like(r)])

    eps = np.finfo(float).eps
    res = least_squares(fun, p0, jac=jac, method="lm", xtol=max(xtol, eps), ftol=max(ftol, eps),
                        gtol=max(gtol, eps), max_nfev=max_nfev)
    center, radius = frame.circle_to_data(res.x)
    return circle_result(points, center, radius, converged=res.status > 0 and np.isfinite(res.x).all(),
                         message=res.message, iterations=int(res.njev or 0), nfev=int(res.nfev),
                         history=[h * frame.scale ** 2 for h in history], extra={"status": int(res.status)})
