"""Programs FEA and FEG of the circle/ellipse paper: algebraic and geometric ellipse fits by
Nelder–Mead, parameters p = (p_x, p_y, gamma, x_C, y_C) as in its tables 3 and 4."""
from __future__ import annotations

import numpy as np

from methods import _simplex as simplex
from methods._errors import InvalidInputError
from methods._registry import register
from methods._validation import check_choice, check_positive, check_vector
from methods.circle._frame import kasa_xy
from methods.ellipse._geometry import Frame, orthogonal_residuals, to_local
from methods.ellipse._result import ellipse_result

PAPER_ORDER = "(p_x, p_y, gamma, x_C, y_C)"


def _setup(points, name, backend, start, step, xatol, fatol, max_fev):
    check_choice("backend", backend, simplex.BACKENDS, name)
    check_positive("xatol", xatol, name)
    check_positive("fatol", fatol, name, allow_zero=True)
    max_fev = int(check_positive("max_fev", max_fev, name))
    s1 = check_vector("start", start, 5, name)
    lam = check_vector("step", step, 5, name)
    if lam is not None and np.any(lam == 0):
        raise InvalidInputError(f"{name}: every simplex step lambda_j must be non-zero, got {step!r}")
    frame = Frame.of(points)
    if s1 is None:  # a circle: Kåsa's, as p_x = p_y = R, gamma = 0 (the paper starts from a circle too)
        xc, yc, r = kasa_xy(frame.x, frame.y)
        x0 = np.array([r, r, 0.0, xc, yc]) if np.isfinite(r) else np.array([1.0, 1.0, 0.0, 0.0, 0.0])
    else:
        px, py, g, xc, yc = s1
        x0 = np.array([px / frame.scale, py / frame.scale, g, (xc - frame.shift[0]) / frame.scale,
                       (yc - frame.shift[1]) / frame.scale])
    if lam is None:
        lam_unit = np.array([1e-3, 1e-3, 1e-2, 1e-3, 1e-3])
    else:
        lam_unit = np.array([lam[0] / frame.scale, lam[1] / frame.scale, lam[2], lam[3] / frame.scale,
                             lam[4] / frame.scale])
    return frame, x0, lam_unit, max_fev


def _finish(points, frame, run, scale_power):
    px, py, g, xc, yc = run.x
    p = frame.params_to_data([xc, yc, px, py, g])
    return ellipse_result(points, p, converged=run.converged, message=run.message, iterations=run.iterations,
                          nfev=run.nfev, history=[h * frame.scale ** scale_power for h in run.history],
                          extra={"paper_parameters": {"p_x": float(p[2]), "p_y": float(p[3]), "gamma": float(p[4]),
                                                      "x_C": float(p[0]), "y_C": float(p[1])}})


@register("ellipse.algebraic_nm", kind="iterative",
          summary="FEA: algebraic distances of eq. 15 (frame O', eq. 14) summed (eq. 16), minimised by Nelder–Mead",
          reference="Glavonjić, circle/ellipse paper, eq. 14-16 (program FEA, table 3)")
def algebraic_nm(points, *, backend="scipy", start=None, step=None, xatol=1e-10, fatol=1e-20, max_fev=50000):
    """Minimise S_EA = sum e_i^2, e_i = p_y^2 x_i'^2 + p_x^2 y_i'^2 - p_x^2 p_y^2 (eq. 15-16) with
    (x_i', y_i') the points in the ellipse frame (eq. 14), over p = (p_x, p_y, gamma, x_C, y_C).
    Simplex from ``start`` = s1S (table 3: (299, 299, 0, 0, 0)) and ``step`` = lambda, data units
    (gamma in radians); default start: Kåsa's circle. ``backend`` scipy or nlopt."""
    frame, x0, lam, max_fev = _setup(points, "ellipse.algebraic_nm", backend, start, step, xatol, fatol, max_fev)
    x, y = frame.x, frame.y

    def objective(q):
        px, py, g, xc, yc = q
        u, v = to_local(x, y, (xc, yc, px, py, g))
        e = py * py * u * u + px * px * v * v - px * px * py * py
        return float(e @ e)

    run = simplex.nelder_mead(objective, x0, lam, backend=backend, xatol=xatol, fatol=fatol, max_fev=max_fev)
    return _finish(points, frame, run, 8)


@register("ellipse.geometric_nm", kind="iterative",
          summary="FEG: geometric (orthogonal) distances, closest points by eq. 10 and 21, minimised by Nelder–Mead",
          reference="Glavonjić, circle/ellipse paper, eq. 10, 17-22 (program FEG, table 4)")
def geometric_nm(points, *, backend="scipy", start=None, step=None, xatol=1e-10, fatol=1e-20, max_fev=50000):
    """Minimise S_EG = sum d_i^2 over p = (p_x, p_y, gamma, x_C, y_C), d_i the distance from each point
    to its closest point on the ellipse (the solution of eq. 10 and 21, solved for all points at once
    by :func:`~methods.ellipse._geometry.closest_points`). Simplex as in ellipse.algebraic_nm (table 4
    uses the same s1S as table 3)."""
    frame, x0, lam, max_fev = _setup(points, "ellipse.geometric_nm", backend, start, step, xatol, fatol, max_fev)
    x, y = frame.x, frame.y

    def objective(q):
        px, py, g, xc, yc = q
        if px <= 0 or py <= 0:
            return np.inf
        d, _ = orthogonal_residuals(x, y, (xc, yc, px, py, g), with_phi=False)
        return float(d @ d)

    run = simplex.nelder_mead(objective, x0, lam, backend=backend, xatol=xatol, fatol=fatol, max_fev=max_fev)
    return _finish(points, frame, run, 2)
