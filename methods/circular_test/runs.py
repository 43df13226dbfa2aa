"""What a careful operator checks before evaluating a circular test (ISO 230-4), from the data alone.

* The direction of each run is read from the order of its points: the unwrapped polar angle about
  the centre increases for a counter-clockwise (G03) run and decreases for a clockwise (G02) run, as
  seen in the plane's own axes (first axis to the right, second up).
* Lead-in and lead-out arcs (the feed-in/feed-out segments ballbar software records around the data
  arc) are removed by angle swept from the start and before the end; overrun beyond the nominal arc
  (e.g. 380 deg recorded for a 360 deg test) is trimmed and reported. The arc swept is measured along the
  point order, so the result does not depend on where the run starts. Arcs are compared within
  :func:`~methods.circular_test.evaluation.arc_tolerance_deg` (roundoff and the path's own deviations): a
  partial run recorded over exactly its nominal arc keeps its end point; a full circle drops only the point
  that closes it (back at 360 deg within roundoff).
* Repeated samples (the machine at rest: a dwell before it moves, a feed hold; or a logger writing each sample
  twice) are not points of the contour: a sample that moved less than ``REPEAT_FRACTION`` of its run's median
  sampling step from the one before it repeats it, and is dropped by :func:`drop_repeated`, which says how many
  and where (the first sample of each group, the position the machine stood at, is kept). Kept, a 60-sample
  dwell at the start pulled the least-squares centres towards it (G CW 25.22 instead of 25.11 um) and every
  sample twice divided the diagnostics' u by sqrt 2.
* A nominal centre or radius far from the data's own least-squares circle gives F values dominated by
  the set-up error: warned with the fitted values (threshold ``NOMINAL_WARN_FRACTION`` of the radius).
"""
from __future__ import annotations

import numpy as np

from methods._errors import InvalidInputError
from methods.circular_test.evaluation import MIN_ARC_DEG, arc_tolerance_deg, groups_text, repeated_groups

#: nominal centre or radius further than this fraction of the radius from the fitted circle: a warning
#: (2e-4 R = 60 µm at R = 300 mm, 20 µm for a 100 mm ballbar: well above a careful set-up)
NOMINAL_WARN_FRACTION = 2e-4
#: a sample closer than this fraction of its run's median (non-zero) sampling step to the one before it repeats it
#: (the machine did not move: 1 % of a step is 5 µm at 1000 mm/min and 30 Hz, far above an encoder's flicker)
REPEAT_FRACTION = 0.01


def unwrapped_angle(points, center) -> np.ndarray:
    """Polar angle of each point about ``center`` along the point order, unwrapped (rad)."""
    ang = np.arctan2(points[:, 1] - center[1], points[:, 0] - center[0])
    return np.unwrap(ang)


def direction(points, center) -> tuple[str, float]:
    """('ccw' or 'cw', signed angle swept in degrees) of a run from the order of its points."""
    a = unwrapped_angle(points, center)
    swept = float(np.degrees(a[-1] - a[0]))
    return ("ccw" if swept > 0 else "cw"), swept


def repeated(points) -> np.ndarray:
    """Mask of the samples that repeat the one before them: moved by at most ``REPEAT_FRACTION`` of the run's
    median non-zero sampling step (exact repeats included)."""
    pts = np.asarray(points, float)
    if len(pts) < 2:
        return np.zeros(len(pts), bool)
    step = np.hypot(*np.diff(pts, axis=0).T)
    moving = step[step > 0]
    limit = REPEAT_FRACTION * float(np.median(moving)) if len(moving) else 0.0
    return np.r_[False, step <= limit]


def drop_repeated(points, center=None, name: str = "") -> tuple[np.ndarray, dict, str | None]:
    """(the run without its repeated samples, report, warning text or None). The report gives the number dropped
    and each group as [first, last] 1-based sample numbers of the run as read (the first is kept) with its
    polar angle about ``center`` (degrees, None without a centre)."""
    pts = np.asarray(points, float)
    mask = repeated(pts)
    groups = repeated_groups(mask)
    ang = None
    if center is not None and groups:
        ang = np.degrees(np.arctan2(pts[:, 1] - center[1], pts[:, 0] - center[0])) % 360.0
    report = {"repeated_samples_dropped": int(mask.sum()),
              "repeated_groups": [[a + 1, b + 1, None if ang is None else round(float(ang[a]), 3)] for a, b in groups]}
    if not groups:
        return pts, report, None
    where = ""
    if len(groups) <= 3 and ang is not None:
        where = ", at " + ", ".join(f"{ang[a]:.1f}°" for a, _ in groups)
    why = "a dwell at the start" if groups[0][0] == 0 and len(groups) == 1 else "a dwell or a logger repeating samples"
    text = (f"{name + ' run: ' if name else ''}{int(mask.sum())} repeated sample(s) dropped: {groups_text(groups)}"
            f"{where} ({why}: the machine moved less than {REPEAT_FRACTION:.0%} of a sampling step); they are not "
            f"contour points, so each position is evaluated once ({len(pts) - int(mask.sum())} of {len(pts)} samples kept)")
    return pts[~mask], report, text


#: samples at a run's start or end further from the circle its middle follows than this many robust standard
#: deviations of the middle's radial deviations, and than OFF_CIRCLE_MIN_MM, are no contour points (a feed-in)
OFF_CIRCLE_SIGMAS = 30.0
OFF_CIRCLE_MIN_MM = 0.05


def off_circle_ends(points, center, name: str = "") -> str | None:
    """What is wrong when the first or last samples of a run lie off the circle the rest of it follows (a radial
    feed-in or feed-out a grid-encoder or tracking recording starts or ends with), or None. The circle is the
    algebraic least-squares circle (Kasa) of the middle 80 % of the samples; a sample is off when its radial
    deviation from it differs from the middle's median by more than OFF_CIRCLE_SIGMAS x 1.4826 MAD of the middle's
    and OFF_CIRCLE_MIN_MM. Kept, 20 samples of a 2 mm feed-in before a 7 µm trace gave G 2003 µm, and the warnings
    blamed the nominal centre and radius. Names the samples, how far off, and the --lead-in / --lead-out that
    removes them (:func:`trim`, angles about ``center``)."""
    p = np.asarray(points, dtype=float)
    n = len(p)
    if n < 20:
        return None
    margin = n // 10
    mid = p[margin:n - margin]
    c = mid.mean(axis=0)
    q = mid - c
    sol = np.linalg.lstsq(np.column_stack([2 * q, np.ones(len(q))]), np.sum(q * q, axis=1), rcond=None)[0]
    centre, radius = c + sol[:2], float(np.sqrt(sol[2] + sol[:2] @ sol[:2]))
    dr = np.hypot(*(p - centre).T) - radius
    med = float(np.median(dr[margin:n - margin]))
    spread = 1.4826 * float(np.median(np.abs(dr[margin:n - margin] - med)))
    off = np.abs(dr - med) > max(OFF_CIRCLE_SIGMAS * spread, OFF_CIRCLE_MIN_MM)
    head = int(np.argmin(off)) if off[0] else 0
    tail = int(np.argmin(off[::-1])) if off[-1] else 0
    if not (0 < head <= margin or 0 < tail <= margin):
        return None
    swept = np.maximum.accumulate(np.degrees(np.abs(unwrapped_angle(p, center) - unwrapped_angle(p, center)[0])))
    total = float(swept[-1])
    out = []
    for part, k, lo, hi, option, edge in (("start", head, 0, head, "--lead-in", swept[head - 1] if head else 0.0),
                                          ("end", tail, n - tail, n, "--lead-out", total - swept[n - tail] if tail else 0.0)):
        if not 0 < k <= margin:
            continue
        worst = lo + int(np.argmax(np.abs(dr[lo:hi] - med)))
        side = "inside" if dr[worst] < med else "outside"
        deg = float(np.degrees(np.arctan2(*(p[worst] - center)[::-1])) % 360.0)
        lead = np.ceil((edge + 1e-9) * 10.0) / 10.0 if edge > 0 else 0.1
        out.append(f"samples {lo + 1}-{hi} at its {part} lie up to {abs(dr[worst] - med) * 1e3:.4g} µm {side} the "
                   f"circle the other samples follow (their spread {spread * 1e3:.2g} µm; near {deg:.1f}°): a radial "
                   f"feed-{'in' if part == 'start' else 'out'}? remove them ({option} {lead:g}, or delete those lines)")
    return f"{name + ' run: ' if name else ''}" + "; ".join(out)


#: the two passes of a run recorded beyond 360 deg differ when they disagree at some common angle by more than this
#: many standard deviations of a difference of two samples (sqrt 2 x the run's sample noise, :func:`sample_noise`)
OVERLAP_SIGMAS = 5.0
#: ... and by more than this (mm): 0.1 µm, a ballbar's resolution (exact or quantised data have no noise to scale by)
OVERLAP_MIN_MM = 1e-4
#: fewest samples of the overlap compared at all, and fewest in each third of it for deciding which pass is steady
OVERLAP_MIN_SAMPLES = 3


def sample_noise(points, center) -> float:
    """Robust standard deviation (mm) of one sample's radius about ``center``: 1.4826 MAD of the differences of
    consecutive radii over sqrt 2 (the path's own shape changes little over one sampling step; a backlash step or
    a spike is a few outliers the MAD ignores)."""
    r = np.hypot(*(np.asarray(points, float) - np.asarray(center, float)).T)
    d = np.diff(r)
    if len(d) < 2:
        return 0.0
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0))


def compare_passes(points, center, swept_deg, arc_deg: float = 360.0, closing_deg: float = 0.0) -> dict | None:
    """The two passes of a run recorded over more than one revolution (``swept_deg``, its arc swept from its first
    sample, beyond ``arc_deg`` = 360), compared over the angles both cover: the first pass's radius interpolated
    linearly in swept angle at each sample of the overrun (the samples from 360 deg - ``closing_deg`` on). ISO 230-4 takes the data
    arc clear of the feed-in and feed-out arcs, whose acceleration transients are no contour deviation; which end
    of an over-long recording is the lead-in or lead-out is not in the file, but the passes say where they differ.
    Returns None for fewer than ``OVERLAP_MIN_SAMPLES`` overrun samples, else {'overlap_deg', 'samples',
    'max_difference_mm', 'noise_mm', 'limit_mm', 'differ', 'at_start', 'at_end', 'steady'}: ``at_start`` the
    largest difference in the third of the overlap where the first pass is the recording's start, ``at_end`` in the
    third where the second pass is its end; ``steady`` 'end' (the first pass carries a transient that has died out
    by the end of the overlap: keep the last 360 deg), 'start' (the second pass differs only near the recording's
    end: keep the first 360 deg) or None (they agree, or differ throughout: a drift, or transients at both ends)."""
    sw = np.asarray(swept_deg, float)
    r = np.hypot(*(np.asarray(points, float) - np.asarray(center, float)).T)
    if arc_deg < 360.0 or len(sw) < 2:
        return None
    step = float(np.median(np.diff(sw)))
    late = sw >= arc_deg - closing_deg      # the samples the full circle trims (from 360 deg within ``closing_deg`` on)
    n = int(late.sum())
    if n < OVERLAP_MIN_SAMPLES:
        return None
    phi = sw[late] - arc_deg
    first = ~late & (sw <= phi[-1] + step + 1e-9)
    if first.sum() < 2:
        return None
    diff = np.interp(phi, sw[first], r[first]) - r[late]   # first pass minus second, at the overrun's angles
    noise = sample_noise(points, center)
    limit = max(OVERLAP_SIGMAS * np.sqrt(2.0) * noise, OVERLAP_MIN_MM)
    third = n // 3
    worst = float(np.max(np.abs(diff)))
    out = {"overlap_deg": float(phi[-1]), "samples": n, "max_difference_mm": worst, "noise_mm": noise,
           "limit_mm": float(limit), "differ": worst > limit, "at_start": None, "at_end": None, "steady": None}
    if third >= OVERLAP_MIN_SAMPLES:
        a, b = float(np.max(np.abs(diff[:third]))), float(np.max(np.abs(diff[-third:])))
        out.update(at_start=a, at_end=b)
        if out["differ"] and a > limit >= b:
            out["steady"] = "end"
        elif out["differ"] and b > limit >= a:
            out["steady"] = "start"
    return out


def trim(points, center, *, arc_deg: float | None = 360.0, lead_in_deg: float = 0.0, lead_out_deg: float = 0.0,
         overrun: str = "end", name: str = ""):
    """Drop ``lead_in_deg`` of arc at the start and ``lead_out_deg`` at the end (along the point order),
    then anything beyond ``arc_deg`` of swept arc (overrun; a partial arc keeps a point at exactly
    ``arc_deg`` within ``arc_tolerance_deg``, a full circle drops the samples back at 360 deg within roundoff or
    within the noise of their angle, 5 x the radial sample noise over the radius (:func:`sample_noise`), at most
    half a sampling step: they measure its first sample's angle again;
    the leads are cut within roundoff; leads as long as the recorded arc are refused). Returns (points, report dict).

    A full circle recorded beyond 360 deg covers its first angles twice: the passes are compared
    (:func:`compare_passes`, in ``report['passes']``). ``overrun='end'`` trims the end (the overrun);
    ``overrun='auto'`` keeps the last 360 deg instead when the first pass carries a transient the second has not
    (a lead-in arc recorded with the data: its first samples off by a 6 µm acceleration transient gave G 6.61 µm
    for a 1.45 µm circle). ``report['overrun_at']`` says which end was trimmed. A run that goes round twice (two
    tests in one file, the second after a blank line) is refused: which revolution is the test is not in the data."""
    for v, n in ((lead_in_deg, "--lead-in"), (lead_out_deg, "--lead-out")):
        if not (np.isfinite(v) and v >= 0):
            raise InvalidInputError(f"{n} must be a non-negative angle in degrees, got {v!r}")
    if arc_deg is not None and not (np.isfinite(arc_deg) and MIN_ARC_DEG <= arc_deg <= 360.0):
        raise InvalidInputError(f"--arc must be between {MIN_ARC_DEG:g} and 360 degrees, got {arc_deg!r}")
    if overrun not in ("end", "auto"):
        raise ValueError(f"overrun must be 'end' or 'auto', got {overrun!r}")
    tol = arc_tolerance_deg(points, center)                           # a recorded arc's end
    eps = arc_tolerance_deg(points, center, deviations=False)         # roundoff only
    a = unwrapped_angle(points, center)
    swept = np.degrees(np.abs(a - a[0]))        # monotone for a clean run; max-accumulate for noise
    swept = np.maximum.accumulate(swept)
    total = float(swept[-1])
    if lead_in_deg + lead_out_deg >= total - eps:
        raise InvalidInputError(f"--lead-in {lead_in_deg:g}° + --lead-out {lead_out_deg:g}° is not shorter than the run's "
                                f"recorded arc of {total:.1f}°: trimming would leave nothing; give shorter leads")
    keep = (swept >= lead_in_deg - eps) & (swept <= total - lead_out_deg + eps)
    n_lead = int(len(points) - keep.sum())
    pts = points[keep]
    sw = swept[keep] - (swept[keep][0] if keep.any() else 0.0)
    over, passes, at = 0, None, None
    step = float(np.median(np.diff(sw))) if len(sw) > 1 else 0.0     # the sampling step (deg)
    if arc_deg is not None and len(pts):
        if arc_deg >= 360.0:   # the full circle: the samples back at its start's angle (within their noise) are not kept
            r_mid = float(np.median(np.hypot(*(pts - np.asarray(center, float)).T)))
            half = max(eps, min(step / 2.0, float(np.degrees(OVERLAP_SIGMAS * sample_noise(pts, center) / r_mid))))
            if len(sw) > 2 and sw[-1] >= 720.0 - 2 * step - eps:
                k = int(np.argmax(sw >= 360.0 - half))
                first_out = np.ceil((sw[-1] - 360.0 + step / 2.0) * 10.0 - 1e-6) / 10.0   # cut between samples
                second_in = np.floor((sw[k] - step / 2.0) * 10.0 + 1e-6) / 10.0
                raise InvalidInputError(
                    f"{name + ' run: ' if name else ''}recorded {sw[-1]:.1f}°: it goes round twice (samples 1-{k} and "
                    f"{k + 1}-{len(sw)}{' after the lead-in/out' if n_lead else ''}), two tests in one file (the "
                    f"second after a blank line?) or one recorded twice; evaluate one revolution: --lead-out "
                    f"{first_out + lead_out_deg:g} keeps the first, --lead-in {second_in + lead_in_deg:g} the second "
                    f"(or give each test in a file of its own)")
            within = sw < arc_deg - half
            passes = compare_passes(pts, center, sw, arc_deg, half)
            if overrun == "auto" and passes is not None and passes["steady"] == "end":
                within = sw > sw[-1] - arc_deg + half
        else:
            within = sw <= arc_deg + tol
        over = int(len(pts) - within.sum())
        if over:
            at = "end" if within[0] else "start"
        pts, sw = pts[within], sw[within]
        sw = sw - sw[0] if len(sw) else sw
    report = {"recorded_arc_deg": total, "lead_removed_points": n_lead, "lead_in_deg": float(lead_in_deg),
              "lead_out_deg": float(lead_out_deg), "overrun_trimmed_points": over, "overrun_at": at,
              "sampling_step_deg": step, "passes": passes, "evaluated_arc_deg": float(sw[-1]) if len(sw) else 0.0}
    return pts, report


def overrun_text(report: dict, name: str = "", arc_deg: float = 360.0) -> tuple[str | None, str | None]:
    """(the note naming which end of a run was trimmed, a warning when its two passes over the same angles
    differ beyond the noise, or None) for a report of :func:`trim`. The note: 'the last 179 points (overrun
    beyond 360°)'; the warning: how much they differ, where, what was kept and the option that keeps the other."""
    over, at, ps = report["overrun_trimmed_points"], report["overrun_at"], report["passes"]
    lead = report["lead_removed_points"]
    if not (over or lead):
        return None, None
    who = f"{name} run: " if name else ""
    what = (f"the {'first' if at == 'start' else 'last'} {over} point(s) ("
            f"{'a lead-in: its first pass differs' if at == 'start' else f'overrun beyond {arc_deg:g}°'}) trimmed"
            if over else "no overrun trimmed")
    note = (f"{who}recorded {report['recorded_arc_deg']:.1f}°, {lead} lead-in/out point(s) removed, {what}; "
            f"{report['evaluated_arc_deg']:.1f}° evaluated")
    if not (ps and ps["differ"]):
        return note, None
    e = ps["overlap_deg"]
    extra = report["recorded_arc_deg"] - arc_deg      # the leads that leave one revolution
    half = report["sampling_step_deg"] / 2.0      # cut half a step beyond, not at, the angle of a sample
    lead_in, lead_out = (np.ceil((extra + half - v) * 10.0 - 1e-6) / 10.0
                         for v in (report["lead_out_deg"], report["lead_in_deg"]))
    noise = np.sqrt(2.0) * ps["noise_mm"]
    limit = (f"more than {OVERLAP_SIGMAS:g} x the {noise * 1e3:.2f} µm noise of a difference: "
             f"{ps['limit_mm'] * 1e3:.2f} µm" if OVERLAP_SIGMAS * noise >= OVERLAP_MIN_MM else
             f"more than {OVERLAP_MIN_MM * 1e3:g} µm, a ballbar's resolution")
    same = (f"{who}its first {e:.1f}° and its last {e:.1f}° cover the same angles and differ by up to "
            f"{ps['max_difference_mm'] * 1e3:.2f} µm ({limit})")
    if ps["steady"] == "start":   # what was trimmed anyway: said in the note
        return note + (f" (its two passes over the first {e:.1f}° differ only near the run's end: a lead-out "
                       "transient)"), None
    if ps["steady"] == "end":
        if at == "start":
            return note, (f"{same}, most at its start and within the limit where the overlap ends: a lead-in "
                          f"transient; the first {over} point(s) trimmed instead of the last (--lead-out {lead_out:g} "
                          f"keeps them)")
        return note, (f"{same}, most at its start and within the limit where the overlap ends: a lead-in transient? "
                      f"give --lead-in {lead_in:g}")
    both = ps["at_start"] is not None and min(ps["at_start"], ps["at_end"]) > ps["limit_mm"]
    where = " at both ends of the overlap (a drift over the revolution, or transients at both ends?)" if both else ""
    return note, (f"{same}{where}; the last {over} point(s) trimmed as overrun: if the run starts with a "
                  f"lead-in transient, give --lead-in {lead_in:g} (if it ends with a lead-out, --lead-out {lead_out:g})")


def check_pair(runs: dict, center, *, as_given: bool = False) -> tuple[dict, list]:
    """``runs`` = {'cw': points, 'ccw': points} as labelled by the user: returns them in the right slots
    and the warnings. Identical runs are refused; both runs in one direction are refused; a swapped pair
    is swapped back with a warning (``as_given`` keeps the labels and only warns)."""
    cw, ccw = runs["cw"], runs["ccw"]
    if cw.shape == ccw.shape and np.array_equal(cw, ccw):
        raise InvalidInputError("the CW and CCW runs are the same data (the same file twice?); give one run in "
                                "each direction")
    d_cw, s_cw = direction(cw, center)
    d_ccw, s_ccw = direction(ccw, center)
    warnings = []
    if d_cw == d_ccw:
        msg = (f"both runs go {d_cw.upper()} by their point order (swept {s_cw:+.0f} and {s_ccw:+.0f} deg); "
               "a circular test needs one CW (G02) and one CCW (G03) run")
        if not as_given:
            raise InvalidInputError(msg + " (--as-given to evaluate anyway)")
        warnings.append(msg + "; evaluated as labelled (--as-given)")
        return {"cw": cw, "ccw": ccw}, warnings
    if d_cw == "ccw":
        if as_given:
            warnings.append("the run given as CW goes CCW by its point order (and the other CW); evaluated as labelled "
                            "(--as-given): backlash and servo mismatch have the wrong sign")
            return {"cw": cw, "ccw": ccw}, warnings
        warnings.append("the runs were given in the wrong order (the first goes CCW, the second CW by their point "
                        "order); swapped back (--as-given to keep the labels)")
        return {"cw": ccw, "ccw": cw}, warnings
    return {"cw": cw, "ccw": ccw}, warnings


def check_nominal(fitted_center, fitted_radius, nominal_center, nominal_radius) -> list:
    """Warnings when the nominal centre or radius is far from the data's least-squares circle."""
    out = []
    lim = NOMINAL_WARN_FRACTION * nominal_radius
    if nominal_center is not None:
        off = float(np.hypot(*(np.asarray(fitted_center) - np.asarray(nominal_center, float))))
        if off > lim:
            out.append(f"the nominal centre ({nominal_center[0]:.4f}, {nominal_center[1]:.4f}) mm is {off * 1e3:.1f} µm "
                       f"from the data's fitted centre ({fitted_center[0]:.4f}, {fitted_center[1]:.4f}) mm "
                       f"(more than {NOMINAL_WARN_FRACTION:g} R = {lim * 1e3:.0f} µm): F about it is dominated by the "
                       "set-up; check --nominal-center")
    dr = float(fitted_radius - nominal_radius)
    if abs(dr) > lim:
        out.append(f"the nominal radius {nominal_radius:.4f} mm differs from the data's fitted radius "
                   f"{fitted_radius:.4f} mm by {dr * 1e3:+.1f} µm (more than {NOMINAL_WARN_FRACTION:g} R = "
                   f"{lim * 1e3:.0f} µm): F is dominated by it; check --nominal-radius (and the ballbar's calibration)")
    return out
