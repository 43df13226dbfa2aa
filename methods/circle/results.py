"""Circle results: :class:`CircleFit` (a fitted circle) and :class:`ZoneFit` (a circle with the zone of its
points: minimum zone, MIC, MCC, Chebyshev), their builders and the row columns they declare (centre, radius, zone
radii, errors against the true centre and radius; :mod:`methods.result_base`)."""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from methods._frame import is_point_array, point_kernels
from methods.result_base import (CENTER_COLUMNS, CENTER_ERROR_COLUMNS, FitResult, center_errors, error_columns,
                                 geometry_columns, number_text, radial_distances)

__all__ = ["CircleFit", "ZoneFit", "circle_result", "zone_result"]


@dataclass(kw_only=True)
class CircleFit(FitResult):
    """A fitted circle. ``residuals`` are signed radial deviations r_i - R; ``form_error`` is
    max(r_i) - min(r_i) about ``center`` (the circularity about that centre)."""

    center: tuple
    radius: float

    FAMILY = "circle"
    COLUMNS = (*FitResult.COLUMNS, *CENTER_COLUMNS, *geometry_columns("radius", check="positive"),
               *CENTER_ERROR_COLUMNS, *error_columns("radius_error"))
    SHAPES = {"center": (2,), "residuals": ("n",)}

    def geometry(self) -> dict:
        return {"center_x": self.center[0], "center_y": self.center[1], "radius": self.radius}

    def truth_errors(self, truth: dict) -> dict:
        out = center_errors(self.center, truth)
        if "radius" in truth:
            out["radius_error"] = self.radius - truth["radius"]
        return out

    def report_lines(self, unit: str = "mm") -> list[tuple[str, str]]:
        return [("center x", f"{number_text(self.center[0])} {unit}"),
                ("center y", f"{number_text(self.center[1])} {unit}"),
                ("radius", f"{number_text(self.radius)} {unit}")]

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        # Put the geometry first: it is what a reader looks for.
        head = {k: d.pop(k) for k in ("method", "center", "radius", "form_error")}
        return {**head, **d}

    @staticmethod
    def consistency(result: "CircleFit", points: np.ndarray) -> str | None:
        """A converged circle's form error and residuals are those of its points about its centre and radius."""
        return _radial_problem(result, points)[0]


def _radial_problem(result: CircleFit, points: np.ndarray):
    """(what :meth:`CircleFit.consistency` finds wrong or None, min r_i, max r_i, the tolerance it applied): the radial
    distances r_i of the points about the returned centre, swept once (also for :meth:`ZoneFit.consistency`)."""
    radius = result.radius
    if type(radius) is not float:
        radius = float(radius)
    swept = _compiled_sweep(points, result.center, radius)  # r_i - R, min and max r_i in one pass
    if swept is None:
        with np.errstate(all="ignore"):
            r = np.hypot(points[:, 0] - result.center[0], points[:, 1] - result.center[1])
            deviations, r_min, r_max = r - radius, float(r.min()), float(r.max())
    else:  # finite r_i - R (the sweep returns None otherwise), computed without a NumPy operation
        deviations, r_min, r_max = swept
    span = r_max - r_min
    tol = 1e-9 * (r_max + abs(radius)) + 1e-6 * span
    form_error = result.form_error
    if type(form_error) is not float:
        form_error = float(form_error)
    if not abs(form_error - span) <= tol:
        return (f"form_error = {form_error:.10g} but the points' radial span about the "
                f"returned centre is {span:.10g}"), r_min, r_max, tol
    residuals = result.residuals
    if residuals.shape != deviations.shape:
        return None, r_min, r_max, tol
    if swept is not None and residuals.dtype == _FLOAT64 and residuals.tobytes() == deviations.tobytes():
        return None, r_min, r_max, tol  # the very numbers (as a builder computes them: the same sweep), finite
    with np.errstate(all="ignore"):
        if not (np.abs(residuals - deviations) <= tol).all():
            return "residuals are not the radial distances minus the radius about the returned centre", r_min, r_max, tol
    return None, r_min, r_max, tol


_FLOAT64 = np.dtype(np.float64)


def _compiled_sweep(points, center, radius: float):
    """(r_i - R, min r_i, max r_i) by the compiled sweep (``methods/circle/_ckernels.c`` ``radial``), or None
    where :func:`_compiled_residuals` would be (no kernel, other input, a distance outside (1e-145, 1e150))."""
    ck = point_kernels()
    if ck is None:
        return None
    if type(points) is np.ndarray and points.dtype is _FLOAT64:  # the validated data: only their layout to check
        if not (points.ndim == 2 and points.shape[1] == 2 and points.flags.c_contiguous):
            return None
    elif not is_point_array(points):
        return None
    m = points.shape[0]
    if not m:
        return None
    cx, cy = center[0], center[1]
    if type(cx) is not float:
        cx = float(cx)
    if type(cy) is not float:
        cy = float(cy)
    if not (math.isfinite(cx) and math.isfinite(cy) and math.isfinite(radius)):
        return None
    out = np.empty(m)
    r_min, r_max, _, outside = ck.radial(points, cx, cy, radius, out)
    return None if outside else (out, float(r_min), float(r_max))


def _compiled_residuals(points, center, radius: float):
    """(r_i - R, max r - min r) by one compiled sweep (``methods/circle/_ckernels.c`` ``radial``): the same
    operations as :func:`radial_distances` then ``r - radius``, hence the same bits; None on the NumPy
    path, for input the kernel does not take, or when a distance leaves (1e-145, 1e150) (np.hypot then)."""
    ck = point_kernels()
    if ck is None or not is_point_array(points):
        return None
    out = np.empty(points.shape[0])
    r_min, r_max, _, outside = ck.radial(points, center[0], center[1], radius, out)
    if outside or not out.size:
        return None
    return out, r_max - r_min


def circle_result(points: np.ndarray, center, radius: float, *, converged: bool, message: str,
                  iterations=None, nfev=None, history=None, extra=None) -> CircleFit:
    """Build a :class:`CircleFit`, computing residuals and form error from the data in data units.

    A converged claim about a circle that is infinite but not NaN (a finite circle beyond float64's range: what a
    fit of nearly straight points gives in data units) is downgraded to not converged, with the reason. A claim
    about a NaN centre or radius is kept: NaN is no answer, and the result gate refuses it (an ``invalid`` row)."""
    xc, yc, radius = float(center[0]), float(center[1]), float(radius)
    center = (xc, yc)
    ok_geometry = math.isfinite(xc) and math.isfinite(yc) and math.isfinite(radius)
    beyond_range = not ok_geometry and not (math.isnan(xc) or math.isnan(yc) or math.isnan(radius))
    residuals = _compiled_residuals(points, center, radius) if ok_geometry else None
    if residuals is not None:
        residuals, form_error = residuals
    else:
        with np.errstate(over="ignore", invalid="ignore"):  # a degenerate circle far away: NaN/inf, no warning
            r = radial_distances(points, center)
        with np.errstate(over="ignore", invalid="ignore"):
            form_error = float(r.max() - r.min()) if ok_geometry else float("nan")
        residuals = r - radius
    if converged and beyond_range:  # the downgrade says why (the method's own words follow)
        message = (f"the circle is not finite in float64 (centre ({xc:.6g}, {yc:.6g}), radius {radius:.6g}: e.g. points so "
                   f"nearly straight that their circle is beyond float64's range), so no fit is claimed; the method said: {message}")
    return CircleFit(center=center, radius=radius, form_error=form_error, residuals=residuals,
                     converged=bool(converged and not beyond_range), iterations=iterations, nfev=nfev,
                     history=list(history) if history else [], message=message,
                     extra=dict(extra) if extra else {})


@dataclass(kw_only=True)
class ZoneFit(CircleFit):
    """A circle with the zone of the points about its centre (minimum zone, MIC, MCC, Chebyshev).

    ``inner_radius``/``outer_radius`` are the smallest/largest radial distance about ``center``;
    ``form_error`` = outer - inner; ``contacts`` = {"outer": [...], "inner": [...]} are the indices
    of the points on the circles that determine (and certify) the solution."""

    inner_radius: float
    outer_radius: float
    contacts: dict

    COLUMNS = (*CircleFit.COLUMNS, *geometry_columns("inner_radius", "outer_radius", check="nonnegative"))

    def geometry(self) -> dict:
        return {**super().geometry(), "inner_radius": self.inner_radius, "outer_radius": self.outer_radius}

    def report_lines(self, unit: str = "mm") -> list[tuple[str, str]]:
        return [*super().report_lines(unit), ("inner radius", f"{number_text(self.inner_radius)} {unit}"),
                ("outer radius", f"{number_text(self.outer_radius)} {unit}"),
                ("contacts", f"outer {self.contacts['outer']}, inner {self.contacts['inner']} (point indices)")]

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        head = {k: d.pop(k) for k in ("method", "center", "radius", "inner_radius", "outer_radius",
                                      "form_error", "contacts")}
        return {**head, **d}

    @staticmethod
    def consistency(result: "ZoneFit", points: np.ndarray) -> str | None:
        """A converged zone is a circle's (:meth:`CircleFit.consistency`) whose ``inner_radius``/``outer_radius`` are
        the smallest/largest radial distance of the points about its centre and whose ``contacts`` name points at
        those radii (indices, as ``{"outer": [...], "inner": [...]}``), to the circle's tolerance (1e-9 of the radii
        + 1e-6 of the zone width: the zone methods' contacts tie to 1e-12 of the radius in their unit frame)."""
        problem, r_min, r_max, tol = _radial_problem(result, points)
        if problem:
            return problem
        for name, value, extreme, which in (("inner_radius", result.inner_radius, r_min, "smallest"),
                                            ("outer_radius", result.outer_radius, r_max, "largest")):
            value = float(value)
            if not abs(value - extreme) <= tol:
                return (f"{name} = {value:.10g} but the {which} radial distance of the points about the returned "
                        f"centre is {extreme:.10g}")
        return _contacts_problem(result, points, r_min, r_max, tol)


def _contacts_problem(result: ZoneFit, points: np.ndarray, r_min: float, r_max: float, tol: float) -> str | None:
    """What is wrong with a zone's ``contacts`` (None: each names a point at the zone's outer or inner radius). A zone
    has a few contacts (2 to 4 for the built-in methods): they are checked one by one, in Python floats."""
    contacts = result.contacts
    if not (isinstance(contacts, dict) and len(contacts) == 2 and "outer" in contacts and "inner" in contacts):
        return (f"contacts must be {{'outer': [...], 'inner': [...]}} (point indices), got "
                f"{type(contacts).__name__} {str(contacts)[:60]}")
    n = points.shape[0]
    cx, cy = float(result.center[0]), float(result.center[1])
    for side, extreme in (("outer", r_max), ("inner", r_min)):
        given = contacts[side]
        if not isinstance(given, (list, tuple)):
            return f"contacts['{side}'] must be a list of point indices, got {str(given)[:60]}"
        for i in given:
            if not (isinstance(i, (int, np.integer)) and not isinstance(i, (bool, np.bool_))):
                return f"contacts['{side}'] must be a list of point indices, got {str(given)[:60]}"
            if not 0 <= i < n:
                return f"contacts['{side}'] names point {int(i)}, not one of the {n} points"
            r = math.hypot(float(points[i, 0]) - cx, float(points[i, 1]) - cy)
            if not abs(r - extreme) <= tol:
                return (f"contacts['{side}'] names point {int(i)} at {r:.10g} from the returned centre, not at the "
                        f"{side} radius {extreme:.10g}")
    return None


def zone_result(points: np.ndarray, center, radius: float, contacts: dict, *, converged: bool, message: str,
                iterations=None, nfev=None, history=None, extra=None) -> ZoneFit:
    """Build a :class:`ZoneFit`; the zone radii come from all points about ``center`` (the final check)."""
    base = circle_result(points, center, radius, converged=converged, message=message, iterations=iterations,
                         nfev=nfev, history=history, extra=extra)
    r = base.residuals + base.radius
    ok = np.isfinite(r).all()
    return ZoneFit(**{f.name: getattr(base, f.name) for f in fields(base)},
                   inner_radius=float(r.min()) if ok else float("nan"),
                   outer_radius=float(r.max()) if ok else float("nan"),
                   contacts={k: [int(i) for i in v] for k, v in contacts.items()})
