"""Ellipse results: :class:`EllipseFit`, its builder (residuals, form error, conic and the paper's angle
solutions from (xc, yc, a, b, theta)) and the row columns it declares (centre, semi-axes, angle and their errors
against the truth; :mod:`methods.result_base`)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from methods.ellipse._geometry import canonical, orthogonal_residuals, paper_gamma_solutions, params_to_conic
from methods.result_base import (CENTER_COLUMNS, CENTER_ERROR_COLUMNS, FitResult, center_errors, error_columns,
                                 geometry_columns, number_text)

__all__ = ["EllipseFit", "ellipse_result"]


@dataclass(kw_only=True)
class EllipseFit(FitResult):
    """A fitted ellipse. ``semi_axes`` = (a, b) with a >= b; ``angle`` = direction of the a axis in
    radians, in [0, pi); ``conic`` = (A, B, C, D, E, F) of A x^2 + B xy + C y^2 + D x + E y + F = 0,
    normalised to 4AC - B^2 = 1 with A + C > 0; ``residuals`` = signed orthogonal distances
    (positive outside); ``form_error`` = max - min of them."""

    center: tuple
    semi_axes: tuple
    angle: float
    conic: tuple

    FAMILY = "ellipse"
    COLUMNS = (*FitResult.COLUMNS, *CENTER_COLUMNS, *geometry_columns("semi_axis_a", "semi_axis_b", check="positive"),
               *geometry_columns("angle", quantity="angle"), *CENTER_ERROR_COLUMNS,
               *error_columns("semi_axis_a_error", "semi_axis_b_error"),
               *error_columns("angle_error", quantity="angle"))
    SHAPES = {"center": (2,), "semi_axes": (2,), "conic": (6,), "residuals": ("n",)}

    def geometry(self) -> dict:
        return {"center_x": self.center[0], "center_y": self.center[1], "semi_axis_a": self.semi_axes[0],
                "semi_axis_b": self.semi_axes[1], "angle": self.angle}

    def truth_errors(self, truth: dict) -> dict:
        out = center_errors(self.center, truth)
        if "semi_axes" in truth:
            out["semi_axis_a_error"] = self.semi_axes[0] - truth["semi_axes"][0]
            out["semi_axis_b_error"] = self.semi_axes[1] - truth["semi_axes"][1]
            out["angle_error"] = float((self.angle - truth["angle"] + np.pi / 2) % np.pi - np.pi / 2)
        return out

    def report_lines(self, unit: str = "mm") -> list[tuple[str, str]]:
        a, b = number_text(self.semi_axes[0]), number_text(self.semi_axes[1])
        return [("center x", f"{number_text(self.center[0])} {unit}"),
                ("center y", f"{number_text(self.center[1])} {unit}"),
                ("semi-axes", f"a = {a} {unit}, b = {b} {unit}"),
                ("angle", f"{number_text(self.angle)} rad ({number_text(math.degrees(self.angle))}°, direction of a)")]

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        head = {k: d.pop(k) for k in ("method", "center", "semi_axes", "angle", "conic", "form_error")}
        return {**head, **d}

    @staticmethod
    def consistency(result: "EllipseFit", points: np.ndarray) -> str | None:
        """A converged ellipse keeps its declared form (a >= b, angle in [0, pi)), and its residuals and form error
        are those of its points about it: the signed orthogonal distances, solved again from the data about the
        returned ellipse by the family's closest-point solver (:func:`methods.ellipse._geometry.orthogonal_residuals`),
        and their span.

        Tolerance, per point: 1e-9 (a + max|r|) + 1e-6 span (the circles' gate and :data:`GEOMETRY`) + 64 eps
        (|xc| + |yc|). The solver gives each distance to rounding (Newton on Eberly's root function to a relative step
        of 1e-8, then one more step: quadratic, so ~1 ulp; bisection to adjacent floats where Newton is slow), i.e. a
        few ulps of a + |r|; a built-in method solves in its unit frame (:func:`residuals_from_unit`) about the ellipse
        before it is rounded to data units, the gate in data units about the rounded one: they differ by the rounding
        of the centre and of the coordinates (measured: at most 2.4 ulps of a, or 1 ulp of a + |centre|, for every
        built-in method from 1e-150 to 1e300 and for a 2-um ellipse 1e9 from the origin), which the last term bounds
        when the centre is far from the origin in units of a. ~30 ns per point (compiled kernel)."""
        a, b = float(result.semi_axes[0]), float(result.semi_axes[1])
        if not a >= b:
            return f"semi_axes = ({a:.10g}, {b:.10g}): a must be >= b"
        if not 0.0 <= float(result.angle) < math.pi:
            return f"angle = {float(result.angle):.10g} rad must lie in [0, pi)"
        d = result.residuals
        if not d.size:
            return None
        span = float(d.max() - d.min())
        if not abs(float(result.form_error) - span) <= 1e-9 * (a + span) + 1e-6 * span:
            return f"form_error = {float(result.form_error):.10g} but its residuals span {span:.10g}"
        xc, yc = float(result.center[0]), float(result.center[1])
        if points.dtype != _FLOAT64:
            points = points.astype(np.float64)
        with np.errstate(all="ignore"):  # a distance the solver cannot represent is told below, not warned
            solved, _ = orthogonal_residuals(points[:, 0], points[:, 1], (xc, yc, a, b, float(result.angle)),
                                             with_phi=False)
            if solved.shape != d.shape:
                return None  # the shape check told it
            if d.dtype == _FLOAT64 and d.tobytes() == solved.tobytes() and np.isfinite(span):
                return None  # the very numbers (ellipse_result solving in data units)
            worst = float(np.max(np.abs(d - solved)))
            tol = 1e-9 * (a + float(np.max(np.abs(solved)))) + 1e-6 * span + 64 * _EPS * (abs(xc) + abs(yc))
        if not worst <= tol:
            i = int(np.argmax(np.abs(d - solved)))
            return (f"residuals are not the orthogonal distances of the points to the returned ellipse (point {i}: "
                    f"{float(d[i]):.10g}, solved from the data {float(solved[i]):.10g}; tolerance {tol:.3g})")
        return None


_FLOAT64 = np.dtype(np.float64)
_EPS = float(np.finfo(float).eps)


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
    when the method already has them for this ellipse.

    As :func:`methods.circle.results.circle_result`: a converged claim about a NaN centre, semi-axis or angle is
    kept, so the result gate refuses it (an ``invalid`` row: NaN is no answer); an ellipse that is infinite
    without NaN or has a zero semi-axis (a finite fit over- or underflowing float64 in data units) is downgraded to
    not converged, with that reason and the method's own message."""
    p = canonical(params)
    if not (np.isfinite(p).all() and p[3] > 0):
        if converged and np.isnan(p).any():
            return _nan_claim(points, p, message=message, iterations=iterations, nfev=nfev, history=history,
                              extra=extra, residuals=residuals)
        why = (f"the ellipse is not representable in float64 (centre ({p[0]:.6g}, {p[1]:.6g}), semi-axes "
               f"({p[2]:.6g}, {p[3]:.6g}), angle {p[4]:.6g} rad: a fit over- or underflowing float64 in data units)"
               if not np.isnan(p).any() else f"no valid ellipse: parameters {p.tolist()}")
        if converged:
            why += ", so no fit is claimed"
        return failed(points, f"{why}; the method said: {message}" if message else why,
                      iterations=iterations, nfev=nfev)
    if residuals is None:
        residuals, _ = orthogonal_residuals(points[:, 0], points[:, 1], p, with_phi=False)
    d = residuals
    conic, conic_extra = _conic(p)
    extra = {**(extra or {}), **conic_extra}
    if converged and (note := angle_note(p[2] - p[3], d)) is not None:
        extra["notes"] = [*extra.get("notes", []), note]
    return EllipseFit(center=(float(p[0]), float(p[1])), semi_axes=(float(p[2]), float(p[3])), angle=float(p[4]),
                      conic=tuple(float(c) for c in conic), form_error=float(d.max() - d.min()), residuals=d,
                      converged=bool(converged), iterations=iterations, nfev=nfev, history=list(history or []),
                      message=message, extra=extra)


#: the first-order standard uncertainty of the angle (deg) from which a fit notes that its angle is ill-determined
ANGLE_NOTE_DEG = 10.0


def angle_note(a_minus_b: float, residuals) -> str | None:
    """A note when the angle of the a axis is ill-determined: its first-order standard uncertainty
    u = RMS / ((a - b) sqrt(N/2)) rad (docs/methods.md, the ellipse_angle study: residual RMS as the noise, N points
    around the ellipse; larger on a partial arc) is ``ANGLE_NOTE_DEG`` or more, as for a circle whose a - b is below
    its residual RMS, or a = b. None otherwise (scale-free: no overflow for data near the float range's ends)."""
    d = np.asarray(residuals, float)
    if not d.size or not np.isfinite(d).all() or not a_minus_b >= 0:
        return None
    if a_minus_b == 0:
        return "the angle is undetermined: a = b, any direction of a describes this ellipse"
    m = float(np.max(np.abs(d)))
    rms = m * float(np.sqrt(np.mean((d / m) ** 2))) if m > 0 else 0.0
    ratio = a_minus_b / rms if rms > 0 else math.inf     # a - b in residual RMS
    u = math.degrees(1.0 / (ratio * math.sqrt(d.size / 2)))
    if not u >= ANGLE_NOTE_DEG:
        return None
    return (f"the angle is {'undetermined' if u >= 3 * ANGLE_NOTE_DEG else 'ill-determined'}: a - b is {ratio:.2g} x "
            f"the residual RMS over {d.size} points, a first-order standard uncertainty of {u:.2g}° "
            "(RMS / ((a - b) sqrt(N/2)) rad)" + ("; the points fit a circle within their scatter" if ratio < 1 else ""))


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


def _nan_claim(points, p, *, message, iterations, nfev, history, extra, residuals) -> EllipseFit:
    """A converged claim about an ellipse with NaN parameters, kept as it was made (the gate refuses it)."""
    nan = float("nan")
    d = np.full(len(points), nan) if residuals is None else residuals
    return EllipseFit(center=(float(p[0]), float(p[1])), semi_axes=(float(p[2]), float(p[3])), angle=float(p[4]),
                      conic=(nan,) * 6, form_error=nan, residuals=d, converged=True, iterations=iterations,
                      nfev=nfev, history=list(history or []), message=message, extra=dict(extra or {}))


def failed(points, message: str, **kw) -> EllipseFit:
    nan = float("nan")
    return EllipseFit(center=(nan, nan), semi_axes=(nan, nan), angle=nan, conic=(nan,) * 6, form_error=nan,
                      residuals=np.full(len(points), nan), converged=False, message=message, **kw)
