"""Program FCG of the circle/ellipse paper: geometric circle fit by the Nelder–Mead simplex method."""
from __future__ import annotations

import numpy as np

from methods import _simplex as simplex
from methods._errors import InvalidInputError
from methods._registry import register
from methods._result import circle_result
from methods._validation import check_choice, check_positive, check_vector
from methods.circle._frame import Frame, algebraic_start


@register("circle.nelder_mead", kind="iterative",
          summary="FCG: geometric sum of squares (eq. 9) by Nelder–Mead, simplex from s1S and lambda",
          reference="Glavonjić, circle/ellipse paper, eq. 8-9 (program FCG, table 2); Nelder & Mead, Comput. J. 7 (1965) 308-313")
def nelder_mead(points, *, backend="scipy", start=None, step=None, xatol=1e-13, fatol=1e-16, max_fev=20000):
    """Minimise S_CG = sum (sqrt((x_i - xc)^2 + (y_i - yc)^2) - R)^2 (eq. 8-9) with Nelder–Mead.

    The initial simplex is the first vertex s1S = ``start`` = (xc, yc, R) and s1S + lambda_j e_j
    with ``step`` = lambda (table 2: s1S = (0, 0, 299), lambda = (0.001, 0.001, 0.001) mm), both in
    data units. Defaults: start = Kåsa's algebraic circle, lambda = 1e-3 x the RMS radius of the data.
    ``backend`` is ``"scipy"`` (scipy.optimize, ``iterations`` = simplex iterations) or ``"nlopt"``
    (NLopt's LN_NELDERMEAD with the same simplex; NLopt does not count iterations, so
    ``iterations`` is None and ``history`` is the best objective after each evaluation).
    scipy stops when the simplex is smaller than ``xatol`` and its values differ by at most
    ``fatol``; NLopt stops on ``xatol`` alone (its ftol means one small step, which halts Nelder–Mead
    early). Both in the unit frame (data centred, RMS radius 1); the paper's epsilon was 1e-9.
    Comparing values of S_CG in float64 resolves the optimum only to about
    sqrt(eps * S* / lambda_min(J^T J)); Nelder–Mead cannot do better than that (README, NIST).
    """
    name = "circle.nelder_mead"
    check_choice("backend", backend, simplex.BACKENDS, name)
    check_positive("xatol", xatol, name)
    check_positive("fatol", fatol, name, allow_zero=True)
    max_fev = int(check_positive("max_fev", max_fev, name))
    s1 = check_vector("start", start, 3, name)
    lam = check_vector("step", step, 3, name)
    if lam is not None and np.any(lam == 0):
        raise InvalidInputError(f"{name}: every simplex step lambda_j must be non-zero, got {step!r}")
    frame = Frame.of(points)
    x, y = frame.x, frame.y
    x0 = algebraic_start(x, y) if s1 is None else frame.circle_to_unit(s1)
    lam_unit = np.full(3, 1e-3) if lam is None else lam / frame.scale

    def objective(p):
        dx, dy = x - p[0], y - p[1]
        d = np.sqrt(dx * dx + dy * dy) - p[2]
        return float(d @ d)

    run = simplex.nelder_mead(objective, x0, lam_unit, backend=backend, xatol=xatol, fatol=fatol, max_fev=max_fev)
    center, radius = frame.circle_to_data(run.x)
    return circle_result(points, center, radius, converged=run.converged, message=run.message,
                         iterations=run.iterations, nfev=run.nfev, history=[h * frame.scale ** 2 for h in run.history])
