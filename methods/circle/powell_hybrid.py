"""Program FCA of the circle/ellipse paper: Powell's hybrid method on the normal equations (6)."""
from __future__ import annotations

import numpy as np

from methods._frame import dot

from methods._registry import register
from methods.circle.results import circle_result
from methods._validation import check_positive, check_vector
from methods.circle import _stationarity as stationarity
from methods.circle._frame import Frame

EPS = np.finfo(float).eps


def three_point_start(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Circle through the points at positions 0, N/3, 2N/3 (unit frame); (0, 0, 1) if collinear."""
    n = len(x)
    i, j, k = 0, n // 3, (2 * n) // 3
    bx, by, cx, cy = x[j] - x[i], y[j] - y[i], x[k] - x[i], y[k] - y[i]
    d = 2.0 * (bx * cy - by * cx)
    if abs(d) <= 1e-12 * (bx * bx + by * by + cx * cx + cy * cy):
        return np.array([0.0, 0.0, 1.0])
    b2, c2 = bx * bx + by * by, cx * cx + cy * cy
    ux, uy = (cy * b2 - by * c2) / d, (bx * c2 - cx * b2) / d
    return np.array([x[i] + ux, y[i] + uy, np.hypot(ux, uy)])


@register("circle.powell_hybrid", kind="iterative",
          summary="FCA: grad S_CA = 0 (eq. 6) by MINPACK's Powell hybrid with analytic Jacobian (eq. 7)",
          reference="Glavonjić, circle/ellipse paper, eq. 5-7 (program FCA, table 1); Powell (1970), MINPACK hybrj")
def powell_hybrid(points, *, start=None, xtol=1e-12, maxfev=2000):
    """Solve f1 = dS/dxc = 0, f2 = dS/dyc = 0, f3 = dS/dR = 0 (eq. 6) for the algebraic objective
    S_CA = sum e_i^2, e_i = (x_i - xc)^2 + (y_i - yc)^2 - R^2 (eq. 4-5), with MINPACK's modified
    Powell hybrid method (hybrj, the algorithm of the IMSL routine neqnj the paper used) and the
    analytic Jacobian [J] of eq. 7 (the Hessian of S_CA).

    ``start`` is the initial estimate p_s = (xc, yc, R) in data units (table 1: (0, 0, 299));
    default: the circle through the points at positions 0, N/3 and 2N/3 of the data (three spread
    points, the start of Cordero-Dávila & Cornejo, ref. 8 of the roundness paper); the centroid with
    the RMS distance from it when those three are collinear. ``xtol`` is the paper's epsilon: relative
    error between successive iterates (table 1: 1e-8). ``iterations`` = function evaluations - 1
    (hybrj evaluates the function once per iteration).
    """
    name = "circle.powell_hybrid"
    check_positive("xtol", xtol, name)
    maxfev = int(check_positive("maxfev", maxfev, name))
    p_start = check_vector("start", start, 3, name)
    frame = Frame.of(points)
    x, y = frame.x, frame.y
    n = len(x)
    p0 = three_point_start(x, y) if p_start is None else frame.circle_to_unit(p_start)
    history = []

    def equations(p):
        a, b, rr = p
        du, dv = x - a, y - b
        e = du * du  # du du + dv dv - R^2 in place (the same operations; peak memory)
        t = dv * dv
        e += t
        del t
        e -= rr * rr
        history.append(dot(e, e))
        se, su, sv = e.sum(), du.sum(), dv.sum()
        f = -4.0 * np.array([dot(e, du), dot(e, dv), rr * se])
        jac = np.array([
            [4.0 * (2.0 * dot(du, du) + se), 8.0 * dot(du, dv), 8.0 * rr * su],
            [8.0 * dot(du, dv), 4.0 * (2.0 * dot(dv, dv) + se), 8.0 * rr * sv],
            [8.0 * rr * su, 8.0 * rr * sv, -4.0 * se + 8.0 * rr * rr * n],
        ])
        return f, jac

    with np.errstate(over="ignore", invalid="ignore"):
        from scipy.optimize import root  # imported on first use (light import)

        sol = root(equations, p0, jac=True, method="hybr", options={"xtol": xtol, "maxfev": maxfev})
    minpack = "MINPACK: " + " ".join(str(sol.message).split())
    # MINPACK's own stop (status 1: xtol met; 3: xtol too small; 4, 5: no progress, which on exact data
    # happens at the root itself) is necessary; the flag then needs the point to be a non-degenerate
    # stationary point of S_CA (its R = 0 stationary point and a centre at infinity are refused).
    check = stationarity.algebraic(x, y, sol.x, frame.ulp)
    stopped = int(sol.status) in (1, 3, 4, 5)
    ok = stopped and check.ok
    message = f"{minpack}; {check.text}" if stopped or check.degenerate else minpack
    extra = {"njev": int(getattr(sol, "njev", 0) or 0), "residual_equations": [float(v) for v in sol.fun],
             "minpack_status": int(sol.status), **check.extra(frame.power(4))}
    center, radius = frame.circle_to_data(sol.x) if np.isfinite(sol.x).all() else ((np.nan, np.nan), np.nan)
    return circle_result(points, center, radius, converged=ok, message=message,
                         iterations=max(len(history) - 1, 0), nfev=len(history),
                         history=[h * frame.power(4) for h in history], extra=extra)
