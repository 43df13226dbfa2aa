"""ISO 230-4 evaluation of a bidirectional circular test.

* G (circular deviation) of each run: the minimum radial separation of two concentric circles that
  enclose the path; evaluated about the least-squares centre of that run (``center='lsq'``, the
  standard's usual evaluation) or as the minimum zone (``center='mz'``).
* G(b) (bidirectional circular deviation): the same for both runs together.
* H (circular hysteresis, ISO 230-4:1996): the largest radial difference between the two runs at the
  same angle, about the least-squares centre of both runs together. Each run is read as the linear
  interpolation of its radius in angle between its consecutive points (periodic for a full circle); H is
  the maximum of |r_cw(theta) - r_ccw(theta)| over every angle both runs cover. That difference is linear
  between the angles of the two runs' points, so its maximum lies at one of them: H is evaluated exactly at
  every point of both runs (the data's resolution; no grid, no subsampling) by :func:`hysteresis`.
* F_max, F_min (radial deviation): the largest and smallest deviation of the path from the nominal
  radius, about the nominal centre when given, else the least-squares centre of both runs.
* mean radial deviation: the mean of those deviations.

Repeated samples (a sample with the coordinates of the one before it: the machine dwelling, or a logger writing
each sample twice) are refused (:func:`refuse_repeated`): the contour is the path while the machine moves, and a
repeated position weights the least-squares centres (a 60-sample dwell moved G(b) by 0.3 um) and makes the
diagnostics' uncertainties optimistic (every sample twice divides them by sqrt 2).
:func:`methods.circular_test.runs.drop_repeated` drops them and says where (``fitbench circular-test`` does).

Partial arcs (ISO 230-4 allows arcs smaller than 360 deg, e.g. in vertical planes where the
ballbar's fixture blocks part of the circle: 180 deg or 220 deg): G, G(b) and F are evaluated on the
arc measured (the least-squares centre of an arc of at least 90 deg is well determined); H on the
angles both runs cover. Arcs under ``MIN_ARC_DEG`` are refused; arc spans are compared within
:func:`arc_tolerance_deg` (the angles' floating-point resolution plus the path's own deviations, which
move its ends), so a run recorded over exactly 90 deg is accepted.
"""
from __future__ import annotations

from dataclasses import asdict, is_dataclass

import numpy as np

import methods
from methods._errors import InvalidInputError
from methods.circular_test.results import CircularTestFit
from methods._validation import validate_points

RADIUS_TOLERANCE = 0.05     # the data's mean radius may differ from the nominal radius by 5 % at most
RUNS_TOLERANCE = 0.01       # the two runs' circles may differ by 1 % of the radius at most
MAX_ANGULAR_GAP_DEG = 30.0  # a run with no angular gap wider than this counts as a full circle
MIN_ARC_DEG = 90.0          # the shortest arc evaluated (ISO 230-4 partial arcs)
ARC_ULPS = 64               # arc spans equal within this many units of roundoff of the angles (arc_tolerance_deg)
ARC_DEVIATIONS = 4.0        # ... and within this many radial peak-to-valleys over the radius (arc_tolerance_deg)


def arc_tolerance_deg(points, center, deviations: bool = True) -> float:
    """Tolerance (deg) within which an arc span of ``points`` about ``center`` equals a nominal arc.

    A run recorded over exactly its nominal arc spans it only up to (a) the floating-point resolution of
    its polar angles, ``ARC_ULPS`` units of roundoff of angles up to 2 pi computed from coordinates as large
    as M = max |coordinate| at radii r (eps M / r rad for the coordinate, the subtraction and the centre
    each), and (b) the path's own deviations, which move its ends along the circle: ``ARC_DEVIATIONS``
    times the run's radial peak-to-valley over its radius. For a linear error (squareness, scale or servo
    mismatch) the deviation along the path is half the angular derivative of the radial one, so a 90 deg
    arc's span moves by up to twice its radial peak-to-valley (a squareness alpha moves the end of a
    0-90 deg arc by alpha R along the path, its radial peak-to-valley being alpha R / 2); the factor
    doubles that for noise and the non-linear errors. ``deviations=False``: (a) only (the point that closes
    a full circle).
    """
    pts = np.asarray(points, float)
    c = np.asarray(center, float)
    if not len(pts):
        return 0.0
    r = np.hypot(pts[:, 0] - c[0], pts[:, 1] - c[1])
    m = max(float(np.max(np.abs(pts))), float(np.max(np.abs(c))))
    r_min, r_mid = float(r.min()), float(np.median(r))
    if not r_min > 0:
        return 0.0
    roundoff = ARC_ULPS * np.finfo(float).eps * (2 * np.pi + 3 * m / r_min)
    return float(np.degrees(roundoff + (ARC_DEVIATIONS * (float(r.max()) - r_min) / r_mid if deviations else 0.0)))


def repeated_groups(mask) -> list[tuple[int, int]]:
    """The groups of consecutive repeated samples of a run: [(first, last)] 0-based sample indices, ``first`` the
    sample that the group repeats (``mask[i]``: sample i repeats sample i - 1)."""
    mask = np.asarray(mask, bool)
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    return [(int(a) - 1, int(b) - 1) for a, b in zip(edges[::2], edges[1::2])]


def groups_text(groups, limit: int = 3) -> str:
    """'samples 1-60 are one position' / 'samples 1-2, 3-4, 5-6 and 3379 more groups are one position each'
    (1-based sample numbers in the run's order)."""
    shown = ", ".join(f"{a + 1}-{b + 1}" for a, b in groups[:limit])
    more = len(groups) - limit
    return (f"samples {shown}" + (f" and {more} more group{'s' if more > 1 else ''}" if more > 0 else "") +
            (" are one position each" if len(groups) > 1 else " are one position"))


def refuse_repeated(points, name: str) -> None:
    """Refuse a run with consecutive samples at exactly the same coordinates (a dwell, a logger repeating samples):
    they are not independent points of the contour (module docstring)."""
    pts = np.asarray(points, float)
    mask = np.r_[False, np.all(pts[1:] == pts[:-1], axis=1)] if len(pts) else np.zeros(0, bool)
    if mask.any():
        groups = repeated_groups(mask)
        raise InvalidInputError(
            f"{name} run: {int(mask.sum())} sample(s) repeat the one before them ({groups_text(groups)}: a dwell, "
            "or a logger writing samples twice); repeated samples weight the least-squares "
            "centres and make the diagnostics' uncertainties optimistic: drop them first "
            "(methods.circular_test.runs.drop_repeated; fitbench circular-test does and says where)")


def coverage_deg(points, center) -> tuple[float, float]:
    """(arc covered, largest angular gap) in degrees of points about ``center``."""
    a = np.sort(np.degrees(np.arctan2(points[:, 1] - center[1], points[:, 0] - center[0])))
    gap = max(np.diff(a).max(initial=0.0), 360.0 - (a[-1] - a[0]))
    return float(360.0 - gap), float(gap)


def radii(points, center):
    return np.hypot(points[:, 0] - center[0], points[:, 1] - center[1])


#: a typical ballbar radius (mm; ISO 230-4 ballbars measure 50 to 600 mm): of two unit readings that both fit
#: the data, the one whose radius is nearer to it (in ratio) is named (:func:`nominal_mismatch`)
TYPICAL_RADIUS_MM = 150.0
#: the units a unit mix-up is looked for in (a file's numbers, or --nominal-radius typed in one of them)
_MIXUP_UNITS = ("nm", "µm", "mm", "m", "in")


def _unit_for(target_mm_per: float, exclude: str) -> str | None:
    """The unit u (not ``exclude``) whose ``mm_per(u)`` is within ``RADIUS_TOLERANCE`` of ``target_mm_per``."""
    from methods.units import canonical, mm_per
    for u in _MIXUP_UNITS:
        if u != canonical(exclude) and abs(mm_per(u) / target_mm_per - 1.0) <= RADIUS_TOLERANCE:
            return u
    return None


def nominal_mismatch(points, name: str, nominal_radius: float, nominal_center=None, unit: str = "mm",
                     center=None) -> str | None:
    """Why the run ``points`` (mm, read from a file in ``unit``) lie off the nominal circle, or None when the median
    distance of its points from ``nominal_center`` (else ``center``, else the run's own least-squares centre) is
    within ``RADIUS_TOLERANCE`` of ``nominal_radius``. The run's own least-squares circle tells a wrong nominal centre
    (its radius matches) from a unit mix-up: the unit that scales the file's numbers onto the nominal circle
    (``--unit``), or the unit ``--nominal-radius`` was typed in. When both fit, the nominal centre decides (the data
    rescaled must land on it: the centre and the radius are given in one unit), else the reading whose radius is
    nearer (in ratio) to ``TYPICAL_RADIUS_MM``."""
    from methods.units import canonical, mm_per
    pts = np.asarray(points, float)
    R = float(nominal_radius)
    own = None
    if nominal_center is None and center is None:
        own = methods.fit("circle.gauss_newton", pts)
        center = own.center
    about = np.asarray(nominal_center if nominal_center is not None else center, float)
    dist = float(np.median(radii(pts, about)))
    if abs(dist - R) <= RADIUS_TOLERANCE * R:
        return None
    own = own or methods.fit("circle.gauss_newton", pts)
    c_own, r_own = np.asarray(own.center, float), float(own.radius)
    unit = canonical(unit)
    if nominal_center is not None:
        where = (f"{name} run: the data lie {dist:.6g} mm from --nominal-center ({about[0]:g}, {about[1]:g}) mm, "
                 f"not {R:g} mm (--nominal-radius)")
        if abs(r_own - R) <= RADIUS_TOLERANCE * R:   # the right circle in the wrong place
            return (f"{where}; their own circle (radius {r_own:.6g} mm) is centred at ({c_own[0]:.6g}, "
                    f"{c_own[1]:.6g}) mm, {float(np.hypot(*(c_own - about))):.6g} mm from it: check --nominal-center")
    if not r_own > 0:
        return f"{where if nominal_center is not None else name + ' run: far from the nominal circle'}; " \
               "check --nominal-radius and --unit"
    factor = R / r_own   # what the data would have to be multiplied by to lie on the nominal circle
    scale = f"{factor:.4g} times smaller" if factor > 1 else f"{1 / factor:.4g} times larger"
    if nominal_center is not None:
        what = (f"{where}; their own circle (centre ({c_own[0]:.6g}, {c_own[1]:.6g}) mm, radius {r_own:.6g} mm, "
                f"read as {unit}) is {scale} than the nominal circle")
    else:
        what = (f"{name} run: the data's radius ({dist:.6g} mm, read as {unit}) is far from the nominal radius {R:g} mm "
                f"(more than {RADIUS_TOLERANCE:.0%}: {scale})")
    candidates = []      # (does not fit the nominal centre, log distance from a typical radius, hint)
    named = {"in": "inches"}
    file_unit = _unit_for(factor * mm_per(unit), unit)
    if file_unit is not None:
        off_centre = nominal_center is not None and float(np.hypot(*(c_own * factor - about))) > RADIUS_TOLERANCE * R
        candidates.append((off_centre, abs(np.log(R / TYPICAL_RADIUS_MM)),
                           f"is the file in {named.get(file_unit, file_unit)}? (--unit {file_unit.replace('µ', 'u')})"))
    radius_unit = _unit_for(r_own / R, "mm")
    if radius_unit is not None:   # --nominal-radius typed in radius_unit (and --nominal-center as given or in it)
        f, u = mm_per(radius_unit), named.get(radius_unit, radius_unit)
        as_given, scaled = (None, None) if nominal_center is None else \
            (float(np.hypot(*(c_own - about))), float(np.hypot(*(c_own - about * f))))
        if nominal_center is not None and scaled <= RADIUS_TOLERANCE * r_own < as_given:   # both typed in that unit
            hint = (f"are --nominal-radius and --nominal-center in {u}? (they are in mm: give --nominal-radius "
                    f"{R * f:.6g} --nominal-center {about[0] * f:.6g} {about[1] * f:.6g})")
        else:
            hint = f"is --nominal-radius in {u}? (it is in mm: give --nominal-radius {R * f:.6g})"
        off_centre = nominal_center is not None and min(as_given, scaled) > RADIUS_TOLERANCE * r_own
        candidates.append((off_centre, abs(np.log(r_own / TYPICAL_RADIUS_MM)), hint))
    if not candidates:
        return f"{what}; check --nominal-radius, --unit" + (" and --nominal-center" if nominal_center is not None else "")
    return f"{what}; {min(candidates)[2]}"


def _check_run(points, name, nominal_radius, center, nominal_center=None, unit="mm"):
    if (why := nominal_mismatch(points, name, nominal_radius, nominal_center, unit, center=center)) is not None:
        raise InvalidInputError(why)
    arc, gap = coverage_deg(points, center)
    if arc < MIN_ARC_DEG - arc_tolerance_deg(points, center):
        raise InvalidInputError(f"{name} run: it covers an arc of {arc:.6g} deg; an evaluation needs at least "
                                f"{MIN_ARC_DEG:g} deg of arc (ISO 230-4 partial arcs) or the full circle")
    return arc, gap


def _zone(points, center_kind):
    if center_kind == "mz":
        res = methods.fit("circle.minimum_zone", points)
        if not res.converged:
            raise InvalidInputError(f"minimum-zone evaluation failed: {res.message}")
        return np.array(res.center), res.form_error
    res = methods.fit("circle.gauss_newton", points)
    if not res.converged:
        raise InvalidInputError(f"least-squares centre failed: {res.message}")
    return np.array(res.center), res.form_error


def _run_polar(pts, center, ref=0.0):
    """(angles in (-pi, pi] about ``center`` relative to ``ref``, sorted; their radii)."""
    ang = np.angle(np.exp(1j * (np.arctan2(pts[:, 1] - center[1], pts[:, 0] - center[0]) - ref)))
    order = np.argsort(ang, kind="stable")
    return ang[order], radii(pts, center)[order]


def hysteresis(cw, ccw, center, partial=False):
    """H = max |r_cw(theta) - r_ccw(theta)| (ISO 230-4:1996) about ``center``, each run's radius
    linearly interpolated in angle between its neighbouring points (periodic for full circles; for partial
    arcs over the angles both runs cover, measured from the middle of the arc). The difference of two
    piecewise-linear functions is linear between their knots, so evaluating it at every point of both runs
    gives its maximum exactly."""
    ref = 0.0
    if partial:
        both = np.vstack([cw, ccw])
        ref = np.arctan2(np.mean(both[:, 1] - center[1]), np.mean(both[:, 0] - center[0]))  # middle of the arc
    (a1, r1), (a2, r2) = _run_polar(cw, center, ref), _run_polar(ccw, center, ref)
    if not partial:
        d12 = r1 - np.interp(a1, a2, r2, period=2 * np.pi)
        d21 = r2 - np.interp(a2, a1, r1, period=2 * np.pi)
        return float(max(np.max(np.abs(d12)), np.max(np.abs(d21))))
    lo, hi = max(a1[0], a2[0]), min(a1[-1], a2[-1])
    if hi < lo:
        raise InvalidInputError("the CW and CCW runs cover no common arc: H cannot be evaluated")
    i1, i2 = (a1 >= lo) & (a1 <= hi), (a2 >= lo) & (a2 <= hi)
    d = [np.abs(r1[i1] - np.interp(a1[i1], a2, r2)), np.abs(r2[i2] - np.interp(a2[i2], a1, r1))]
    return float(max(np.max(v, initial=0.0) for v in d))


def evaluate(cw, ccw, nominal_radius: float, nominal_center=None, center: str = "lsq",
             conditions=None) -> CircularTestFit:
    """ISO 230-4 figures of a bidirectional test (see the module docstring) as a
    :class:`~methods.circular_test.results.CircularTestFit`; lengths in data units."""
    if center not in ("lsq", "mz"):
        raise InvalidInputError(f"center must be 'lsq' or 'mz', got {center!r}")
    if is_dataclass(conditions):
        conditions = asdict(conditions)
    if not (np.isfinite(nominal_radius) and nominal_radius > 0):
        raise InvalidInputError(f"the nominal radius must be a positive number, got {nominal_radius!r}")
    cw = validate_points(cw, min_points=10, method="circular test (CW run)")
    ccw = validate_points(ccw, min_points=10, method="circular test (CCW run)")
    refuse_repeated(cw, "CW")
    refuse_repeated(ccw, "CCW")
    both = np.vstack([cw, ccw])
    c_both = np.array(methods.fit("circle.gauss_newton", both).center)
    arcs = {}
    for pts, name in ((cw, "CW"), (ccw, "CCW")):
        arcs[name.lower()], _ = _check_run(pts, name, nominal_radius,
                                           nominal_center if nominal_center is not None else c_both, nominal_center,
                                           (conditions or {}).get("input_unit") or "mm")
    partial = any(360.0 - a > MAX_ANGULAR_GAP_DEG for a in arcs.values())
    fits = {name: methods.fit("circle.gauss_newton", pts) for name, pts in (("cw", cw), ("ccw", ccw))}
    dc = np.hypot(*(np.array(fits["cw"].center) - fits["ccw"].center))
    dr = abs(fits["cw"].radius - fits["ccw"].radius)
    if max(dc, dr) > RUNS_TOLERANCE * nominal_radius:
        raise InvalidInputError(f"the CW and CCW runs do not describe the same circle (centres {dc:.4g} apart, "
                                f"radii differ by {dr:.4g}): mismatched files?")
    c_cw, G_cw = _zone(cw, center)
    c_ccw, G_ccw = _zone(ccw, center)
    c_b, G_b = _zone(both, center)
    H = hysteresis(cw, ccw, c_both, partial=partial)
    f_center = np.asarray(nominal_center, dtype=float) if nominal_center is not None else c_both
    dev = radii(both, f_center) - nominal_radius
    about = {"lsq": "the least-squares centre", "mz": "the minimum-zone centre"}[center]
    return CircularTestFit(
        method="ISO 230-4", form_error=float(G_b), residuals=dev, converged=True,
        message=f"ISO 230-4 figures: G about {about} of each run and of both runs, H and F as stated",
        figures={"G_cw": float(G_cw), "G_ccw": float(G_ccw), "G_b": float(G_b), "H": H, "F_max": float(dev.max()),
                 "F_min": float(dev.min()), "mean_radial_deviation": float(dev.mean())},
        center=tuple(float(v) for v in c_b), center_cw=tuple(float(v) for v in c_cw),
        center_ccw=tuple(float(v) for v in c_ccw), center_kind=center, F_center=tuple(float(v) for v in f_center),
        F_about="nominal centre" if nominal_center is not None else "least-squares centre of both runs",
        H_about="least-squares centre of both runs (ISO 230-4:1996)", nominal_radius=float(nominal_radius),
        n_points={"cw": len(cw), "ccw": len(ccw)}, conditions=conditions or {}, partial_arc=bool(partial),
        arc_deg={k: round(v, 3) for k, v in arcs.items()})
