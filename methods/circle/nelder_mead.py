"""Program FCG of the circle/ellipse paper: geometric circle fit by the Nelder–Mead simplex method."""
from __future__ import annotations

import numpy as np

from methods._frame import dot

from methods import _simplex as simplex
from methods._errors import InvalidInputError
from methods._registry import register
from methods.circle.results import circle_result
from methods._validation import check_choice, check_positive, check_vector
from methods.circle import _stationarity as stationarity
from methods.circle._frame import Frame, algebraic_start


@register("circle.nelder_mead", kind="iterative",
          summary="FCG: geometric sum of squares (eq. 9) by Nelder–Mead, simplex from s1S and lambda",
          reference="Glavonjić, circle/ellipse paper, eq. 8-9 (program FCG, table 2); Nelder & Mead, Comput. J. 7 (1965) 308-313")
def nelder_mead(points, *, backend="scipy", start=None, step=None, xatol=1e-15, fatol=0.0, max_fev=20000):
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
        # sqrt(dx dx + dy dy) - R in place: the same operations in the same order, two arrays of N
        dx, dy = x - p[0], y - p[1]
        dx *= dx
        dy *= dy
        dx += dy
        np.sqrt(dx, out=dx)
        dx -= p[2]
        return dot(dx, dx)

    # Stopping tolerances at the objective's resolution (README, NIST): values of S_CG scatter by their
    # rounding noise once the simplex is small, so asking for a smaller simplex makes the stop a matter of
    # the last bit. Each run has at most RUN_BUDGET evaluations (a simplex that wanders in the
    # noise stagnates there); the flag is then decided by the point, never by which rule ended the run:
    # converged = stationary (first-order optimum of S_CG, checked below). A run that ends at a point that
    # is not stationary (a far start, a collapsed simplex) is restarted there with a fresh simplex of the
    # same steps (Kelley's restart), within the total budget max_fev.
    p, history, iterations, nfev, restarts = x0, [], 0, 0, 0
    while True:
        xat, fat = _resolution_tolerances(x, y, p, xatol, fatol)
        run = simplex.nelder_mead(objective, p, lam_unit, backend=backend, xatol=xat, fatol=fat,
                                  max_fev=min(RUN_BUDGET, max_fev - nfev))
        history += run.history
        iterations = None if run.iterations is None else iterations + run.iterations
        nfev += run.nfev
        p = run.x
        check = stationarity.geometric(x, y, p, frame.ulp)
        if check.ok or check.degenerate or restarts >= MAX_RESTARTS or nfev >= max_fev:
            break
        restarts += 1
    converged = check.ok
    how = "simplex within tolerance" if run.converged else f"run stopped after {run.nfev} evaluations"
    message = (f"{run.message} ({how}; xatol={xat:.1e}, fatol={fat:.1e}: the resolution of S_CG, unit frame"
               f"{f'; {restarts} restart(s)' if restarts else ''}); {check.text}")
    if not converged and not check.degenerate:
        message += f"; gave up after {nfev} of max_fev={max_fev} evaluations"
    center, radius = frame.circle_to_data(p)
    return circle_result(points, center, radius, converged=converged, message=message,
                         iterations=iterations, nfev=nfev, history=[h * frame.power(2) for h in history],
                         extra={"restarts": restarts, "xatol_used": xat * frame.scale, "fatol_used": fat * frame.power(2),
                                "simplex_stop": bool(run.converged), **check.extra(frame.power(2))})


#: evaluations per Nelder–Mead run (a converging run from Kåsa's start needs 100-600) and restarts at most
RUN_BUDGET = 2000
MAX_RESTARTS = 5


def _resolution_tolerances(x, y, p, xatol: float, fatol: float) -> tuple[float, float]:
    """(xatol, fatol) raised to the resolution of S_CG at p. Each residual d_i = r_i - R carries a
    rounding error of about eps (r_i + R), so values of S_CG = sum d_i^2 scatter by
    noise = 4 eps sqrt(sum d_i^2 (r_i + R)^2) (+ eps^2 sum (r_i + R)^2 for residuals at rounding level),
    which is far above eps F when the residuals are small. A simplex smaller than
    sqrt(noise / lambda_min(J^T J)) can no longer be ordered by its values: asking for less makes the
    stop a matter of the last bit. fatol = 2 noise (the values' own scatter passes it), xatol = a quarter of
    that size (values there differ by ~noise/16: shrink steps still reduce the simplex), at least the
    caller's values. Unit frame."""
    dx, dy = x - p[0], y - p[1]
    r = dx * dx  # the operations of r = sqrt(dx dx + dy dy), c, s = dx / r, dy / r, d = r - R, w = r + |R|,
    d = dy * dy  # in place: four arrays of N (peak memory), the same values
    r += d
    np.sqrt(r, out=r)
    with np.errstate(divide="ignore", invalid="ignore"):
        c, s = np.divide(dx, r, out=dx), np.divide(dy, r, out=dy)
    np.subtract(r, p[2], out=d)
    w = np.add(r, abs(float(p[2])), out=r)
    eps = np.finfo(float).eps
    ww = dot(w, w)
    d *= d
    w *= w
    noise = 4 * eps * np.sqrt(dot(d, w)) + eps * eps * ww
    del d, w
    jtj = np.array([[dot(c, c), dot(c, s), c.sum()], [dot(c, s), dot(s, s), s.sum()], [c.sum(), s.sum(), float(len(x))]])
    if not np.isfinite(jtj).all():
        return xatol, fatol
    lam_min = max(float(np.linalg.eigvalsh(jtj)[0]), eps * len(x))
    return max(xatol, 0.25 * float(np.sqrt(noise / lam_min))), max(fatol, 2 * noise)
