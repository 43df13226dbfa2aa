"""Gauss–Newton geometric circle fit as in the roundness paper (Pınar & Güllü, sec. 3)."""
from __future__ import annotations

import math

import numpy as np

from methods._frame import dot
from methods._registry import register
from methods.circle.results import circle_result
from methods._validation import check_choice, check_positive, check_vector
from methods.circle import _stationarity as stationarity
from methods.circle._frame import geometric_setup, solve_linear

STOPPING_CRITERIA = ("objective", "step", "gradient")
EPS = np.finfo(float).eps


@register("circle.gauss_newton", kind="iterative",
          summary="Gauss–Newton geometric least squares from the algebraic start (roundness paper)",
          reference="Pınar & Güllü, roundness paper, eq. 7 (start), 8-10 (Jacobian), 12-13 (step)")
def gauss_newton(points, *, stop="step", xtol=1e-12, ftol=1e-14, gtol=1e-14, max_iter=100, start=None):
    """Minimise F = sum d_i^2, d_i = r_i - R (eq. 3-4), by Gauss–Newton.

    Start: Kåsa's algebraic solution of eq. 7 (the paper's), or ``start`` = (xc, yc, R) in data units. Each iteration solves J Delta = -d in the least-squares
    sense with J of eq. 10 (rows [-(x_i - xc)/r_i, -(y_i - yc)/r_i, -1]) and updates by eq. 13.
    The paper lists three stopping criteria; ``stop`` selects one, in the unit frame (data centred,
    RMS radius 1, so the tolerances are relative to the size of the data):

    * ``"objective"`` — 1. the change of F is small: |F_{k-1} - F_k| <= ftol * F_{k-1} + the
      rounding noise of F (4 eps sqrt(N F) max r_i);
    * ``"step"`` — 2. the step is small: (Delta^T Delta)^(1/2) <= xtol (the paper's choice, default;
      the paper stops at 1e-4 mm, which is far from the optimum's precision; pass xtol to mimic it);
    * ``"gradient"`` — 3. g = J^T d is small: |g| / N <= gtol.
    """
    name = "circle.gauss_newton"
    check_choice("stop", stop, STOPPING_CRITERIA, name)
    for key, val in (("xtol", xtol), ("ftol", ftol), ("gtol", gtol)):
        check_positive(key, val, name)
    max_iter = int(check_positive("max_iter", max_iter, name))
    p_start = check_vector("start", start, 3, name)
    frame, p, sweep, coordinates, ck = geometric_setup(points, p_start)  # compiled: no unit-frame copy, one sweep per state
    solve = solve_linear(ck)
    n = len(points)
    history, steps = [], []
    converged, message = False, f"no convergence within max_iter={max_iter} iterations"
    state = sweep(p)  # J of eq. 10, as J^T J and J^T d, and F: one sweep
    f_prev = None
    it = 0
    for it in range(1, max_iter + 1):
        if state is None:
            message = "an iterate's centre coincides with a data point (Jacobian eq. 9 undefined)"
            break
        f, jtj, jtd, _ = state
        history.append(f)
        if stop == "gradient" and math.sqrt(dot(jtd, jtd)) / n <= gtol:
            converged, message = True, f"|J^T d|/N <= gtol={gtol:g}"
            break
        # F is a sum of squared differences of O(1) numbers: its rounding noise is ~2 eps sqrt(N F) r_max
        pr = float(p[2])  # plain floats: the same IEEE operations as NumPy scalars, less overhead
        noise = 8.0 * EPS * math.sqrt(n * f * (f / n + 4.0 * pr * pr))
        if stop == "objective" and f_prev is not None and abs(f_prev - f) <= ftol * f_prev + noise:
            converged, message = True, f"|F_(k-1) - F_k| <= ftol={ftol:g} * F_(k-1) (+ rounding noise of F)"
            break
        try:
            delta = solve(jtj, -jtd)  # normal equations of J Delta = -d (eq. 12)
        except np.linalg.LinAlgError:
            message = "singular Gauss–Newton system (J^T J not invertible)"
            break
        # the decrease of F this step promises, against F's rounding noise (8 eps sqrt(F sum (r_i + R)^2)):
        # below it, and not shrinking any more, steps are rounding noise and can never reach xtol
        promised = -dot(delta, jtd)
        s2 = max(f - 4.0 * abs(pr) * float(jtd[2]) + 4.0 * n * pr * pr, 0.0)
        f_noise = 8.0 * EPS * math.sqrt(f * s2) + 16.0 * EPS * EPS * s2
        p = p + delta  # eq. 13
        if not all(map(math.isfinite, p)):
            message = "Gauss–Newton diverged (non-finite iterate)"
            break
        step = math.sqrt(dot(delta, delta))
        steps.append(step)
        f_prev = f
        state = sweep(p)
        if stop == "step" and step <= xtol:
            converged, message = True, f"(Delta^T Delta)^(1/2) <= xtol={xtol:g}"
            break
        if stop == "step" and promised <= f_noise and len(steps) > 1 and step >= 0.5 * steps[-2]:
            converged = True
            message = (f"(Delta^T Delta)^(1/2) = {step:.1e} stopped shrinking with a promised decrease of F "
                       f"below its rounding noise (xtol={xtol:g} is below the resolution)")
            break
    if converged:  # a flag is a promise: check first-order optimality of S_CG at the returned point
        check = stationarity.geometric_from_state(p, state if all(map(math.isfinite, p)) else None, frame.ulp, ck,
                                                  stationarity.unit_coordinates(points, frame, coordinates))
        converged = check.ok
        message = f"{message}; {check.text}"
    else:
        check = None
    center, radius = frame.circle_to_data(p)
    scale2 = frame.power(2)
    scale = frame.scale
    del state, sweep, frame, coordinates  # the result's residual sweep needs none of them
    extra = {"step_norms": [s * scale for s in steps], "stop": stop}
    if check is not None:
        extra.update(check.extra(scale2))
    return circle_result(points, center, radius, converged=converged, message=message, iterations=it,
                         nfev=it, history=[h * scale2 for h in history], extra=extra)
