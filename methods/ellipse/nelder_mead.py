"""Programs FEA and FEG of the circle/ellipse paper: algebraic and geometric ellipse fits by
Nelder–Mead, parameters p = (p_x, p_y, gamma, x_C, y_C) as in its tables 3 and 4.

Stopping and the converged flag (the same for both programs):
- Nelder–Mead stops when the values on its simplex differ by no more than ``fatol``, never less than the
  rounding noise of the objective at the best vertex (below it the simplex only sees rounding, its moves
  depend on the last bit and a run wanders until its budget: the status would flip between CPUs), and,
  if ``xatol`` is given, when the simplex is also smaller than ``xatol`` (unit frame).
- Then a short Levenberg–Marquardt probe from the best vertex (:mod:`methods.ellipse._checks`) tests
  stationarity of the objective. Where it finds a decrease, Nelder–Mead is restarted from that vertex with
  the initial steps (the remedy for stagnation of Kelley, SIAM J. Optim. 10 (1999) 43-55), until the probe
  finds the point stationary or the budget ``max_fev`` is spent.
- ``converged=True`` only for a stationary, non-degenerate ellipse; a collapsed ellipse (the algebraic
  objective eq. 16 is 0 at p_x = p_y = 0) or one running off to infinity is reported as degenerate.
"""
from __future__ import annotations

import numpy as np

from methods import _simplex as simplex
from methods._errors import InvalidInputError
from methods._frame import dot
from methods._registry import register
from methods._validation import check_choice, check_positive, check_vector
from methods.circle._frame import kasa_xy
from methods.ellipse._checks import degenerate_reason, stationarity_probe, sum_of_squares_noise, triangular_by_blocks
from methods.ellipse._geometry import Frame, orthogonal_residuals, to_local
from methods.ellipse.results import ellipse_result, failed, history_to_data, residuals_from_unit
from methods.ellipse._validation import check_distinct_points
from methods.ellipse.orthogonal import distance_jacobian

PAPER_ORDER = "(p_x, p_y, gamma, x_C, y_C)"
#: Restarts of Nelder–Mead from its best vertex at most (each must lower the objective).
MAX_ROUNDS = 30


def _setup(points, name, backend, start, step, xatol, fatol, max_fev):
    check_choice("backend", backend, simplex.BACKENDS, name)
    if xatol is not None:
        check_positive("xatol", xatol, name)
    if fatol is not None:
        check_positive("fatol", fatol, name, allow_zero=True)
    max_fev = int(check_positive("max_fev", max_fev, name))
    s1 = check_vector("start", start, 5, name)
    lam = check_vector("step", step, 5, name)
    if lam is not None and np.any(lam == 0):
        raise InvalidInputError(f"{name}: every simplex step lambda_j must be non-zero, got {step!r}")
    check_distinct_points(points, 5, name)
    frame = Frame.of(points)
    if s1 is None:  # a circle: Kåsa's, as p_x = p_y = R, gamma = 0 (the paper starts from a circle too)
        xc, yc, r = kasa_xy(frame.x, frame.y)
        x0 = np.array([r, r, 0.0, xc, yc]) if np.isfinite(r) else np.array([1.0, 1.0, 0.0, 0.0, 0.0])
    else:
        px, py, g, xc, yc = s1
        x0 = np.array([px / frame.scale, py / frame.scale, g, (xc - frame.shift[0]) / frame.scale,
                       (yc - frame.shift[1]) / frame.scale])
        if not np.isfinite(x0).all():
            raise InvalidInputError(f"{name}: start {start!r} is too far from the data ({frame.scale:.3g} RMS radius) "
                                    "to be represented in its frame")
    if lam is None:
        lam_unit = np.array([1e-3, 1e-3, 1e-2, 1e-3, 1e-3])
    else:
        lam_unit = np.array([lam[0] / frame.scale, lam[1] / frame.scale, lam[2], lam[3] / frame.scale,
                             lam[4] / frame.scale])
        if not (np.isfinite(lam_unit).all() and np.all(lam_unit != 0)):
            raise InvalidInputError(f"{name}: step {step!r} is not representable relative to the data's size "
                                    f"({frame.scale:.3g} RMS radius)")
    return frame, x0, lam_unit, max_fev


def _minimise(objective, residuals, jacobian, noise, x0, lam, *, n, backend, xatol, fatol, max_fev):
    """Nelder–Mead rounds until the probe finds the best vertex stationary (see the module docstring).
    ``residuals(q, part)`` and ``jacobian(q, part)`` evaluate a slice of the points: the probe's R of [J r] is
    built block by block (:func:`~methods.ellipse._checks.triangular_by_blocks`), never the N x 5 Jacobian.
    Returns (x, converged, message, iterations, nfev, history, stationarity)."""
    x = np.asarray(x0, dtype=np.float64)
    triangular = triangular_by_blocks(jacobian, residuals, n)
    history, iterations, nfev, probe, message = [], 0, 0, None, ""
    f_best = float(objective(x))
    stalled = 0
    for round_ in range(1, MAX_ROUNDS + 1):
        left = max_fev - nfev
        if left <= len(x) + 1:
            message = f"evaluation budget max_fev={max_fev} spent"
            break
        r_now = residuals(x)
        fatol_eff = max(float(fatol or 0.0), sum_of_squares_noise(r_now, lambda part: noise(x, part))
                        if np.isfinite(r_now).all() else 0.0)
        del r_now  # not held through the run (peak memory)
        xtol = xatol if xatol is not None else (np.inf if backend == "scipy" else 1e-13)
        # after a restart without progress, one more from a simplex reflected and ten times larger (a collapsed
        # simplex can stall Nelder-Mead away from a minimum: McKinnon 1998; Kelley 1999 restarts it afresh)
        steps = lam if stalled == 0 else -10.0 * lam
        run = simplex.nelder_mead(objective, x, steps, backend=backend, xatol=xtol, fatol=fatol_eff, max_fev=left)
        iterations += run.iterations or 0
        nfev += run.nfev
        history += run.history
        f_run = float(objective(run.x))
        progressed = f_run < f_best
        if progressed or round_ == 1:
            x, f_best = np.asarray(run.x, dtype=np.float64), min(f_run, f_best)
        probe = stationarity_probe(residuals, None, x, noise=lambda r, q: sum_of_squares_noise(r, lambda part: noise(q, part)),
                                   triangular=triangular)
        if probe.stationary:
            message = (f"Nelder-Mead stopped ({run.message}); stationary point"
                       f"{'' if round_ == 1 else f' after {round_ - 1} restart(s)'}: {probe.checked()}")
            return x, True, message, iterations, nfev, history, probe
        message = probe.reason()
        if not progressed and round_ > 1:
            stalled += 1
            if stalled == 2:
                message += f"; Nelder-Mead restarted there makes no progress ({run.message})"
                break
        else:
            stalled = 0
    else:
        message = (message + "; " if message else "") + f"{MAX_ROUNDS} Nelder-Mead restarts"
    return x, False, message, iterations or None, nfev, history, probe


def _finish(points, frame, x, converged, message, iterations, nfev, history, probe, scale_power):
    px, py, g, xc, yc = x
    why = degenerate_reason(abs(px), abs(py))
    if why is not None:
        converged, message = False, f"{why} ({message})"
    p = frame.params_to_data([xc, yc, px, py, g])
    if not np.isfinite(p).all() or min(abs(p[2]), abs(p[3])) == 0:
        return failed(points, f"{message}; the ellipse is not representable in data units "
                              f"(parameters {p.tolist()})", iterations=iterations, nfev=nfev)
    extra = {"paper_parameters": {"p_x": float(p[2]), "p_y": float(p[3]), "gamma": float(p[4]),
                                  "x_C": float(p[0]), "y_C": float(p[1])}}
    if probe is not None:
        extra["stationarity"] = probe.as_dict()
    if why is not None:
        extra["degenerate"] = why
    hist = history_to_data(history, frame.scale, scale_power)
    if hist is None:
        hist, extra["history_units"] = history, f"unit frame (the data-unit values, length^{scale_power}, overflow)"
    return ellipse_result(points, p, converged=converged, message=message, iterations=iterations, nfev=nfev,
                          history=hist, extra=extra, residuals=residuals_from_unit(frame, [xc, yc, abs(px), abs(py), g]))


def _algebraic_model(x, y):
    """Residuals e_i of eq. 15, their Jacobian in (p_x, p_y, gamma, x_C, y_C), and the size of their terms."""
    def residuals(q, part=slice(None)):
        px, py, g, xc, yc = q
        u, v = to_local(x[part], y[part], (xc, yc, px, py, g))
        # py py u u + px px v v - px px py py in place, the same operations in the same order: three arrays of N
        e = u * (py * py)
        e *= u
        np.multiply(v, px * px, out=u)
        u *= v
        e += u
        e -= px * px * py * py
        return e

    def jacobian(q, part=slice(None)):
        px, py, g, xc, yc = q
        c, s = np.cos(g), np.sin(g)
        u, v = to_local(x[part], y[part], (xc, yc, px, py, g))
        J = np.empty((len(u), 5))
        J[:, 0] = 2 * px * (v * v - py * py)
        J[:, 1] = 2 * py * (u * u - px * px)
        J[:, 2] = 2 * u * v * (py * py - px * px)
        J[:, 3] = -2 * py * py * u * c + 2 * px * px * v * s
        J[:, 4] = -2 * py * py * u * s - 2 * px * px * v * c
        return J

    def term_size(q, part=slice(None)):
        px, py, g, xc, yc = q
        u, v = to_local(x[part], y[part], (xc, yc, px, py, g))
        reach = np.abs(x[part]) + np.abs(y[part]) + abs(xc) + abs(yc)
        return py * py * u * u + px * px * v * v + px * px * py * py + 2 * (py * py * np.abs(u) + px * px * np.abs(v)) * reach

    return residuals, jacobian, term_size


def _geometric_model(x, y):
    """Orthogonal distances d_i, their Jacobian in (p_x, p_y, gamma, x_C, y_C), and the size of their terms."""
    def residuals(q, part=slice(None)):
        px, py, g, xc, yc = q
        if not (px > 0 and py > 0):
            return np.full(len(x[part]), np.inf)
        return orthogonal_residuals(x[part], y[part], (xc, yc, px, py, g), with_phi=False)[0]

    def jacobian(q, part=slice(None)):
        px, py, g, xc, yc = q
        p = (xc, yc, px, py, g)
        _, phi = orthogonal_residuals(x[part], y[part], p)
        return distance_jacobian(x[part], y[part], p, phi)[:, [2, 3, 4, 0, 1]]

    def term_size(q, part=slice(None)):
        px, py, g, xc, yc = q
        return np.abs(x[part]) + np.abs(y[part]) + abs(xc) + abs(yc) + max(abs(px), abs(py))

    return residuals, jacobian, term_size


def _fit(points, model, name, scale_power, backend, start, step, xatol, fatol, max_fev):
    frame, x0, lam, max_fev = _setup(points, name, backend, start, step, xatol, fatol, max_fev)
    residuals, jacobian, term_size = model(frame.x, frame.y)

    def objective(q):
        r = residuals(q)
        return dot(r, r) if np.isfinite(r).all() else np.inf   # not BLAS: the same bits on every CPU

    out = _minimise(objective, residuals, jacobian, term_size, x0, lam, n=len(frame.x), backend=backend, xatol=xatol,
                    fatol=fatol, max_fev=max_fev)
    return _finish(points, frame, *out, scale_power)


@register("ellipse.algebraic_nm", kind="iterative",
          summary="FEA: algebraic distances of eq. 15 (frame O', eq. 14) summed (eq. 16), minimised by Nelder–Mead",
          reference="Glavonjić, circle/ellipse paper, eq. 14-16 (program FEA, table 3)")
def algebraic_nm(points, *, backend="scipy", start=None, step=None, xatol=None, fatol=None, max_fev=50000):
    """Minimise S_EA = sum e_i^2, e_i = p_y^2 x_i'^2 + p_x^2 y_i'^2 - p_x^2 p_y^2 (eq. 15-16) with
    (x_i', y_i') the points in the ellipse frame (eq. 14), over p = (p_x, p_y, gamma, x_C, y_C).
    Simplex from ``start`` = s1S (table 3: (299, 299, 0, 0, 0)) and ``step`` = lambda, data units
    (gamma in radians); default start: Kåsa's circle. ``backend`` scipy or nlopt. S_EA is 0 at
    p_x = p_y = 0: a run that follows it there is reported as degenerate. Stopping and the converged
    test: module docstring (``xatol`` unit frame, ``fatol`` unit frame^8, None = rounding level)."""
    return _fit(points, _algebraic_model, "ellipse.algebraic_nm", 8, backend, start, step, xatol, fatol, max_fev)


@register("ellipse.geometric_nm", kind="iterative",
          summary="FEG: geometric (orthogonal) distances, closest points by eq. 10 and 21, minimised by Nelder–Mead",
          reference="Glavonjić, circle/ellipse paper, eq. 10, 17-22 (program FEG, table 4)")
def geometric_nm(points, *, backend="scipy", start=None, step=None, xatol=None, fatol=None, max_fev=50000):
    """Minimise S_EG = sum d_i^2 over p = (p_x, p_y, gamma, x_C, y_C), d_i the distance from each point
    to its closest point on the ellipse (the solution of eq. 10 and 21, solved for all points at once
    by :func:`~methods.ellipse._geometry.closest_points`). Simplex as in ellipse.algebraic_nm (table 4
    uses the same s1S as table 3); stopping and the converged test as there (``fatol`` unit frame^2)."""
    return _fit(points, _geometric_model, "ellipse.geometric_nm", 2, backend, start, step, xatol, fatol, max_fev)
