"""Pitch-error compensation tables from an ISO 230-2 positioning test, and writers for controllers.

The table (``compensation_table``) is one equally spaced grid for every format:

* it is anchored at the machine's **reference point** R (a grid point; default: position 0 when the
  measured travel contains it, else the end of the travel nearer 0; it may lie outside the travel, where the
  deviation is held at the nearer target's, ``outside_reference``) and **covers the measured travel** and R:
  its first point is at or before the first target, its last point at or after the last target. Without
  ``interval`` the step is chosen so that the longer side of the travel from R is a whole number of steps
  (within 0.001 mm, the step being a multiple of 0.001 mm, no coarser than the smallest target spacing);
  with ``interval`` the table goes on to the first grid point at or beyond each end, and must reproduce the
  curve at the targets as each format's controller applies it (``APPLIED``: linearly, or stepwise for FANUC;
  ``_check_represents``: a coarser step is refused).
  Beyond the targets the values are held at those of the end targets (the model is never extrapolated); the
  header of every file says what range it covers and how far it was extended.
* values are the mean bidirectional deviation x(P) (ISO 230-2: deviation = reached - target; the mean of
  the up and down curves, from the GLS polynomials or linearly interpolated between the mean deviations
  at the targets) **relative to its value at R**, so that every format holds 0 at the reference point
  (SINUMERIK 808D Function Manual 01/2017 p. 106: "the compensation value at the reference point should be
  zero"; FANUC: the pitch error is counted from the reference position). A constant offset only moves
  the axis' zero, which the reference point defines anyway.
* ``compensation_mm`` = -(x(P) - x(R)): what a controller must add to the commanded position. Each writer
  converts it to its controller's sign (see the writer's docstring).
* the mean reversal value B = mean over the targets of (x_up - x_down) (ISO 230-2:2014 sec. 2.17, exactly
  the figure of the ISO table) is not in the table: controllers take the backlash as a separate parameter,
  and the header says what to enter (-B; see ``_backlash_line``).
* ``per_direction`` (``--compensation-directions both``, a bidirectional test): a table per direction as well,
  compensation_up_mm / compensation_down_mm = -(x_up / x_down(P) - x(R)), which hold the reversal B_i at every point
  (no backlash with them): for a reversal that varies along the travel, which the mean table with one backlash
  leaves as (B_i - B)/2 in each direction. csv columns, a FANUC bidirectional pitch-error tape; no SINUMERIK file.

Formats (``WRITERS``; each checks the axis name against its grammar and its controller's limits, and
refuses what does not fit with one line saying what to change): ``csv``, ``siemens-eec``, ``fanuc-pitch``.
The simulated controllers in the tests read each file with a strict parser of its grammar, apply it by
the manual's rule and must at least halve the measured positioning error. docs/compensation.md has the
formats, signs, limits and citations.
"""
from __future__ import annotations

import math
import re

import numpy as np

from methods import InvalidInputError
from methods.positioning.model import evaluate_band

NM = 1e-6                 # grid positions are whole multiples of 1e-6 mm (printed exactly with 6 decimals)
AUTO_QUANTUM = 1000       # an automatic step is a multiple of 0.001 mm (1000 x 1e-6 mm)
INCH_MM = 25.4
MAX_POINTS = 100_000      # a generic table longer than this is certainly a mistaken --interval
#: a compensation value beyond this share of the measured travel (and beyond VALUE_FLOOR_MM) is not a machine
#: axis' pitch error but a unit mistake: the positioning reader's plausibility bound (0.1 % of the travel, at
#: least 0.1 mm). Real pitch errors are tens of µm per metre; even a transport-class rolled ball screw deviates
#: by about 0.2 mm per 300 mm, while µm read as mm is 1000 times the error.
VALUE_PER_TRAVEL = 1e-3
VALUE_FLOOR_MM = 0.1
#: a backlash entry beyond this is not a drive to compensate but one to repair (ball-screw drives have a few
#: µm to tens of µm of lost motion); µm read as mm turns 4 µm into 4 mm
BACKLASH_LIMIT_MM = 0.5
AXIS = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,31}")
NOT_GIVEN = "not given"      # the axis name in a CSV / FANUC header when none was given


class CompensationError(InvalidInputError):
    """A compensation table that does not fit the controller (too many points, a field out of range)."""


class _Required:
    """The default of a writer's ``axis``: not given (a controller table is for one axis, which the caller names)."""

    def __repr__(self) -> str:
        return "<required>"


AXIS_REQUIRED = _Required()


def _exact(q: int) -> str:
    """A position of q x 1e-6 mm written exactly with 6 decimals (no float rounding)."""
    sign = "-" if q < 0 else ""
    q = abs(int(q))
    return f"{sign}{q // 1_000_000}.{q % 1_000_000:06d}"


def _fixed6(x: float) -> str:
    """A value with 6 decimals, never '-0.000000'."""
    s = f"{x:.6f}"
    return "0.000000" if float(s) == 0.0 else s


def _ceil_div(a: int, b: int) -> int:
    return -((-a) // b)


def _grid_range(ref_q: int, lo_q: int, hi_q: int, step_q: int) -> tuple[int, int]:
    """(k_lo, k_hi): the grid R + k step (k_lo <= 0 <= k_hi) from the first point at or before the first target
    to the first at or after the last, always holding R, also when R lies outside the measured travel."""
    return min(0, -_ceil_div(ref_q - lo_q, step_q)), max(0, _ceil_div(hi_q - ref_q, step_q))


def compensation_table(res, data, *, interval: float | None = None, source: str = "model",
                       reference_mm: float | None = None, formats=(), quantum_q: int = AUTO_QUANTUM,
                       per_direction: bool = False):
    """The table (see the module docstring) as a DataFrame with columns position_mm, deviation_mm,
    deviation_up_mm, deviation_down_mm, compensation_mm and the grid in ``.attrs``. ``res`` is a
    positioning.gls_polynomial result (or positioning.iso230_2 with ``source='mean'``), ``data`` its input.
    ``formats``: the formats it is written in; the coarse-interval guard checks the table as each one's controller
    applies it (:data:`APPLIED`; none given: linearly). ``quantum_q``: an automatic or suggested step is a multiple
    of it (x 1e-6 mm; 0.001 mm, or 0.0001 in = 2540 for a FANUC inch machine, whose 3624 counts 0.0001 in).
    ``per_direction`` (a bidirectional test only): also the columns compensation_up_mm = -(x_up(P) - x(R)) and
    compensation_down_mm = -(x_down(P) - x(R)), a table per direction relative to the mean deviation at R (their
    mean is compensation_mm), from the model's curve of each direction or each direction's means at the targets;
    the interval guard then checks every curve written (mean, up, down)."""
    import pandas as pd  # loaded when a table is made (the fitbench command stays light)
    P = np.asarray(data.targets, float)
    if P.size < 2 or not np.all(np.diff(P) > 0):
        raise InvalidInputError("a compensation table needs at least two targets in increasing order")
    first, last = float(P[0]), float(P[-1])
    if source not in ("model", "mean"):
        raise InvalidInputError(f"--compensation-from must be 'model' or 'mean', got {source!r}")
    if source == "model" and not getattr(res, "polynomial", None):
        raise InvalidInputError("--compensation-from model needs the GLS polynomial (positioning.gls_polynomial)")
    if per_direction and len(data.directions) != 2:
        raise InvalidInputError(one_direction_refusal(data))
    if reference_mm is None:
        reference_mm = 0.0 if first <= 0.0 <= last else (first if abs(first) <= abs(last) else last)
    ref = float(reference_mm)
    if not np.isfinite(ref):
        raise InvalidInputError(f"the reference point must be a finite position in mm, got {reference_mm!r}")
    ref_q = int(round(ref / NM))
    lo_q, hi_q = math.floor(first / NM + 1e-3), math.ceil(last / NM - 1e-3)
    if interval is None:
        spacing = float(np.min(np.diff(P)))
        longest = max(hi_q - ref_q, ref_q - lo_q)
        steps = max(1, math.ceil(longest * NM / spacing - 1e-9))
        step_q = _ceil_div(_ceil_div(longest, steps), quantum_q) * quantum_q
    else:
        if not (np.isfinite(interval) and interval > 0):
            raise InvalidInputError(f"--interval must be a positive length in mm, got {interval!r}")
        step_q = int(round(interval / NM))
        if step_q < 1 or abs(step_q * NM - interval) > 1e-9 * max(1.0, interval):
            raise InvalidInputError(f"--interval {interval!r} mm is not a whole number of 0.000001 mm; "
                                    "round it to 6 decimals")
    k_lo, k_hi = _grid_range(ref_q, lo_q, hi_q, step_q)
    n = k_hi - k_lo + 1
    if n > MAX_POINTS:
        raise CompensationError(f"--interval {step_q * NM:g} mm gives {n} points over {last - first:g} mm "
                                f"(at most {MAX_POINTS}); choose a coarser interval")
    pos_q = ref_q + step_q * np.arange(k_lo, k_hi + 1, dtype=np.int64)
    pos = pos_q * NM
    dirs = data.directions
    curves = _curves(res, data, source, pos)
    up = curves.get("up", np.full_like(pos, np.nan))
    down = curves.get("down", np.full_like(pos, np.nan))
    mean = np.mean([curves[d] for d in dirs], axis=0)
    rules = sorted({APPLIED.get(f, "linear") for f in formats} or {"linear"})
    which = ("mean", "up", "down") if per_direction else ("mean",)
    tables = {"mean": mean, "up": up, "down": down}
    if interval is not None:
        _check_represents(res, data, source, pos, tables, step_q * NM, ref_q, lo_q, hi_q, rules, formats, quantum_q,
                          which)
    else:
        _warn_if_missed(res, data, source, pos, tables, step_q * NM, -k_lo, rules, formats, which)
    at_ref = float(mean[-k_lo])
    table = pd.DataFrame({"position_mm": pos, "deviation_mm": mean, "deviation_up_mm": up,
                          "deviation_down_mm": down, "compensation_mm": -(mean - at_ref)})
    if per_direction:
        table["compensation_up_mm"] = -(up - at_ref)
        table["compensation_down_mm"] = -(down - at_ref)
    backlash = (float(np.mean(data.up.mean(axis=1) - data.down.mean(axis=1))) if len(dirs) == 2 else float("nan"))
    table.attrs.update(interval_mm=step_q * NM, step_q=int(step_q), first_q=int(pos_q[0]), last_q=int(pos_q[-1]),
                       reference_q=ref_q, reference_index=int(-k_lo), measured_mm=(first, last), source=source,
                       deviation_at_reference_mm=at_ref, backlash_mm=backlash, directions=tuple(dirs),
                       direction_given=bool(getattr(data, "direction_given", True)), thermal_note=thermal_line(data),
                       quantum_q=int(quantum_q), per_direction=bool(per_direction))
    return table


def one_direction_refusal(data) -> str:
    """The one line refusing per-direction tables for a unidirectional test."""
    d = data.directions[0] if data.directions else "one"
    return (f"--compensation-directions both needs a bidirectional test and this one has only the "
            f"{d if getattr(data, 'direction_given', True) else 'one'} direction: drop --compensation-directions "
            "(its table is that direction's)")


#: a table given by --interval must reproduce the curve at the targets, as each requested format's controller applies
#: it, within this share of the curve's span (or REPRESENT_FLOOR_MM); a default table that does not is warned about
#: (the model's default table misses by about 1 %)
REPRESENT_SHARE = 0.1
REPRESENT_FLOOR_MM = 0.0005
#: how each format's controller applies the table between its points. SINUMERIK LEC: linear interpolation between
#: the interpolation points (840D sl Function Manual 01/2008 p. 355); the CSV's reader is told the same. FANUC pitch
#: error compensation: stepwise, one increment per section output as the axis passes the point, so between two
#: points the compensation stays at the value of the point on the reference position's side (0i-PB parameter manual
#: B-63980EN/01 p. 99-100: "the compensation value is output at the compensation position No. corresponding to each
#: section"; the write_fanuc_pitch docstring)
APPLIED = {"csv": "linear", "siemens-eec": "linear", "fanuc-pitch": "stepwise"}
HOW_APPLIED = {"linear": "interpolated linearly between its points as the SINUMERIK does",
               "stepwise": "applied stepwise as the FANUC does, each point's value held over the interval after it "
                           "seen from the reference point"}


def _curves(res, data, source: str, pos) -> dict:
    """{direction: deviation at ``pos``} from the model or the means at the targets, never extrapolated: beyond
    the first / last target the value there is held (a cubic extrapolated 4.6 m gave 7.4 mm)."""
    P = np.asarray(data.targets, float)
    x = np.clip(pos, P[0], P[-1])
    if source == "model":
        return {d: evaluate_band(res.polynomial[d], x)[0] for d in data.directions}
    return {d: np.interp(x, P, res.per_target[f"mean_{d}"]) for d in data.directions}


def applied(pos, values, x, rule: str, ref_index: int):
    """The table (``values`` at the grid ``pos``) at positions ``x`` as a controller applies it: ``linear``
    interpolation (the end values beyond), or ``stepwise`` (FANUC): at x the value of the last grid point reached
    from the reference point pos[ref_index], the end values beyond."""
    if rule == "linear":
        return np.interp(x, pos, values)
    step = pos[1] - pos[0] if len(pos) > 1 else 1.0
    t = (np.asarray(x, float) - pos[ref_index]) / step
    k = np.trunc(t + np.sign(t) * 1e-9).astype(np.int64) + ref_index    # a point reached exactly counts (1e-9 step)
    return np.asarray(values)[np.clip(k, 0, len(pos) - 1)]


def _miss(res, data, source: str, pos, values, rule: str = "linear", ref_index: int = 0,
          curve: str = "mean") -> tuple[float, float]:
    """(largest miss at the targets of the table ``values`` of ``curve`` (mean, up or down) as a controller applies it
    by ``rule`` (:func:`applied`), the span of that curve there), mm."""
    P = np.asarray(data.targets, float)
    curves = _curves(res, data, source, P)
    truth = np.mean([curves[d] for d in data.directions], axis=0) if curve == "mean" else curves[curve]
    return float(np.max(np.abs(applied(pos, values, P, rule, ref_index) - truth))), float(np.ptp(truth))


def _worst_miss(res, data, source, pos, tables, ref_index, rules, which=("mean",)):
    """(miss, span, rule, curve) of the rule and curve under which the table misses the curve at the targets most,
    relative to the bound (``tables``: {curve: values}; a bare array is the mean table)."""
    if not isinstance(tables, dict):
        tables = {"mean": tables}
    found = [(*_miss(res, data, source, pos, tables[c], r, ref_index, c), r, c) for r in rules for c in which]
    return max(found, key=lambda f: (f[0] / max(REPRESENT_SHARE * f[1], REPRESENT_FLOOR_MM), f[0], f[1], f[2]))


def _curve_name(curve: str) -> str:
    """'' for the mean table (its messages as they were), ' of the up direction' for a direction's."""
    return "" if curve == "mean" else f" of the {curve} direction"


def _formats_of(rule: str, formats) -> str:
    names = [f for f in formats if APPLIED.get(f, "linear") == rule]
    return f" for {', '.join(names)}" if names else ""


def _warn_if_missed(res, data, source, pos, mean, step, ref_index=0, rules=("linear",), formats=(),
                    which=("mean",)) -> None:
    """The default table is not refused (no step is asked for), but a table that misses the curve at the targets
    beyond the bound of ``_check_represents`` is warned about: means at irregular targets with a periodic error
    are a broken line that an equally spaced grid cannot pass through (up to 36 % of the span)."""
    import warnings
    miss, span, rule, curve = _worst_miss(res, data, source, pos, mean, ref_index, rules, which)
    if miss > max(REPRESENT_SHARE * span, REPRESENT_FLOOR_MM):
        what = "the model" if source == "model" else "the means"
        warnings.warn(f"the compensation table{_curve_name(curve)}{_formats_of(rule, formats)} (every {step:g} mm, equally spaced as the "
                      f"controllers require), {HOW_APPLIED[rule]}, misses {what} at the targets by up to {miss * 1e3:.3g} µm of the {span * 1e3:.3g} µm the curve spans: "
                      "the controller will not reproduce the measured curve there; a finer --interval follows it "
                      "closer", UserWarning, stacklevel=3)


def _check_represents(res, data, source, pos, mean, step, ref_q, lo_q, hi_q, rules=("linear",), formats=(),
                      quantum_q: int = AUTO_QUANTUM, which=("mean",)) -> None:
    """Refuse an ``--interval`` whose table, as the controller interpolates it, misses the measured curve at the
    targets by more than REPRESENT_SHARE of its span (a coarse step: --interval 700 left 15.6 of 22.6 µm),
    naming the coarsest step of the form travel / k that would do."""
    P = np.asarray(data.targets, float)
    ref_index = int(round((ref_q * NM - pos[0]) / step))
    miss, span, rule, curve = _worst_miss(res, data, source, pos, mean, ref_index, rules, which)
    tol = max(REPRESENT_SHARE * span, REPRESENT_FLOOR_MM)
    travel = float(P[-1] - P[0])
    if miss <= tol and step <= travel:
        return
    spacing = np.diff(P)
    ok = None
    for k in range(1, 20 * P.size + 1):       # candidate steps, coarse to fine (a few hundred small tables at most)
        q = math.ceil(travel / k / NM / quantum_q - 1e-6) * quantum_q     # rounded up: the grid reaches the last
        # target at its k-th step (within k quanta, k x 0.001 mm), not one step beyond it
        if q <= 0 or q * NM >= step:
            continue
        k_lo, k_hi = _grid_range(ref_q, lo_q, hi_q, q)
        g = (ref_q + q * np.arange(k_lo, k_hi + 1, dtype=np.int64)) * NM
        cv = _curves(res, data, source, g)
        m = {"mean": np.mean(list(cv.values()), axis=0), **cv}
        worst = _worst_miss(res, data, source, g, m, -k_lo, rules, which)
        if worst[0] <= max(REPRESENT_SHARE * worst[1], REPRESENT_FLOOR_MM):
            ok = q * NM
            break
    what = "the model" if source == "model" else "the means"
    why = (f"longer than the measured travel ({travel:g} mm)" if step > travel else
           f"too coarse: the table{_curve_name(curve)}{_formats_of(rule, formats)}, {HOW_APPLIED[rule]}, misses {what} at the "
           f"targets by up to {miss * 1e3:.3g} µm of the {span * 1e3:.3g} µm the curve spans (at most "
           f"{tol * 1e3:.3g} µm, {REPRESENT_SHARE:.0%})")
    advice = (f"give --interval {ok:g} or finer" if ok else "give a finer --interval")
    raise CompensationError(f"--interval {step:g} mm is {why}; {advice} (the targets are {spacing.min():g} to "
                            f"{spacing.max():g} mm apart), or leave it out for a table at the target spacing")


# --------------------------------------------------------------------------------------------- header
def _header(table, axis: str, values: str, backlash: str | None = None) -> list[str]:
    """The lines every format carries (ASCII, without the comment mark): what the table covers, the
    reference point, the sign of the values, the backlash to enter and the verification run."""
    a = table.attrs
    first, last = a["measured_mm"]
    lo, hi = a["first_q"] * NM, a["last_q"] * NM
    ext = (f"values beyond the targets, {first - lo:.6g} mm before the first and {hi - last:.6g} mm after the last, "
           + ("held at the model's values at the end targets" if a["source"] == "model"
              else "held at the end targets' means")
           if (lo < first - 1e-9 or hi > last + 1e-9) else "no point beyond the targets")
    what = ("deviation of each direction and the mean bidirectional deviation" if a.get("per_direction") else
            "mean bidirectional deviation" if len(a["directions"]) == 2
            else f"deviation of the one direction measured, "
                 f"{a['directions'][0] if a.get('direction_given', True) else 'direction not given'},")
    return ([a["warning"]] if a.get("warning") else []) + ([a["thermal_note"]] if a.get("thermal_note") else []) + \
        ([a["reversal_note"]] if a.get("reversal_note") else []) + [
            f"fitbench pitch-error compensation table, axis {axis}, from the {a['source']} of the {what}",
            f"covers {_exact(a['first_q'])} to {_exact(a['last_q'])} mm: {len(table)} points every "
            f"{_exact(a['step_q'])} mm; measured travel {first:.6g} to {last:.6g} mm; {ext}",
            f"reference point at {_exact(a['reference_q'])} mm holds 0: deviations taken relative to the "
            f"{a['deviation_at_reference_mm'] * 1e3:.3f} um there" + (f"; {outside_reference(table)}"
                                                                      if outside_reference(table) else ""),
            f"values: {values}",
            backlash or _backlash_line(table),
            "check the result with a verification run after loading"]


def outside_reference(table) -> str | None:
    """What the table assumes when the reference point R lies outside the measured travel (ISO 230-2 leaves the
    travel ends out, where the reference point of a machine usually is), or None: nothing was measured between R
    and the nearer end target, so the deviation there is held at that target's value (the model is not
    extrapolated) and the table holds 0 from R to that target; FANUC anchors its sections at R (0i-PB parameter
    manual B-63980EN/01 p. 99-100), SINUMERIK holds its end values beyond MIN / MAX."""
    a = table.attrs
    first, last = a["measured_mm"]
    ref = a["reference_q"] * NM
    if first - 1e-9 <= ref <= last + 1e-9:
        return None
    gap, end, side = (first - ref, first, "before the first") if ref < first else (ref - last, last, "after the last")
    held = "the model's value" if a["source"] == "model" else "the mean"
    return (f"the reference point lies {gap:.6g} mm {side} target, outside the measured travel: nothing was measured "
            f"from {min(ref, end):.6g} to {max(ref, end):.6g} mm, where the deviation is held at {held} at the "
            f"{end:.6g} mm target (not extrapolated), so the table holds 0 from the reference point to that target")


def _backlash_line(table) -> str:
    """The mean reversal value B of ISO 230-2 (x_up - x_down, mean over the targets) and the backlash to
    enter: -B. A normal backlash (the axis travels too little after a reversal) makes B negative and is
    entered positive; SINUMERIK 808D Parameter Manual 08/2013, MD32450 $MA_BACKLASH: "positive, if the
    encoder is leading the machine part (normal situation); negative, if the encoder is behind the
    machine part"; FANUC 0i-C Parameter Manual B-64120EN/01 p. 116, parameter 1851 (detection units,
    -9999 ... +9999): "the positive or negative direction for compensating values is the direction of
    movement", so a positive value adds travel after a reversal, likewise."""
    b = table.attrs["backlash_mm"]
    if not np.isfinite(b):
        return "mean reversal value B unknown, unidirectional test: no backlash figure"
    enter = -b
    kind = ("normal backlash: the axis travels too little after a reversal" if enter > 0 else
            "negative backlash: the axis travels too far after a reversal" if enter < 0 else "no backlash")
    return (f"mean reversal value B = {b * 1e3:.3f} um, ISO 230-2: mean of x_up - x_down over the targets; "
            f"enter the backlash as -B = {enter * 1e3:.3f} um, {kind}; SINUMERIK MD32450 $MA_BACKLASH in mm, "
            f"FANUC 1851 in detection units; not in this table")


def check_axis(axis, fmt: str) -> str:
    """An axis name of the format's grammar: a letter then letters, digits or '_' (at most 32), as
    SINUMERIK machine-axis names (MD10000 $MN_AXCONF_MACHAX_NAME_TAB, e.g. X1) are; nothing that could
    end a comment, a line or an index of the file."""
    if not isinstance(axis, str) or not AXIS.fullmatch(axis):
        raise InvalidInputError(f"--axis {axis!r} is not a valid axis name for {fmt}: use a letter followed by "
                                "letters, digits or '_' (at most 32), e.g. X1")
    return axis


# --------------------------------------------------------------------------------------------- writers
def write_csv(table, axis: str | None = "X") -> str:
    """Generic CSV: ``#`` header lines, then one row per grid point with the columns position_mm,
    deviation_mm, deviation_up_mm, deviation_down_mm (ISO 230-2 deviations as measured; empty for a
    direction not measured) and compensation_mm = -(deviation_mm - deviation at the reference point), the
    value to **add to the commanded position** (a controller that adds it reaches the target). Numbers
    with 6 decimals in mm, never -0.000000. ``axis`` None: the header says 'axis not given'.

    A per-direction table (``compensation_table(per_direction=True)``) adds compensation_up_mm and
    compensation_down_mm, what to add in travel in the positive / negative direction: minus each direction's
    deviation relative to the mean deviation at the reference point, so that they hold the reversal B_i at every
    point (their mean is compensation_mm); with them no backlash is entered, with compensation_mm alone -B."""
    axis = NOT_GIVEN if axis is None else check_axis(axis, "csv")
    a = table.attrs
    names = ["deviation_mm", "deviation_up_mm", "deviation_down_mm", "compensation_mm"]
    values = "compensation_mm is added to the commanded position; it is minus the deviation relative to the reference point"
    backlash = None
    if a.get("per_direction"):
        names += ["compensation_up_mm", "compensation_down_mm"]
        values += ("; compensation_up_mm / compensation_down_mm are added in travel in the positive / negative "
                   "direction: minus that direction's deviation relative to the mean deviation at the reference point, "
                   "a table per direction that holds the reversal B_i at every point")
        b = a["backlash_mm"]
        backlash = (f"mean reversal value B = {b * 1e3:.3f} um, ISO 230-2: mean of x_up - x_down over the targets; with "
                    f"compensation_mm (the mean) enter the backlash as -B = {-b * 1e3:.3f} um; with compensation_up_mm "
                    "and compensation_down_mm (a table per direction) enter none: they hold the reversal at every point")
    lines = ["# " + h for h in _header(table, axis, values, backlash)]
    lines.append("position_mm," + ",".join(names))
    cols = [table[c].to_numpy() for c in names]
    for k in range(len(table)):
        cells = [_exact(a["first_q"] + k * a["step_q"])]
        cells += ["" if not np.isfinite(c[k]) else _fixed6(c[k]) for c in cols]
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"


SINUMERIK_MAX_POINTS = 200
#: why no SINUMERIK table per direction is written (docs/compensation.md): the LEC table ($AA_ENC_COMP) has one curve;
#: direction-dependent compensation is the CEC tables' $AN_CEC_DIRECTION (K3 Function Manual 03/2013 sec. 4.4, p. 249), whose
#: sign relative to the LEC table and the backlash MD32450 were not confirmed here from a manual page
SIEMENS_PER_DIRECTION = ("siemens-eec: a SINUMERIK LEC table ($AA_ENC_COMP) holds one curve for both directions; "
                         "direction-dependent compensation goes through CEC tables ($AN_CEC_DIRECTION), which fitbench "
                         "does not write: write siemens-eec without --compensation-directions both (the mean table with "
                         "a backlash), or the per-direction csv and enter its columns by hand")


def write_siemens_eec(table, axis: str = AXIS_REQUIRED, max_points: int = SINUMERIK_MAX_POINTS) -> str:
    """SINUMERIK leadscrew / measuring-system error compensation (LEC/MSEC) as a part program
    ``%_N_AX_EEC_INI``, ``CHANDATA(1)``, ``$AA_ENC_COMP[0,N,AXIS]`` (mm), ``$AA_ENC_COMP_STEP``,
    ``_MIN``, ``_MAX``, ``_IS_MODULO``, ``M17`` (SINUMERIK Function Manual Extended Functions, K3
    Compensation, sec. 4.4.2, 03/2013, 6FC5397-1BP40-3BA1: layout and example).

    Sign: "A positive compensation value causes the corresponding machine axis to move in the negative
    direction" (same manual sec. 4.4.2.1; SINUMERIK 808D Function Manual 01/2017 p. 106), the value
    modifying the actual position value. An axis that reaches target + x(P) must move by -x(P), so the
    table holds **+(x(P) - x(R))**, the ISO 230-2 deviation relative to the reference point.

    Limits: N = 0 ... MD38000 $MA_MM_ENC_COMP_MAX_POINTS - 1; the 808D allows "up to 200 interpolation
    points (N = 0...199)" (808D Function Manual p. 106), the default ``max_points``; an 840D with a larger
    MD38000 may pass it. The controller takes the table's end as MIN + k STEP (840D sl Function Manual
    01/2008 p. 355), so STEP, MIN and MAX are printed exactly with MIN + STEP (n - 1) = MAX. The value at
    the reference point is 0 (808D p. 106). Values beyond MIN / MAX stay at the first / last value.

    ``axis`` (required): the machine-axis name the entries compensate (MD10000 $MN_AXCONF_MACHAX_NAME_TAB, e.g.
    X1); a missing or None axis is refused (:class:`CompensationError`), as ``--axis`` is on the command line."""
    if axis is AXIS_REQUIRED or axis is None:
        raise CompensationError("siemens-eec: a SINUMERIK table names the machine axis it compensates "
                                "($AA_ENC_COMP[0,N,AXIS], MD10000 $MN_AXCONF_MACHAX_NAME_TAB) and no axis is given: "
                                "give axis=NAME, e.g. write_siemens_eec(table, axis='X1')")
    axis = check_axis(axis, "siemens-eec")
    if table.attrs.get("per_direction"):
        raise CompensationError(SIEMENS_PER_DIRECTION)
    n = len(table)
    if n > max_points:
        raise CompensationError(f"siemens-eec: {n} points do not fit the controller's {max_points} "
                                f"(MD38000 MM_ENC_COMP_MAX_POINTS); choose --interval of at least "
                                f"{_exact(_ceil_div(table.attrs['last_q'] - table.attrs['first_q'], max_points - 1))} mm")
    a = table.attrs
    out = ["%_N_AX_EEC_INI"]
    out += ["; " + h for h in _header(table, axis, "$AA_ENC_COMP = +(deviation - deviation at the reference point) "
                                                   "in mm: a positive value moves the axis in the negative direction")]
    out += [f"; MD38000 $MA_MM_ENC_COMP_MAX_POINTS of {axis} must be >= {n}; MD32700 ENC_COMP_ENABLE = 0 "
            "while loading"]
    if np.isfinite(a["backlash_mm"]):
        out.append(f"; backlash: MD32450 $MA_BACKLASH[0] of {axis} = {_fixed6(-a['backlash_mm'])} mm, i.e. -B")
    out.append("CHANDATA(1)")
    comp = table.deviation_mm.to_numpy() - a["deviation_at_reference_mm"]
    out += [f"$AA_ENC_COMP[0,{i},{axis}]={_fixed6(c)}" for i, c in enumerate(comp)]
    out += [f"$AA_ENC_COMP_STEP[0,{axis}]={_exact(a['step_q'])}", f"$AA_ENC_COMP_MIN[0,{axis}]={_exact(a['first_q'])}",
            f"$AA_ENC_COMP_MAX[0,{axis}]={_exact(a['last_q'])}", f"$AA_ENC_COMP_IS_MODULO[0,{axis}]=0", "M17"]
    return "\n".join(out) + "\n"


FANUC_POINTS = 1024            # pitch-error compensation point numbers 0 ... 1023, tape addresses N10000 ... N11023
FANUC_VALUE = (-128, 127)      # compensation value per point, in units of detection unit x magnification
FANUC_MAGNIFICATION = (1, 100)  # parameter 3623 (0 means 1)
FANUC_INTERVAL_MAX = 99_999_999  # parameter 3624 (two-word, in the least input increment)


def _fanuc_sections(ref_q: int, lo_q: int, hi_q: int, step_q: int) -> tuple[int, int]:
    """(lowest, highest): the FANUC sections (relative to the reference position's point) a table every ``step_q``
    anchored at R covers, with R's point and one above it."""
    k_lo, k_hi = _grid_range(ref_q, lo_q, hi_q, step_q)
    return min(k_lo + 1, 0), max(k_hi, 1)


def _blocks(table) -> int:
    """How many point blocks a FANUC tape of ``table`` fills: 2 for a table per direction (bidirectional pitch-error
    compensation: the positive direction's 3621 ... 3622, the negative direction's from 3626), else 1."""
    return 2 if table.attrs.get("per_direction") else 1


def fanuc_fitting_step(table, first_number: int = 0) -> int | None:
    """The finest step (x 1e-6 mm, a multiple of the table's quantum) whose table, anchored at the reference point
    over the measured travel, fills no more than the points left from ``first_number`` to 1023; None when fewer
    than two are left (every table fills R's point and the one above it). The count falls as the step grows."""
    blocks = _blocks(table)
    room = FANUC_POINTS - int(first_number)
    if room < 2 * blocks:
        return None
    a = table.attrs
    first, last = a["measured_mm"]
    ref_q, lo_q, hi_q = a["reference_q"], math.floor(first / NM + 1e-3), math.ceil(last / NM - 1e-3)
    quantum_q = a.get("quantum_q", AUTO_QUANTUM)
    lo, hi = 1, max(1, _ceil_div(max(ref_q - lo_q, hi_q - ref_q), quantum_q))   # hi: one section each side, 2 points
    while lo < hi:
        mid = (lo + hi) // 2
        lowest, highest = _fanuc_sections(ref_q, lo_q, hi_q, mid * quantum_q)
        if blocks * (highest - lowest + 1) <= room:
            hi = mid
        else:
            lo = mid + 1
    return lo * quantum_q


def fanuc_point_numbers(table, first_number: int = 0, check_interval=None) -> tuple[int, int, int]:
    """(3621, 3620, 3622): the first, the reference position's and the last pitch-error point number a FANUC tape
    of ``table`` fills when its points start at ``first_number``. The point numbers are one block shared by every
    axis (0i-PB parameter manual B-63980EN/01 p. 99-100: a linear axis at 33 ... 56, a rotary axis at 60 ... 68), so
    each axis' tape needs its own range; what does not fit 0 ... 1023 is refused, naming the largest first number
    that fits and the finest --interval whose points fit (:func:`fanuc_fitting_step`) if ``check_interval(step_mm)``
    (makes that step's table; raises CompensationError) accepts it."""
    if (isinstance(first_number, bool) or not isinstance(first_number, (int, np.integer))
            or not 0 <= first_number <= FANUC_POINTS - 1):
        raise CompensationError(f"fanuc-pitch: the first point number {first_number!r} (parameter 3621) must be a "
                                f"whole number 0 ... {FANUC_POINTS - 1}")
    a = table.attrs
    blocks = _blocks(table)
    lowest, highest = min(-a["reference_index"] + 1, 0), max(len(table) - 1 - a["reference_index"], 1)
    n = blocks * (highest - lowest + 1)      # a table per direction: the negative direction's block follows (3626)
    ref_no = int(first_number) - lowest
    if int(first_number) + n - 1 <= FANUC_POINTS - 1:
        return int(first_number), ref_no, ref_no + highest
    room = FANUC_POINTS - int(first_number)
    advice = [f"give a first point number of at most {FANUC_POINTS - n} (--fanuc-first-point)"] if n <= FANUC_POINTS else []
    step_q = fanuc_fitting_step(table, first_number)
    why = (f"{room} point is left from {first_number} and every table fills at least {2 * blocks} (the reference "
           f"position's and the one above it{', for each direction' if blocks == 2 else ''})" if step_q is None else "")
    if step_q is not None:
        try:
            if check_interval is not None:
                check_interval(step_q * NM)
            advice.append(f"choose a coarser --interval (at least {_exact(step_q)} mm, the finest whose points fit "
                          f"the {room} from {first_number})")
        except CompensationError:
            why = (f"no coarser --interval helps: {_exact(step_q)} mm, the finest whose points fit the {room} from "
                   f"{first_number}, is refused as too coarse for the curve")
    if not advice:
        from_zero = fanuc_fitting_step(table, 0)
        advice.append(f"give a lower first point number (--fanuc-first-point) and a coarser --interval (from point 0: "
                      f"at least {_exact(from_zero)} mm)")
    raise CompensationError(f"fanuc-pitch: {n} points{' (a block per direction)' if blocks == 2 else ''} from number "
                            f"{first_number} do not fit the pitch block "
                            f"0 ... {FANUC_POINTS - 1} (N10000 ... N{10000 + FANUC_POINTS - 1})"
                            f"{'; ' + why if why else ''}; {' or '.join(advice)}")


def fanuc_points_line(table, first_number: int = 0) -> str:
    """What a FANUC tape of ``table`` fills, for its header and the command's output."""
    first, ref, p22 = fanuc_point_numbers(table, first_number)
    last = p22 + (_blocks(table) - 1) * (p22 - first + 1)
    default = ", from the default first point 0" if first == 0 else ""
    negative = (f", 3626 = {p22 + 1} (the points of the negative direction, {p22 + 1} ... {last})" if _blocks(table) == 2
                else "")
    return (f"fills pitch-error points {first} ... {last}, N{10000 + first} ... N{10000 + last}{default}: 3621 = {first}, "
            f"3620 = {ref}, 3622 = {p22}{negative}; the points are one block for all axes, so another axis' tape must not overlap "
            + (f"them: write it with --fanuc-first-point {last + 1} or higher" if last < FANUC_POINTS - 1 else
               f"them: this one ends the block at {last}, so another axis' tape must end below {first}" if first > 0 else
               "them: this one fills the whole block, leaving no point for another axis"))


def write_fanuc_pitch(table, axis: str | None = AXIS_REQUIRED, detection_unit_mm: float = 0.001, increment_mm: float = 0.001,
                      first_number: int = 0, magnification: int | None = None, machine_unit: str = "mm",
                      reference_return: str = "up") -> str:
    """FANUC pitch-error compensation data in the parameter-tape format: ``%``, comments ``(...)``, one
    line ``N<10000 + point number> P<value>`` per compensation point, ``%`` (FANUC Series 0i-PB
    parameter manual B-63980EN/01 sec. 4, parameters 3620-3624 and the linear-axis example p. 99-100;
    technical report A-77810E, bidirectional pitch-error compensation, parameter table 3620-3627).

    Grid: point 3620 is the reference position R; point 3620 + k (k >= 1) holds the pitch error of the
    section (R + (k-1) d, R + k d], point 3620 - j (j >= 0) that of (R - (j+1) d, R - j d], with d = 3624;
    3621 / 3622 are the most negative / positive point numbers (3621 <= 3620 < 3622). Values are
    **incremental** (the change of the compensation over the point's section, "as viewed from the
    negative direction"), in units of detection unit x 3623 (magnification), each in -128 ... 127.

    Sign: the compensation pulses are output with the move command, so a positive value moves the axis
    in the positive direction; an axis that reaches target + x(P) needs -x(P): the increments are those
    of **-(x(P) - x(R))**, rounded on the absolute curve (no accumulated rounding).

    Limits: the point block 0 ... 1023 (tape N10000 ... N11023): the axis' points start at
    ``first_number`` (3621) and must end by 1023; 3624 = d / ``increment_mm`` (the least input increment,
    IS-B 0.001 mm) must be a whole number in 1 ... 99999999 (FANUC also requires d >= rapid traverse /
    7500, which the header states); 3623 in 1 ... 100, by default the smallest that keeps every value
    within -128 ... 127. What does not fit is refused.

    ``machine_unit``: "mm" (a metric machine) or "in" (an inch machine, parameter 1001#0 INM = 1: its detection
    unit and least input increment are 0.0001 in for IS-B, 0.00001 in for IS-C; ``detection_unit_mm`` and
    ``increment_mm`` are still given in mm, 0.00254 for 0.0001 in): the values, 3624 and 1851 are counts of the
    machine's units, computed from the whole table in mm and rounded on the absolute curve, and the comments name
    the units in inches.

    ``axis`` (required): the axis the table is for, named in the comments (the tape itself names none: the
    parameters 3620-3624 are set per axis); None: the comments say 'axis not given' (``--axis`` left out on the
    command line). A missing axis is refused (:class:`CompensationError`).

    A table per direction (``compensation_table(per_direction=True)``) gives a tape for **bidirectional pitch-error
    compensation** (technical report A-77810E, parameter table: 3605#0 = 1 enables it; 3620-3624 as above for travel in
    the positive direction; 3626 the most negative point of the table for travel in the negative direction; 3627 the
    compensation, absolute, at the reference position when it is approached opposite to the reference-return
    direction): the positive direction's increments of -(x_up(P) - x_ret(R)) at 3621 ... 3622, then the negative
    direction's of -(x_down(P) - x_ret(R)) from 3626 = 3622 + 1 over the same sections, x_ret being the deviation of
    the ``reference_return`` direction ('up': the reference position is returned to in the positive direction), whose
    table holds 0 at R; 3627 the other direction's value at R in detection units; backlash 1851 = 0 (the tables hold
    the reversal). Not confirmed from a manual page, and said in the tape: that the negative direction's table has the
    sections and incremental sense of the positive one and starts from 3627 at R, and the unit of 3627 (detection
    units; written with magnification 3623 = 1 only, so that the two readings agree)."""
    if machine_unit not in ("mm", "in"):
        raise CompensationError(f"fanuc-pitch: machine_unit must be 'mm' or 'in', got {machine_unit!r}")

    def unit(mm: float) -> str:           # a unit of the machine, as the tape names it
        return f"{mm:g} MM" if machine_unit == "mm" else f"{round(mm / INCH_MM, 8):g} IN"
    if axis is AXIS_REQUIRED:
        raise CompensationError("fanuc-pitch: no axis is given: give axis=NAME (e.g. write_fanuc_pitch(table, "
                                "axis='X')), the axis whose parameters 3620-3624 take the table, or axis=None for "
                                "'axis not given' in its comments")
    label = NOT_GIVEN.upper() if axis is None else check_axis(axis, "fanuc-pitch").upper()
    a = table.attrs
    k0 = a["reference_index"]
    both = bool(a.get("per_direction"))
    if reference_return not in ("up", "down"):
        raise CompensationError(f"fanuc-pitch: reference_return must be 'up' or 'down', got {reference_return!r}")
    if both:                  # each direction's table relative to the reference-return direction's deviation at R
        at_r = float(table[f"deviation_{reference_return}_mm"].iloc[k0])
        rels = [-(table[f"deviation_{d}_mm"].to_numpy() - at_r) for d in ("up", "down")]
        if magnification not in (None, 1):
            raise CompensationError(f"fanuc-pitch: magnification {magnification!r}: a bidirectional tape is written "
                                    "with 3623 = 1 only (whether 3627 is scaled by 3623 is not confirmed)")
        magnification = 1
    else:
        rels = [-(table.deviation_mm.to_numpy() - a["deviation_at_reference_mm"])]     # what to add, mm, 0 at R
    k = np.arange(len(table)) - k0                                            # grid index relative to R
    k_lo, k_hi = int(k[0]), int(k[-1])
    lowest, highest = min(k_lo + 1, 0), max(k_hi, 1)     # sections covered, with R's point and one above it
    first_number, ref_no, last_number = fanuc_point_numbers(table, first_number)
    step_mm = a["step_q"] * NM
    interval = step_mm / increment_mm
    if abs(interval - round(interval)) > 1e-6 or not 1 <= round(interval) <= FANUC_INTERVAL_MAX:
        raise CompensationError(f"fanuc-pitch: the point interval {_exact(a['step_q'])} mm is not a whole number "
                                f"1 ... {FANUC_INTERVAL_MAX} of {unit(increment_mm).lower()} (parameter 3624); "
                                f"choose --interval as a multiple of {unit(increment_mm).lower()}")
    interval = int(round(interval))
    mags = range(FANUC_MAGNIFICATION[0], FANUC_MAGNIFICATION[1] + 1) if magnification is None else [magnification]
    for m in mags:
        if not (isinstance(m, (int, np.integer)) and FANUC_MAGNIFICATION[0] <= m <= FANUC_MAGNIFICATION[1]):
            raise CompensationError(f"fanuc-pitch: magnification {m!r} (parameter 3623) must be a whole number "
                                    f"{FANUC_MAGNIFICATION[0]} ... {FANUC_MAGNIFICATION[1]}")
        absolutes = [np.rint(r / (detection_unit_mm * m)).astype(np.int64) for r in rels]
        inc = np.concatenate([np.diff(ab) for ab in absolutes])  # section k (k_lo < k <= k_hi) -> [k - k_lo - 1]
        if inc.size == 0 or (inc.min() >= FANUC_VALUE[0] and inc.max() <= FANUC_VALUE[1]):
            break
    else:
        raise CompensationError(f"fanuc-pitch: a change of {np.abs(inc).max()} x {unit(detection_unit_mm).lower()} x {m} over "
                                f"one interval exceeds {FANUC_VALUE[1]} (per point); choose a finer --interval"
                                + ("" if both else " or a larger magnification"))
    numbers = ref_no + np.arange(lowest, highest + 1)
    values = np.zeros((len(absolutes), highest - lowest + 1), dtype=np.int64)
    for row, ab in zip(values, absolutes):
        row[(k_lo + 1) - lowest:(k_hi + 1) - lowest] = np.diff(ab)
    def comment(text: str) -> str:
        return "(" + re.sub(r"[^A-Z0-9 .,:;=+\-/*]", " ", text.upper()).strip() + ")"
    out = ["%", comment(f"FANUC PITCH ERROR COMPENSATION AXIS {label} VALUES INCREMENTAL IN {unit(detection_unit_mm)} "
                        f"X MAGNIFICATION {m}")]
    if both:
        b = a["backlash_mm"]
        what = (f"increments of minus the deviation of each direction relative to that of the {reference_return} direction at the "
                "reference point; a positive value moves the axis in the positive direction")
        held = (f"mean reversal value B = {b * 1e3:.3f} um, ISO 230-2: mean of x_up - x_down over the targets; the tables "
                "of the two directions hold the reversal at every point (3627 at the reference position): no backlash, "
                "1851 = 0")
        out += [comment(h) for h in _header(table, label, what, held)]
    else:
        out += [comment(h) for h in _header(table, label, "increments of minus the deviation relative to the reference "
                                                           "point; a positive value moves the axis in the positive direction")]
    lag = int(np.abs(inc).max()) if inc.size else 0
    out.append(comment(f"APPLIED STEPWISE: BETWEEN TWO POINTS THE COMPENSATION STAYS AT THE VALUE OF THE POINT ON THE "
                       f"REFERENCE POSITION S SIDE, UP TO {lag * detection_unit_mm * m * 1e3:g} UM, THE LARGEST CHANGE "
                       f"OVER ONE INTERVAL, OFF THE CURVE BETWEEN THE POINTS; A FINER INTERVAL FOLLOWS IT CLOSER"))
    out.append(comment("THIS TAPE " + fanuc_points_line(table, first_number).replace("'", "").replace(
        "write it with --fanuc-first-point", "give it a first point number 3621 of")))
    out.append(comment(f"SET 3620 = {ref_no} REFERENCE POSITION AT {_exact(a['reference_q'])} MM, "
                       f"3621 = {numbers[0]}, 3622 = {numbers[-1]}, 3623 = {m}, 3624 = {interval} "
                       f"I.E. {_exact(a['step_q'])} MM"
                       + (f", {a['step_q'] * NM / INCH_MM:.6f} IN," if machine_unit == "in" else "")
                       + f" IN UNITS OF {unit(increment_mm)}; RAPID TRAVERSE MM/MIN / 7500 "
                       f"MUST NOT EXCEED {_exact(a['step_q'])} MM"))
    if both:
        other = "down" if reference_return == "up" else "up"
        p26 = int(numbers[-1]) + 1
        p27 = int(absolutes[0 if other == "up" else 1][k0])
        out.append(comment(f"SET 3605 BIT 0 = 1 BIDIRECTIONAL PITCH ERROR COMPENSATION, 3626 = {p26}, 3627 = {p27} "
                           f"IN UNITS OF {unit(detection_unit_mm)}; POSITIVE DIRECTION TABLE {numbers[0]} ... "
                           f"{numbers[-1]}, NEGATIVE DIRECTION TABLE {p26} ... {p26 + len(numbers) - 1}; REFERENCE RETURN "
                           f"IN THE {'POSITIVE' if reference_return == 'up' else 'NEGATIVE'} DIRECTION: 3627 IS THE "
                           f"{'NEGATIVE' if other == 'down' else 'POSITIVE'} DIRECTION S VALUE AT THE REFERENCE POSITION"))
        out.append(comment("NOT CONFIRMED FROM A MANUAL PAGE: THAT THE NEGATIVE DIRECTION TABLE HAS THE SECTIONS AND THE "
                           "INCREMENTAL SENSE OF THE POSITIVE ONE AND STARTS FROM 3627 AT THE REFERENCE POSITION, AND THE "
                           "UNIT OF 3627; CHECK THEM IN A-77810E FOR YOUR SERIES AND WITH A VERIFICATION RUN IN BOTH "
                           "DIRECTIONS"))
        out.append(comment("BACKLASH: SET 1851 = 0, THE TABLES OF THE TWO DIRECTIONS HOLD THE REVERSAL"))
        numbers = np.concatenate([numbers, p26 + np.arange(len(numbers))])
        values = values.ravel()
    elif np.isfinite(a["backlash_mm"]):
        units = int(np.rint(-a["backlash_mm"] / detection_unit_mm))
        if abs(units) > 9999:
            raise CompensationError(f"fanuc-pitch: the backlash -B = {-a['backlash_mm']:g} mm is {units} detection "
                                    "units, beyond parameter 1851's -9999 ... 9999")
        out.append(comment(f"BACKLASH: SET 1851 = {units} DETECTION UNITS OF {unit(detection_unit_mm)}, I.E. -B"))
    out += [f"N{10000 + int(no)} P{int(v)}" for no, v in zip(numbers, np.ravel(values))]
    out.append("%")
    return "\n".join(out) + "\n"


WRITERS = {"csv": write_csv, "siemens-eec": write_siemens_eec, "fanuc-pitch": write_fanuc_pitch}
#: the most points each format's controller takes (the writers' limits: SINUMERIK MD38000, FANUC's point block)
POINT_LIMITS = {"siemens-eec": SINUMERIK_MAX_POINTS, "fanuc-pitch": FANUC_POINTS - 1, "csv": MAX_POINTS}


def _fitting_default(res, data, table, limit: int, fmt: str, source: str, reference_mm, formats=(),
                     per_direction: bool = False):
    """The default table (at the smallest target spacing) has more points than ``fmt`` takes: the finest step (a
    multiple of 0.001 mm) whose table, anchored at the reference point, has at most ``limit`` points, if that table
    still reproduces the curve at the targets (the ``--interval`` rule, :func:`_check_represents`); the choice is
    in ``attrs['chosen']``. Irregular targets (ISO 230-2 advises them) make the smallest spacing far finer than the
    mean spacing: 21 targets on 1000 mm gave 272 points for a 200-point SINUMERIK."""
    a = table.attrs
    first, last = a["measured_mm"]
    ref_q, lo_q, hi_q = a["reference_q"], math.floor(first / NM + 1e-3), math.ceil(last / NM - 1e-3)
    quantum_q = a.get("quantum_q", AUTO_QUANTUM)
    step_q = _ceil_div(_ceil_div(hi_q - lo_q, max(limit - 1, 1)), quantum_q) * quantum_q
    while np.subtract(*_grid_range(ref_q, lo_q, hi_q, step_q)[::-1]) + 1 > limit:
        step_q += quantum_q
    try:
        chosen = compensation_table(res, data, interval=step_q * NM, source=source, reference_mm=reference_mm,
                                    formats=formats, quantum_q=quantum_q, per_direction=per_direction)
    except CompensationError as exc:
        raise CompensationError(f"{fmt}: the default table (at the smallest target spacing, {a['interval_mm']:g} mm) "
                                f"has {len(table)} points, more than the controller's {limit}, and the finest step that "
                                f"fits, {step_q * NM:g} mm, is refused: {exc}") from None
    roomier = [f for f in formats if f != fmt and POINT_LIMITS.get(f, MAX_POINTS) > limit]
    alone = (f"; one table serves every format, so {' and '.join(roomier)} {'gets' if len(roomier) == 1 else 'get'} "
             f"{fmt}'s step: written without {fmt}, {'it takes' if len(roomier) == 1 else 'they take'} a finer one"
             if roomier else "")
    chosen.attrs["chosen"] = (f"every {step_q * NM:g} mm, the finest step whose table fits {fmt}'s {limit} points (the "
                              f"smallest target spacing, {a['interval_mm']:g} mm, gave {len(table)}); --interval sets "
                              f"another{alone}")
    return chosen


def magnitude_problem(table) -> str | None:
    """What makes the table implausible for a machine axis (a unit mistake), or None: a value (relative to
    the reference point) beyond max(VALUE_FLOOR_MM, VALUE_PER_TRAVEL x travel) or a backlash entry beyond
    BACKLASH_LIMIT_MM."""
    first, last = table.attrs["measured_mm"]
    limit = max(VALUE_FLOOR_MM, VALUE_PER_TRAVEL * (last - first))
    peak = float(max(np.max(np.abs(table[c].to_numpy())) for c in ("compensation_mm", "compensation_up_mm",
                                                                    "compensation_down_mm") if c in table))
    backlash = abs(float(table.attrs["backlash_mm"]))
    found = []
    if peak > limit:
        found.append(f"values up to {peak:.4g} mm (more than {limit:g} mm, {VALUE_PER_TRAVEL * 100:g} % of the "
                     f"{last - first:g} mm travel)")
    if np.isfinite(backlash) and backlash > BACKLASH_LIMIT_MM:
        found.append(f"a backlash of {backlash:.4g} mm (more than {BACKLASH_LIMIT_MM:g} mm)")
    return " and ".join(found) or None


def model_misfit(res) -> str | None:
    """What the lack-of-fit test (:func:`methods.positioning.model.lack_of_fit`: weighted chi-square of the model
    against the means at the targets, u(x_i) = s_i / sqrt(n)) says against the polynomial of ``res``, or None when
    no direction's model is rejected."""
    arrow = {"up": "up", "down": "down"}
    bad = [(d, p) for d, p in (getattr(res, "polynomial", None) or {}).items()
           if (p.get("lack_of_fit") or {}).get("rejected")]
    if not bad:
        return None
    degree = bad[0][1]["degree"]
    name = {1: "straight line", 2: "parabola", 3: "cubic"}.get(int(degree), f"degree-{degree} polynomial")
    parts = ", ".join(f"{arrow.get(d, d)} chi2/nu {p['lack_of_fit']['chi2_per_dof']:.3g} > "
                      f"{p['lack_of_fit']['critical']:.3g}, misses the means by up to "
                      f"{p['lack_of_fit']['max_abs_residual'] * 1e3:.3g} um" for d, p in bad)
    return f"the {name} is rejected by its lack of fit ({parts})"


def varying_reversal(data, per_direction: bool = False) -> str | None:
    """What a table of the mean bidirectional deviation with one backlash leaves when the reversal B_i varies
    along the travel (:func:`methods.positioning.iso230_2.reversal_variation`: significant against the scatter of
    the run-by-run differences x_up - x_down at each target), and what to do; that the variation could not be tested
    and why; or None. Controllers with a curve per direction: FANUC bidirectional pitch-error
    compensation (technical report A-77810E, 3605#0, 3620-3627), SINUMERIK direction-dependent LEC (840C/611D
    manual sec. 12.1.2: a second curve per direction), HEIDENHAIN .COM tables (a BACKLASH column). ``per_direction``:
    the tables written hold a curve per direction, which takes the variation in."""
    from methods.positioning.iso230_2 import reversal_variation
    rv = reversal_variation(data)
    if rv and not rv["tested"]:
        return (f"whether the reversal B_i varies along the travel (from {rv['B_i_min'] * 1e3:.3f} to "
                f"{rv['B_i_max'] * 1e3:.3f} um) was not tested: {rv['reason']}")
    if not rv or not rv["significant"]:
        return None
    p = f"p = {rv['p_value']:.2g}" if rv["p_value"] >= 1e-4 else "p below 0.0001"
    if per_direction:
        return (f"the reversal B_i varies along the travel from {rv['B_i_min'] * 1e3:.3f} to {rv['B_i_max'] * 1e3:.3f} "
                f"um (mean {rv['B_mean'] * 1e3:.3f} um; chi2/nu = {rv['chi2_per_dof']:.3g} on {rv['dof']} degrees of "
                f"freedom, above the limit {rv['critical']:.3g} of a {100 * rv['level']:g} % test, {p}): the tables of "
                f"the two directions hold it; the mean table with one backlash would leave up to "
                f"{rv['left'] * 1e3:.3f} um in each direction")
    return (f"the reversal B_i varies along the travel from {rv['B_i_min'] * 1e3:.3f} to {rv['B_i_max'] * 1e3:.3f} um "
            f"(mean {rv['B_mean'] * 1e3:.3f} um; chi2/nu = {rv['chi2_per_dof']:.3g} on {rv['dof']} degrees of freedom, "
            f"above the limit {rv['critical']:.3g} of a {100 * rv['level']:g} % test, {p}: more than the run-to-run scatter of "
            f"x_up - x_down at each target explains, runs paired {rv['pairing']}): this table of the mean bidirectional "
            f"deviation with one backlash (-B mean) leaves (B_i - B mean)/2 in each direction: up to "
            f"{rv['left'] * 1e3:.3f} um, of opposite sign in the two ({2 * rv['left'] * 1e3:.3f} um between them); where the controller takes a curve per "
            "direction (FANUC bidirectional pitch-error compensation 3605#0), write a table per direction with "
            "--compensation-directions both (csv, fanuc-pitch)")


def thermal_line(data) -> str | None:
    """What a table from temperature-corrected deviations (:func:`methods.positioning.data.thermal_correction`)
    holds, or None: the correction was computed from two numbers given, not measured, and decides which machine the
    table suits (one working at 20 °C or with its own temperature compensation, not one working at the test's
    temperature with its scale at that temperature)."""
    th = getattr(data, "thermal", None)
    if not th:
        return None
    (p0, c0), (p1, c1) = th["correction_at_ends_mm"]
    t = th["material_temperature_c"]
    return (f"TEMPERATURE-CORRECTED: the deviations were corrected to 20 C from a material temperature of {t:.4g} C with "
            f"an expansion coefficient of {th['expansion_coefficient_um_per_m_k']:g} um/(m K), by "
            f"{th['correction_um_per_m']:+.4g} um/m x position ({c0 * 1e3:+.3f} um at {p0:g} mm, {c1 * 1e3:+.3f} um at "
            f"{p1:g} mm), given, not measured; the values are the axis error at 20 C: for a machine that works at 20 C "
            f"or compensates temperature itself; a machine working at {t:.4g} C with its scale at {t:.4g} C needs the "
            "table without the correction")


def write_tables(res, data, requests, *, interval=None, source="model", axis=None, write, reference_mm=None,
                 unit_confirmed: bool = False, unit_option: str = "--deviation-unit", on_confirmed=None,
                 model_confirmed: bool = False, axis_hint: str = "", fanuc_unit_mm: float = 0.001,
                 fanuc_first_number: int = 0, fanuc_machine_unit: str = "mm", per_direction: bool = False,
                 fanuc_reference_return: str = "up"):
    """Build the table once and write it in every requested ``(format, path)`` with ``write(path, text)``;
    every format is checked (name, axis, limits) before any file is written. A table implausible for a
    machine axis (:func:`magnitude_problem`: µm read as mm) is refused unless ``unit_confirmed`` (the
    deviations' unit given explicitly, ``unit_option`` on the command line); then ``on_confirmed(text)`` is
    told. A table from a model its lack-of-fit test rejects (:func:`model_misfit`: it would leave the measured
    misfit out of the machine) is refused unless ``model_confirmed`` (the model chosen explicitly); then
    ``on_confirmed`` is told and every file's header says so. ``axis`` None: a SINUMERIK table (whose entries name
    the machine axis they compensate) is refused, naming ``axis_hint`` (what the file says); the other formats say
    'axis not given' in their header. ``fanuc_unit_mm``: the FANUC axis' detection unit and least input increment
    in mm (0.001 mm IS-B, 0.0001 mm IS-C; an inch machine, ``fanuc_machine_unit='in'``: 0.00254 mm = 0.0001 in
    IS-B, 0.000254 mm IS-C, and the automatic step is a multiple of it); ``fanuc_first_number``: its first pitch-error point number (3621; each axis
    needs its own range of the one block, :func:`fanuc_point_numbers`), said in ``attrs['fanuc_points']``.
    ``per_direction``: a table per direction (a bidirectional test; csv columns compensation_up_mm / _down_mm, a FANUC
    bidirectional tape, :func:`write_fanuc_pitch`; SINUMERIK is refused), ``fanuc_reference_return`` the direction of
    the FANUC axis' reference return ('up' or 'down'). Returns the table."""
    for fmt, _ in requests:
        if fmt not in WRITERS:
            raise InvalidInputError(f"--compensation {fmt}: unknown format; use one of {', '.join(WRITERS)}")
    if per_direction and any(fmt == "siemens-eec" for fmt, _ in requests):
        raise CompensationError(SIEMENS_PER_DIRECTION)
    if per_direction and len(data.directions) != 2:
        raise InvalidInputError(one_direction_refusal(data))
    if axis is None and any(fmt == "siemens-eec" for fmt, _ in requests):
        raise CompensationError("siemens-eec: a SINUMERIK table names the machine axis it compensates "
                                "($AA_ENC_COMP[0,N,AXIS], MD10000 $MN_AXCONF_MACHAX_NAME_TAB) and --axis is not given: "
                                f"give --axis NAME, e.g. --axis X1{axis_hint}")
    misfit = model_misfit(res) if source == "model" else None
    if misfit and not model_confirmed:
        raise CompensationError(f"not writing {', '.join(str(p) for _, p in requests)}: {misfit}; a table from it "
                                "would leave that misfit in the machine: give --compensation-from mean (the measured "
                                "means at the targets) or another --degree, or --compensation-from model to write the "
                                "model's table anyway")
    formats = tuple(dict.fromkeys(fmt for fmt, _ in requests))
    unit_q = int(round(fanuc_unit_mm / NM))
    quantum_q = (unit_q if "fanuc-pitch" in formats and unit_q > 0 and AUTO_QUANTUM % unit_q else AUTO_QUANTUM)
    table = compensation_table(res, data, interval=interval, source=source, reference_mm=reference_mm, formats=formats,
                               quantum_q=quantum_q, per_direction=per_direction)
    limit, fmt = min((POINT_LIMITS.get(f, MAX_POINTS) // (2 if per_direction and f == "fanuc-pitch" else 1), f)
                     for f, _ in requests)
    if interval is None and len(table) > limit:
        table = _fitting_default(res, data, table, limit, fmt, source, reference_mm, formats, per_direction)
    if misfit:
        table.attrs["warning"] = (f"WARNING: {misfit}; written from the model as asked: the table leaves that misfit "
                                  "uncompensated (--compensation-from mean follows the measured means)")
        if on_confirmed is not None:
            on_confirmed(f"{misfit}; the compensation table is written from it as --compensation-from model asks and "
                         "leaves that misfit uncompensated (--compensation-from mean follows the measured means)")
    problem = magnitude_problem(table)
    if problem and not unit_confirmed:
        raise CompensationError(f"not writing {', '.join(str(p) for _, p in requests)}: the table would hold {problem}, "
                                f"not a machine axis' error but likely µm read as mm; give the deviations' unit: "
                                f"{unit_option} um if they are in µm (or {unit_option} mm to confirm mm)")
    if problem and on_confirmed is not None:
        on_confirmed(f"the compensation table holds {problem}, written as {unit_option} confirms the unit: "
                     "check it before loading it")
    reversal = varying_reversal(data, per_direction)
    if reversal:
        table.attrs["reversal_note"] = f"NOTE: {reversal}"
    fanuc = {"detection_unit_mm": fanuc_unit_mm, "increment_mm": fanuc_unit_mm, "first_number": fanuc_first_number,
             "machine_unit": fanuc_machine_unit, **({"reference_return": fanuc_reference_return} if per_direction else {})}
    if outside_reference(table):
        table.attrs["reference_note"] = outside_reference(table) + "; every file's header says so"
    first, last = table.attrs["measured_mm"]
    if reference_mm is None and not first <= 0.0 <= last and any(fmt == "fanuc-pitch" for fmt, _ in requests):
        table.attrs["reference_note"] = (
            f"no reference point given and the measured travel ({first:g} to {last:g} mm) does not hold 0 mm: the "
            f"reference point is taken at the nearer end target, {table.attrs['reference_q'] * NM:g} mm; a FANUC table's "
            "sections start at the machine's reference position (3620), so give --reference where it is if it is "
            "elsewhere (outside the measured travel too, e.g. --reference 0 at the travel end)")
    if any(fmt == "fanuc-pitch" for fmt, _ in requests):
        numbers = fanuc_point_numbers(table, fanuc_first_number, check_interval=lambda step: compensation_table(
            res, data, interval=step, source=source, reference_mm=reference_mm, formats=formats, quantum_q=quantum_q,
            per_direction=per_direction))
        table.attrs["fanuc_points"] = fanuc_points_line(table, fanuc_first_number)
        table.attrs["fanuc_numbers"] = dict(zip(("p3621", "p3620", "p3622"), numbers))
        if per_direction:
            table.attrs["fanuc_numbers"]["p3626"] = numbers[2] + 1
    texts = [(path, WRITERS[fmt](table, axis=axis, **(fanuc if fmt == "fanuc-pitch" else {})))
             for fmt, path in requests]
    for path, text in texts:
        write(path, text)
    return table
