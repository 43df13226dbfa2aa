"""Result objects: one shape for every method of a family (named fields, never bare tuples), the row
columns and verification tolerances each family declares, and the gate every result passes before it
becomes a row of the benchmark (:func:`check_result`).

This is the public module a method (built in or a plugin) builds its result with::

    from methods import register
    from methods.results import circle_result

A result class declares

* ``FAMILY``  -- the method family whose contract it is (``"circle"``: every circle method returns a
  :class:`CircleFit` or a subclass);
* ``COLUMNS`` -- the :class:`Column` s its rows have (name, quantity and unit, what a converged result
  must satisfy, the tolerance ``python -m experiments.verify`` allows on another CPU);
* ``SHAPES``  -- the shapes of its array-like fields (``"n"``: one entry per data point).

The engine, the summary and verify read these declarations (:func:`row_columns`, :func:`tolerances`,
:func:`truth_error_columns`); no list elsewhere names a family's columns.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, fields
from typing import NamedTuple

import numpy as np

from methods._frame import is_point_array, point_kernels


def _jsonable(value):
    """Convert numpy scalars/arrays and non-finite floats to plain JSON values (NaN/inf -> None)."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    return value


#: numpy scalars/arrays and non-finite floats as plain JSON values (NaN/inf -> None), for a result's ``to_dict``
jsonable = _jsonable


def _num(v) -> str:
    """A number as a person reads it: 10 significant digits, "nan" for a non-finite value."""
    if v is None:
        return "-"
    v = float(v)
    return f"{v:.10g}" if math.isfinite(v) else "nan"


def _center_errors(center, truth: dict) -> dict:
    """Signed components and distance of a fitted centre from the true one (none without a true centre)."""
    if "center" not in truth:
        return {}
    dx, dy = center[0] - truth["center"][0], center[1] - truth["center"][1]
    return {"center_error_x": dx, "center_error_y": dy, "center_error": float(np.hypot(dx, dy))}

# ---------------------------------------------------------------- column declarations


class Tolerance(NamedTuple):
    """How far a re-computed value may lie from the committed one: |new - old| <= atol + rtol * |old|
    (rtol = atol = 0: exact). ``why`` is the one-line justification from the method's resolution."""

    rtol: float
    atol: float
    why: str


EXACT = Tolerance(0.0, 0.0, "an identity, a status or a count of a deterministic method: must be identical")
#: Geometric fits stop at a step of <= 1e-12 (Gauss-Newton, LM, Powell hybrid; unit-frame coordinates) or are
#: closed forms / convex programs solved to 1e-9 relative gap; a different CPU changes the last bits of the BLAS
#: reductions (about 1e-16 relative per operation, amplified by the condition number, below 1e3 for the data sets
#: here), so 1e-9 relative leaves a margin of three decades over the observed differences.
GEOMETRY = Tolerance(1e-9, 1e-12, "fits converge to ~1e-12 relative in the unit frame; 1e-9 covers CPU rounding")
#: Errors against the truth are differences of two numbers of the data's size: their absolute resolution is that
#: of the fitted geometry (1e-9 relative of lengths of order 1 to 1e3 data units -> 1e-9 absolute for unit-sized
#: data, 1e-6 for the 1000-mm machine-tool data: atol 1e-9 with rtol 1e-6 on the error itself).
ERRORS = Tolerance(1e-6, 1e-9, "a difference of two fitted lengths: absolute resolution of the fit (1e-9 data units)")

#: quantity -> the unit a person reads: lengths are in the data's unit (mm for the machine-tool data)
UNITS = {"length": "mm", "angle": "rad", "count": "", "ratio": "", "time": "s"}


class Column(NamedTuple):
    """One row column a result class declares.

    ``quantity``: ``"length"`` (data units, mm for the machine-tool data), ``"angle"`` (rad), ``"count"``,
    ``"ratio"``; ``check``: what a converged result's value must be (``"finite"``, ``"positive"``,
    ``"nonnegative"``; ``""``: may be NaN, e.g. a figure a family does not define); ``truth_error``: an error
    against the truth whose bias and RMSE the summary reports."""

    name: str
    quantity: str
    tolerance: Tolerance | None
    check: str = "finite"
    truth_error: bool = False

    @property
    def unit(self) -> str:
        return UNITS.get(self.quantity, "")


def _geometry_columns(*names, check="finite", quantity="length"):
    return tuple(Column(n, quantity, GEOMETRY, check) for n in names)


def _error_columns(*names, quantity="length", summary=True):
    return tuple(Column(n, quantity, ERRORS, "", truth_error=summary) for n in names)


_CENTER = _geometry_columns("center_x", "center_y")
_CENTER_ERRORS = (*_error_columns("center_error_x", "center_error_y", summary=False), *_error_columns("center_error"))


@dataclass(kw_only=True)
class FitResult:
    """Fields shared by every method's result (cf. scipy's ``OptimizeResult``), and the one interface the
    engine, the metrics and the CLI read a result through (no family is recognised by its attributes):

    * :meth:`geometry` -- the fitted geometry as named row columns (lengths in data units, angles in rad);
    * :meth:`truth_errors` -- the errors of that geometry against a known truth;
    * :meth:`report_lines` -- (label, text with unit) lines the CLI prints for that geometry.

    ``form_error`` has one meaning per family (lengths in data units):

    ========================  ===============================================================================
    circle (least squares)    max r_i - min r_i about the fitted centre (circularity about that centre)
    circle zone (MZ, MIC,     outer - inner radius of the zone about the centre the criterion chose
    MCC, Chebyshev)
    ellipse                   max - min of the signed orthogonal distances to the fitted ellipse
    positioning (ISO 230-2)   not defined (NaN): the standard's figures A, E, M, R, B are in ``figures``
    ISO 230-4 circular test   G(b), the bidirectional circular deviation (G, H, F are in ``figures``)
    magnify                   the largest contouring error |p - r~| of the trajectory
    multilateration           the largest volumetric error magnitude |X_actual - X_nominal|
    roundness (ISO 12181)     RONt about the MZCI (else about the one reference circle evaluated)
    ========================  ===============================================================================

    ``residuals`` are defined per family (each class says how); ``history`` holds the objective per
    iteration of iterative methods in data units; ``extra`` holds method-specific diagnostics.
    """

    method: str = ""
    form_error: float = float("nan")
    residuals: np.ndarray = field(default_factory=lambda: np.empty(0))
    converged: bool
    iterations: int | None = None
    nfev: int | None = None
    history: list = field(default_factory=list)
    message: str = ""
    runtime_s: float = float("nan")
    params: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)

    #: the family whose contract this class is (None: a base class)
    FAMILY = None
    #: the row columns of a fit of this class (its geometry, errors against the truth, and these two)
    COLUMNS = (Column("form_error", "length", GEOMETRY, "nonnegative"),
               Column("residual_rms", "length", GEOMETRY, "nonnegative"))
    #: array-like fields and their shapes ("n": one entry per data point); checked by :func:`check_result`
    SHAPES = {}

    def geometry(self) -> dict:
        """The fitted geometry as row columns (none for a family without a fitted curve)."""
        return {}

    def truth_errors(self, truth: dict) -> dict:
        """Errors of :meth:`geometry` against ``truth`` (keys the family knows; others are ignored)."""
        return {}

    def report_lines(self, unit: str = "mm") -> list[tuple[str, str]]:
        """(label, text) lines of the fitted geometry for a person to read, every length in ``unit`` (the
        data's unit: the CLI converts every input to mm), angles in rad."""
        return []

    def to_dict(self, residuals: bool = True) -> dict:
        """The JSON-ready dict the CLI prints (``residuals=False`` leaves the per-point array out)."""
        out = {}
        for f in fields(self):
            if f.name == "residuals" and not residuals:
                continue
            out[f.name] = _jsonable(getattr(self, f.name))
        return out


@dataclass(kw_only=True)
class CircleFit(FitResult):
    """A fitted circle. ``residuals`` are signed radial deviations r_i - R; ``form_error`` is
    max(r_i) - min(r_i) about ``center`` (the circularity about that centre)."""

    center: tuple
    radius: float

    FAMILY = "circle"
    COLUMNS = (*FitResult.COLUMNS, *_CENTER, *_geometry_columns("radius", check="positive"), *_CENTER_ERRORS,
               *_error_columns("radius_error"))
    SHAPES = {"center": (2,), "residuals": ("n",)}

    def geometry(self) -> dict:
        return {"center_x": self.center[0], "center_y": self.center[1], "radius": self.radius}

    def truth_errors(self, truth: dict) -> dict:
        out = _center_errors(self.center, truth)
        if "radius" in truth:
            out["radius_error"] = self.radius - truth["radius"]
        return out

    def report_lines(self, unit: str = "mm") -> list[tuple[str, str]]:
        return [("center x", f"{_num(self.center[0])} {unit}"), ("center y", f"{_num(self.center[1])} {unit}"),
                ("radius", f"{_num(self.radius)} {unit}")]

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        # Put the geometry first: it is what a reader looks for.
        head = {k: d.pop(k) for k in ("method", "center", "radius", "form_error")}
        return {**head, **d}


def radial_distances(points: np.ndarray, center) -> np.ndarray:
    """Distances r_i of the points from ``center`` (vectorised); exact to rounding at any float64 scale
    (np.hypot, free of under/overflow, is used when a squared distance would leave the normal range)."""
    dx = points[:, 0] - center[0]
    dy = points[:, 1] - center[1]
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        r = dx * dx
        r += dy * dy
        np.sqrt(r, out=r)
    if r.size and not (1e-145 < r.min() and r.max() < 1e150):
        r = np.hypot(dx, dy)
    return r


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
    """Build a :class:`CircleFit`, computing residuals and form error from the data in data units."""
    xc, yc, radius = float(center[0]), float(center[1]), float(radius)
    center = (xc, yc)
    ok_geometry = math.isfinite(xc) and math.isfinite(yc) and math.isfinite(radius)
    residuals = _compiled_residuals(points, center, radius) if ok_geometry else None
    if residuals is not None:
        residuals, form_error = residuals
    else:
        with np.errstate(over="ignore", invalid="ignore"):  # a degenerate circle far away: NaN/inf, no warning
            r = radial_distances(points, center)
        with np.errstate(over="ignore", invalid="ignore"):
            form_error = float(r.max() - r.min()) if ok_geometry else float("nan")
        residuals = r - radius
    return CircleFit(center=center, radius=radius, form_error=form_error, residuals=residuals,
                     converged=bool(converged and ok_geometry), iterations=iterations, nfev=nfev,
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

    COLUMNS = (*CircleFit.COLUMNS, *_geometry_columns("inner_radius", "outer_radius", check="nonnegative"))

    def geometry(self) -> dict:
        return {**super().geometry(), "inner_radius": self.inner_radius, "outer_radius": self.outer_radius}

    def report_lines(self, unit: str = "mm") -> list[tuple[str, str]]:
        return [*super().report_lines(unit), ("inner radius", f"{_num(self.inner_radius)} {unit}"),
                ("outer radius", f"{_num(self.outer_radius)} {unit}"),
                ("contacts", f"outer {self.contacts['outer']}, inner {self.contacts['inner']} (point indices)")]

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        head = {k: d.pop(k) for k in ("method", "center", "radius", "inner_radius", "outer_radius",
                                      "form_error", "contacts")}
        return {**head, **d}


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
    COLUMNS = (*FitResult.COLUMNS, *_CENTER, *_geometry_columns("semi_axis_a", "semi_axis_b", check="positive"),
               *_geometry_columns("angle", quantity="angle"), *_CENTER_ERRORS,
               *_error_columns("semi_axis_a_error", "semi_axis_b_error"), *_error_columns("angle_error", quantity="angle"))
    SHAPES = {"center": (2,), "semi_axes": (2,), "conic": (6,), "residuals": ("n",)}

    def geometry(self) -> dict:
        return {"center_x": self.center[0], "center_y": self.center[1], "semi_axis_a": self.semi_axes[0],
                "semi_axis_b": self.semi_axes[1], "angle": self.angle}

    def truth_errors(self, truth: dict) -> dict:
        out = _center_errors(self.center, truth)
        if "semi_axes" in truth:
            out["semi_axis_a_error"] = self.semi_axes[0] - truth["semi_axes"][0]
            out["semi_axis_b_error"] = self.semi_axes[1] - truth["semi_axes"][1]
            out["angle_error"] = float((self.angle - truth["angle"] + np.pi / 2) % np.pi - np.pi / 2)
        return out

    def report_lines(self, unit: str = "mm") -> list[tuple[str, str]]:
        return [("center x", f"{_num(self.center[0])} {unit}"), ("center y", f"{_num(self.center[1])} {unit}"),
                ("semi-axes", f"a = {_num(self.semi_axes[0])} {unit}, b = {_num(self.semi_axes[1])} {unit}"),
                ("angle", f"{_num(self.angle)} rad ({_num(math.degrees(self.angle))}°, direction of a)")]

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        head = {k: d.pop(k) for k in ("method", "center", "semi_axes", "angle", "conic", "form_error")}
        return {**head, **d}


@dataclass(kw_only=True)
class PositioningFit(FitResult):
    """Positioning of an NC axis: ISO 230-2 ``figures`` (A, E, M, R, B, ...), ``per_target`` arrays,
    and, for the polynomial models, ``polynomial`` = {"up"/"down": {"coefficients" (increasing powers of
    the position, input unit), "covariance", "degree"}}. ``residuals`` = mean deviations minus the model."""

    figures: dict = field(default_factory=dict)
    per_target: dict = field(default_factory=dict)
    polynomial: dict = field(default_factory=dict)

    FAMILY = "positioning"
    #: ISO 230-2 defines no form error (NaN)
    COLUMNS = (Column("form_error", "length", GEOMETRY, ""), Column("residual_rms", "length", GEOMETRY, "nonnegative"))

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        figures = d.pop("figures")
        return {"method": d.pop("method"), **figures, **d}


@dataclass(kw_only=True)
class CircularTestFit(FitResult):
    """ISO 230-4 evaluation of a bidirectional circular test (:func:`methods.circular_test.evaluate`), lengths in
    data units: ``figures`` = {G_cw, G_ccw, G_b, H, F_max, F_min, mean_radial_deviation}; ``center`` is the
    centre G(b) is evaluated about (``center_kind`` 'lsq': least squares, 'mz': minimum zone), ``center_cw`` /
    ``center_ccw`` those of each run; ``residuals`` = the radial deviations of both runs (CW then CCW) from the
    nominal radius about ``F_center``; ``form_error`` = G(b), the bidirectional circular deviation."""

    #: the standard's figures, in the order they are reported
    FIGURES = ("G_cw", "G_ccw", "G_b", "H", "F_max", "F_min", "mean_radial_deviation")

    figures: dict
    center: tuple
    center_cw: tuple
    center_ccw: tuple
    center_kind: str
    F_center: tuple
    F_about: str
    H_about: str
    nominal_radius: float
    n_points: dict
    partial_arc: bool
    arc_deg: dict
    conditions: dict = field(default_factory=dict)

    FAMILY = "circular_test"
    COLUMNS = (*FitResult.COLUMNS, *_CENTER, *_CENTER_ERRORS)
    SHAPES = {"center": (2,)}

    def geometry(self) -> dict:
        return {"center_x": self.center[0], "center_y": self.center[1]}

    def truth_errors(self, truth: dict) -> dict:
        return _center_errors(self.center, truth)

    def report_lines(self, unit: str = "mm") -> list[tuple[str, str]]:
        f = self.figures
        common = " (over the common arc)" if self.partial_arc else ""
        return [("nominal radius", f"{_num(self.nominal_radius)} {unit}"),
                (f"centre ({self.center_kind})", f"({_num(self.center[0])}, {_num(self.center[1])}) {unit}"),
                ("G CW / CCW", f"{_num(f['G_cw'])} / {_num(f['G_ccw'])} {unit}"),
                ("G(b)", f"{_num(f['G_b'])} {unit}"),
                ("H (1996)", f"{_num(f['H'])} {unit}{common}"),
                ("F max / F min", f"{_num(f['F_max'])} / {_num(f['F_min'])} {unit} ({self.F_about})"),
                ("mean radial deviation", f"{_num(f['mean_radial_deviation'])} {unit}")]

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        figures = d.pop("figures")
        return {"method": d.pop("method"), **figures, "center": d.pop("center"), **d}


@dataclass(kw_only=True)
class MagnifyFit(FitResult):
    """A magnified contouring-error trajectory: ``points`` (one per measured point, in order),
    ``reference_points`` r~(k); ``residuals`` = contouring errors |p - r~|; ``form_error`` = the largest."""

    points: np.ndarray
    reference_points: np.ndarray

    FAMILY = "magnify"

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        return {"method": d.pop("method"), "points": d.pop("points"), **d}


@dataclass(kw_only=True)
class MultilaterationFit(FitResult):
    """Multilateration: ``stations`` (K, 4) = [x, y, z, L] per station in input order (given or located),
    ``points`` (N, 3) actual positions and ``volumetric_errors`` = points - nominal, one row per nominal point in
    order of first appearance; ``condition_numbers`` of every linear system solved (SVD and the paper's
    Theorem 1 lower estimate); ``residuals`` (N, K) = ||X_a,i - LT(k)|| - (L_k + P_i(k)) (NaN: not measured);
    ``form_error`` = the largest volumetric error magnitude. ``frame`` says which frame stations and points are
    in: ``"measurement"`` (that of the given stations or of the nominal points the stations were located
    from) or ``"nominal"`` (a solution defined up to a rigid motion, moved by the least-squares rigid motion
    that aligns its points with the nominal ones)."""

    station_ids: list
    stations: np.ndarray
    points: np.ndarray
    volumetric_errors: np.ndarray
    condition_numbers: dict = field(default_factory=dict)
    frame: str = "measurement"

    FAMILY = "multilateration"

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        head = {k: d.pop(k) for k in ("method", "station_ids", "stations", "points", "volumetric_errors",
                                      "condition_numbers")}
        return {**head, **d}


# ---------------------------------------------------------------- what the engine, summary and verify read


def result_classes() -> list[type]:
    """:class:`FitResult` and every subclass defined so far (the built-in ones, and those of loaded plugins),
    in definition order (parents before children)."""
    out, todo = [], [FitResult]
    while todo:
        cls = todo.pop(0)
        if cls not in out:
            out.append(cls)
            todo.extend(cls.__subclasses__())
    return out


def contract(family: str) -> type | None:
    """The result class a method of ``family`` must return (the most general class declaring that
    ``FAMILY``), or None for a family that declares none (any :class:`FitResult` then)."""
    for cls in result_classes():
        if cls.__dict__.get("FAMILY") == family:
            return cls
    return None


def row_columns() -> dict[str, Column]:
    """Every row column a result class declares, by name (first declaration wins)."""
    out: dict[str, Column] = {}
    for cls in result_classes():
        for col in cls.COLUMNS:
            out.setdefault(col.name, col)
    return out


def truth_error_columns() -> tuple[str, ...]:
    """The errors against the truth whose bias and RMSE the summary reports, in declaration order."""
    return tuple(name for name, col in row_columns().items() if col.truth_error)


def tolerances() -> dict[str, Tolerance | None]:
    """The verification tolerance of every declared row column."""
    return {name: col.tolerance for name, col in row_columns().items()}


# ---------------------------------------------------------------- the gate before a result becomes a row


class InvalidResult(Exception):
    """A result that breaks its family's contract (raised by :func:`check_result` with ``raise_=True``)."""


def _is_real(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))


def _describe(v) -> str:
    if isinstance(v, np.ndarray):
        return f"an array of shape {v.shape}"
    text = repr(v)
    return f"{type(v).__name__} {text[:40] + '...' if len(text) > 40 else text}"


def _value_problem(name: str, v, check: str, converged: bool) -> str | None:
    if not _is_real(v):
        return f"{name} must be a number, got {_describe(v)}"
    v = float(v)
    if not converged or not check:
        return None
    if not math.isfinite(v):
        return f"{name} = {v} is not finite in a converged result"
    if check == "positive" and not v > 0:
        return f"{name} = {v:.10g} must be > 0"
    if check == "nonnegative" and not v >= 0:
        return f"{name} = {v:.10g} must be >= 0"
    return None


def _shape_problem(name: str, value, shape: tuple, n: int | None) -> str | None:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return f"{name} must be numbers of shape {shape}, got {_describe(value)}"
    want = tuple(n if s == "n" else s for s in shape)
    if any(s is None for s in want):
        want = tuple(a if w is None else w for a, w in zip(arr.shape, want)) if arr.ndim == len(want) else want
    if arr.shape != want:
        return f"{name} must have shape {want}, got {arr.shape}"
    return None


def check_result(result, data=None) -> str | None:
    """The gate every result passes before it becomes a row (None: it passes; else the reason, one line).

    Checks the contract of the result's family (:func:`contract` of the family of ``result.method``):
    the class; ``converged`` a bool, ``iterations``/``nfev`` None or counts, ``message`` a string; every
    declared column a number, and in a converged result finite and of the declared sign (radius > 0, form
    error >= 0); every declared shape (``"n"``: one per point of ``data``); ``extra`` JSON-serialisable;
    for circles, the form error and residuals recomputed from ``data`` about the returned centre (a method
    cannot claim a form error its points do not have)."""
    if not isinstance(result, FitResult):
        return f"the method returned {_describe(result)}, not a methods.results.FitResult"
    if not isinstance(result.method, str):
        return f"method must be the method id, got {_describe(result.method)}"
    family = str(result.method).partition(".")[0]
    cls = contract(family)
    if cls is not None and not isinstance(result, cls):
        return f"a {family} method must return a {cls.__name__}, got a {type(result).__name__}"
    if not isinstance(result.converged, (bool, np.bool_)):
        return f"converged must be True or False, got {_describe(result.converged)}"
    converged = bool(result.converged)
    for name in ("iterations", "nfev"):
        v = getattr(result, name)
        if v is not None and not (isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_)) and v >= 0):
            return f"{name} must be None or a count >= 0, got {_describe(v)}"
    if not isinstance(result.message, str):
        return f"message must be a string, got {_describe(result.message)}"
    if not isinstance(result.extra, dict) or not isinstance(result.params, dict):
        return "extra and params must be dicts"
    try:
        json.dumps(_jsonable(result.extra), allow_nan=False)
    except (TypeError, ValueError) as exc:
        return f"extra is not JSON-serialisable ({type(exc).__name__}: {str(exc)[:80]})"
    n = None
    if isinstance(data, np.ndarray) and data.ndim == 2:
        n = data.shape[0]
    for name, shape in {**type(result).SHAPES, **(cls or type(result)).SHAPES}.items():
        problem = _shape_problem(name, getattr(result, name), shape, n)
        if problem:
            return problem
    try:
        values = {"form_error": result.form_error, **result.geometry()}
    except Exception as exc:  # a geometry the class cannot even read out
        return f"the geometry cannot be read ({type(exc).__name__}: {str(exc)[:80]})"
    rules = cls or type(result)  # the family's declarations win over a subclass's own
    declared = {**{c.name: c for c in type(result).COLUMNS}, **{c.name: c for c in rules.COLUMNS}}
    problems = [_value_problem(name, v, declared[name].check if name in declared else "finite", converged)
                for name, v in values.items()]
    if any(problems):
        return "; ".join(p for p in problems if p)
    residuals = result.residuals
    if not isinstance(residuals, np.ndarray) or residuals.dtype.kind not in "fiu":
        return f"residuals must be a numeric array, got {_describe(residuals)}"
    if converged and residuals.size and not np.isfinite(residuals).all():
        return "residuals are not finite in a converged result"
    if converged and n:
        return (cls or type(result)).consistency(result, data)
    return None


def _circle_consistency(result: CircleFit, points: np.ndarray) -> str | None:
    """A converged circle's form error and residuals are those of its points about its centre and radius
    (``CircleFit.consistency``)."""
    with np.errstate(all="ignore"):
        r = np.hypot(points[:, 0] - result.center[0], points[:, 1] - result.center[1])
        span = float(r.max() - r.min())
        scale = float(r.max()) + abs(float(result.radius))
        tol = 1e-9 * scale + 1e-6 * span
        if not abs(float(result.form_error) - span) <= tol:
            return (f"form_error = {float(result.form_error):.10g} but the points' radial span about the returned "
                    f"centre is {span:.10g}")
        if result.residuals.shape == r.shape and not np.all(np.abs(result.residuals - (r - result.radius)) <= tol):
            return "residuals are not the radial distances minus the radius about the returned centre"
    return None


def _ellipse_consistency(result: EllipseFit, points: np.ndarray) -> str | None:
    """A converged ellipse keeps its declared form: a >= b, angle in [0, pi), form error = the span of its
    residuals (``EllipseFit.consistency``)."""
    a, b = float(result.semi_axes[0]), float(result.semi_axes[1])
    if not a >= b:
        return f"semi_axes = ({a:.10g}, {b:.10g}): a must be >= b"
    if not 0.0 <= float(result.angle) < math.pi:
        return f"angle = {float(result.angle):.10g} rad must lie in [0, pi)"
    d = result.residuals
    if d.size:
        span = float(d.max() - d.min())
        if not abs(float(result.form_error) - span) <= 1e-9 * (a + span) + 1e-6 * span:
            return f"form_error = {float(result.form_error):.10g} but its residuals span {span:.10g}"
    return None


def _no_consistency(result, data) -> None:
    return None


FitResult.consistency = staticmethod(_no_consistency)
CircleFit.consistency = staticmethod(_circle_consistency)
EllipseFit.consistency = staticmethod(_ellipse_consistency)
