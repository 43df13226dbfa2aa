"""Building ellipse results: residuals, form error, conic and the paper's angle solutions."""
from __future__ import annotations

import numpy as np

from methods._result import EllipseFit
from methods.ellipse._geometry import canonical, orthogonal_residuals, paper_gamma_solutions, params_to_conic


def ellipse_result(points, params, *, converged: bool, message: str, iterations=None, nfev=None,
                   history=None, extra=None) -> EllipseFit:
    """An :class:`EllipseFit` from (xc, yc, a, b, theta) in data units; residuals are the signed
    orthogonal distances of every point (closest points solved in the ellipse's frame)."""
    p = canonical(params)
    if not (np.isfinite(p).all() and p[3] > 0):
        return failed(points, f"no valid ellipse: parameters {p.tolist()}")
    d, _ = orthogonal_residuals(points[:, 0], points[:, 1], p, with_phi=False)
    conic = params_to_conic(p)
    extra = {**(extra or {}), "paper_gamma_solutions": paper_gamma_solutions(conic)}
    return EllipseFit(center=(float(p[0]), float(p[1])), semi_axes=(float(p[2]), float(p[3])), angle=float(p[4]),
                      conic=tuple(float(c) for c in conic), form_error=float(d.max() - d.min()), residuals=d,
                      converged=bool(converged), iterations=iterations, nfev=nfev, history=list(history or []),
                      message=message, extra=extra)


def failed(points, message: str, **kw) -> EllipseFit:
    nan = float("nan")
    return EllipseFit(center=(nan, nan), semi_axes=(nan, nan), angle=nan, conic=(nan,) * 6, form_error=nan,
                      residuals=np.full(len(points), nan), converged=False, message=message, **kw)
