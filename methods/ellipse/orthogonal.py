"""Orthogonal-distance (geometric) least-squares ellipse fit."""
from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from methods._registry import register
from methods._validation import check_positive, check_vector
from methods.ellipse._geometry import Frame, canonical, orthogonal_residuals
from methods.ellipse._result import ellipse_result, failed
from methods.ellipse.direct import halir_flusser


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
    points of all points at once. Start: ``start`` = (xc, yc, a, b, theta) in data units, default
    Halir & Flusser's direct fit. In the unit frame; tolerances are MINPACK's."""
    name = "ellipse.orthogonal"
    for key, val in (("xtol", xtol), ("ftol", ftol), ("gtol", gtol)):
        check_positive(key, val, name)
    max_nfev = int(check_positive("max_nfev", max_nfev, name))
    p_start = check_vector("start", start, 5, name)
    frame = Frame.of(points)
    x, y = frame.x, frame.y
    if p_start is None:
        direct = halir_flusser(points)
        if not direct.converged:
            return failed(points, f"no start: the direct fit failed ({direct.message}); pass start=")
        p_start = np.array([*direct.center, *direct.semi_axes, direct.angle])
    p0 = frame.params_to_unit(p_start)
    history = []
    cache = {}

    def fun(p):
        d, phi = orthogonal_residuals(x, y, p)
        cache["p"], cache["phi"] = p.copy(), phi
        return d

    def jac(p):
        if "p" not in cache or not np.array_equal(cache["p"], p):
            fun(p)
        d, _ = orthogonal_residuals(x, y, p, with_phi=False)
        history.append(float(d @ d))
        return distance_jacobian(x, y, p, cache["phi"])

    eps = np.finfo(float).eps
    res = least_squares(fun, p0, jac=jac, method="lm", xtol=max(xtol, eps), ftol=max(ftol, eps),
                        gtol=max(gtol, eps), max_nfev=max_nfev, x_scale="jac")
    p = canonical(frame.params_to_data(res.x))
    return ellipse_result(points, p, converged=res.status > 0 and np.isfinite(res.x).all(), message=res.message,
                          iterations=int(res.njev or 0), nfev=int(res.nfev),
                          history=[h * frame.scale ** 2 for h in history], extra={"status": int(res.status)})
