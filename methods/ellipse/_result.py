"""Building ellipse results: residuals, form error, conic and the paper's angle solutions."""
from __future__ import annotations

import numpy as np

from methods._result import EllipseFit
from methods.ellipse._geometry import canonical, orthogonal_residuals, paper_gamma_solutions, params_to_conic


def _conic(p):
    """The data-unit conic and the paper's eq. 23-25 values, or NaN with the reason when the coefficients are
    not representable in float64 (e.g. 1/a^2 underflows for semi-axes near 1e150 and beyond)."""
    with np.errstate(all="ignore"):
        try:
            conic = params_to_conic(p)
        except ValueError:
            conic = None
        if conic is not None and np.isfinite(conic).all():
            return conic, {"paper_gamma_solutions": paper_gamma_solutions(conic)}
    return np.full(6, np.nan), {"conic": "not representable in float64 at this scale (coefficients over- or underflow); "
                                         "use center, semi_axes and angle"}


def ellipse_result(points, params, *, converged: bool, message: str, iterations=None, nfev=None,
                   history=None, extra=None, residuals=None) -> EllipseFit:
    """An :class:`EllipseFit` from (xc, yc, a, b, theta) in data units; residuals are the signed
    orthogonal distances of every point (closest points solved in the ellipse's frame), or ``residuals``
    when the method already has them for this ellipse."""
    p = canonical(params)
    if not (np.isfinite(p).all() and p[3] > 0):
        return failed(points, f"no valid ellipse: parameters {p.tolist()}", iterations=iterations, nfev=nfev)
    if residuals is None:
        residuals, _ = orthogonal_residuals(points[:, 0], points[:, 1], p, with_phi=False)
    d = residuals
    conic, conic_extra = _conic(p)
    extra = {**(extra or {}), **conic_extra}
    return EllipseFit(center=(float(p[0]), float(p[1])), semi_axes=(float(p[2]), float(p[3])), angle=float(p[4]),
                      conic=tuple(float(c) for c in conic), form_error=float(d.max() - d.min()), residuals=d,
                      converged=bool(converged), iterations=iterations, nfev=nfev, history=list(history or []),
                      message=message, extra=extra)


def residuals_from_unit(frame, p_unit) -> np.ndarray:
    """Signed orthogonal distances in data units, solved once in the unit frame (no overflow or underflow
    at any scale; the unit-frame coordinates carry no more rounding than the data's)."""
    d, _ = orthogonal_residuals(frame.x, frame.y, p_unit, with_phi=False)
    d *= frame.scale
    return d


def history_to_data(history, scale: float, power: int):
    """Objective values (unit frame) in data units (length^power), or None when scale^power over- or
    underflows (the history then stays in the unit frame and the result says so)."""
    with np.errstate(over="ignore", under="ignore"):
        factor = np.float64(scale) ** power
    if not (np.isfinite(factor) and factor > 0):
        return None
    return [float(h * factor) for h in history]


def failed(points, message: str, **kw) -> EllipseFit:
    nan = float("nan")
    return EllipseFit(center=(nan, nan), semi_axes=(nan, nan), angle=nan, conic=(nan,) * 6, form_error=nan,
                      residuals=np.full(len(points), nan), converged=False, message=message, **kw)
