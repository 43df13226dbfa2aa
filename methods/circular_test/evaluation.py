"""ISO 230-4 evaluation of a bidirectional circular test.

* G (circular deviation) of each run: the minimum radial separation of two concentric circles that
  enclose the path; evaluated about the least-squares centre of that run (``center='lsq'``, the
  standard's usual evaluation) or as the minimum zone (``center='mz'``).
* G(b) (bidirectional circular deviation): the same for both runs together.
* H (circular hysteresis, ISO 230-4:1996): the largest radial difference between the two runs at the
  same angle, about the least-squares centre of both runs together.
* F_max, F_min (radial deviation): the largest and smallest deviation of the path from the nominal
  radius, about the nominal centre when given, else the least-squares centre of both runs.
* mean radial deviation: the mean of those deviations.

Partial arcs (ISO 230-4 allows arcs smaller than 360 deg, e.g. in vertical planes where the
ballbar's fixture blocks part of the circle: 180 deg or 220 deg): G, G(b) and F are evaluated on the
arc measured (the least-squares centre of an arc of at least 90 deg is well determined); H on the
angles both runs cover. Arcs under ``MIN_ARC_DEG`` are refused.
"""
from __future__ import annotations

from dataclasses import asdict, is_dataclass

import numpy as np

import methods
from methods._errors import InvalidInputError
from methods._result import CircularTestFit
from methods._validation import validate_points

RADIUS_TOLERANCE = 0.05     # the data's mean radius may differ from the nominal radius by 5 % at most
RUNS_TOLERANCE = 0.01       # the two runs' circles may differ by 1 % of the radius at most
MAX_ANGULAR_GAP_DEG = 30.0  # a run with no angular gap wider than this counts as a full circle
MIN_ARC_DEG = 90.0          # the shortest arc evaluated (ISO 230-4 partial arcs)


def coverage_deg(points, center) -> tuple[float, float]:
    """(arc covered, largest angular gap) in degrees of points about ``center``."""
    a = np.sort(np.degrees(np.arctan2(points[:, 1] - center[1], points[:, 0] - center[0])))
    gap = max(np.diff(a).max(initial=0.0), 360.0 - (a[-1] - a[0]))
    return float(360.0 - gap), float(gap)


def radii(points, center):
    return np.hypot(points[:, 0] - center[0], points[:, 1] - center[1])


def _check_run(points, name, nominal_radius, center):
    r = radii(points, center)
    if abs(np.median(r) - nominal_radius) > RADIUS_TOLERANCE * nominal_radius:
        from methods.units import likely_unit
        guess = likely_unit(float(np.median(r)), nominal_radius)
        hint = f"; is the file in {guess}? (--unit {guess.replace('µ', 'u')})" if guess else ""
        raise InvalidInputError(f"{name} run: the data's radius ({np.median(r):.6g} mm) is far from the nominal radius "
                                f"{nominal_radius:g} mm (more than {RADIUS_TOLERANCE:.0%}); check --nominal-radius and "
                                f"--unit{hint}")
    arc, gap = coverage_deg(points, center)
    if arc < MIN_ARC_DEG:
        raise InvalidInputError(f"{name} run: it covers an arc of {arc:.0f} deg; an evaluation needs at least "
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


def hysteresis(cw, ccw, center, samples=3600, partial=False):
    """Largest |r_cw(theta) - r_ccw(theta)| over a common angle grid (periodic linear interpolation; for
    partial arcs linear interpolation over the angles both runs cover)."""
    if not partial:
        grid = np.linspace(-np.pi, np.pi, samples, endpoint=False)
        out = []
        for pts in (cw, ccw):
            ang = np.arctan2(pts[:, 1] - center[1], pts[:, 0] - center[0])
            order = np.argsort(ang)
            out.append(np.interp(grid, ang[order], radii(pts, center)[order], period=2 * np.pi))
        return float(np.max(np.abs(out[0] - out[1])))
    both = np.vstack([cw, ccw])
    ref = np.arctan2(np.mean(both[:, 1] - center[1]), np.mean(both[:, 0] - center[0]))  # middle of the arc
    angs, rads = [], []
    for pts in (cw, ccw):
        ang = np.angle(np.exp(1j * (np.arctan2(pts[:, 1] - center[1], pts[:, 0] - center[0]) - ref)))
        order = np.argsort(ang)
        angs.append(ang[order])
        rads.append(radii(pts, center)[order])
    lo, hi = max(a[0] for a in angs), min(a[-1] for a in angs)
    if hi <= lo:
        raise InvalidInputError("the CW and CCW runs cover no common arc: H cannot be evaluated")
    grid = np.linspace(lo, hi, samples)
    out = [np.interp(grid, a, r) for a, r in zip(angs, rads)]
    return float(np.max(np.abs(out[0] - out[1])))


def evaluate(cw, ccw, nominal_radius: float, nominal_center=None, center: str = "lsq",
             conditions=None) -> CircularTestFit:
    """ISO 230-4 figures of a bidirectional test (see the module docstring) as a
    :class:`~methods._result.CircularTestFit`; lengths in data units."""
    if center not in ("lsq", "mz"):
        raise InvalidInputError(f"center must be 'lsq' or 'mz', got {center!r}")
    if not (np.isfinite(nominal_radius) and nominal_radius > 0):
        raise InvalidInputError(f"the nominal radius must be a positive number, got {nominal_radius!r}")
    cw = validate_points(cw, min_points=10, method="circular test (CW run)")
    ccw = validate_points(ccw, min_points=10, method="circular test (CCW run)")
    both = np.vstack([cw, ccw])
    c_both = np.array(methods.fit("circle.gauss_newton", both).center)
    arcs = {}
    for pts, name in ((cw, "CW"), (ccw, "CCW")):
        arcs[name.lower()], _ = _check_run(pts, name, nominal_radius,
                                           nominal_center if nominal_center is not None else c_both)
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
    if is_dataclass(conditions):
        conditions = asdict(conditions)
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
