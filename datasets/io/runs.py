"""Circular-test runs and roundness profiles (:func:`read_runs`, :func:`read_profile`): one file in any
instrument layout (:func:`datasets.io.roles.resolve`), x, y or angle + radial deviation / radius (the data view of
ballbar and roundness software, e.g. the Renishaw Ballbar 20 text export), holding one run or both directions of an
ISO 230-4 circular test (a direction or run column: CW/CCW, G02/G03, :data:`CW_WORDS`), as :class:`CircularRuns` in
mm."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from datasets.io._pandas import pd
from datasets.io.columns import data_blocks, read_columns
from datasets.io.headers import column_unit, length_unit
from datasets.io.layout import Layout, sniff
from datasets.io.numbers import DataFileError
from datasets.io.polar import (_unit_assumed, angle_unit_of, polar_to_points, profile_circle,
                               warn_radius_like_deviation, warn_too_small, warn_too_small_xy)
from datasets.io.roles import PLANES, Resolved, coordinate_kind, read_offsets, resolve
from methods.units import to_mm


@dataclass
class CircularRuns:
    """The runs read from one file: a list of (label, (N, 2) points in mm, in the file's order)."""

    runs: list
    source: str
    kind: str          # 'xy' or 'polar'
    unit: str
    notes: list = field(default_factory=list)
    angle_unit: str | None = None
    axes: tuple = ("x", "y")   # names of the two coordinates: the header's names of x, y columns, else x, y
    unit_assumed: bool = False  # no unit in the header nor given: ``unit`` is mm by default
    columns_note: str | None = None  # which columns were read when the header held more than x, y (actual, deviation)


def _axes(layout: Layout, res: Resolved, plane: str | None = None) -> tuple:
    """Names of the two coordinates read: the header's keys of an x, y layout (``z``, ``x`` for a z-x plane),
    else ``x``, ``y``; angle + deviation files are placed in the ``plane`` given (the angle turning from its first
    axis to its second, ``zx``: from Z to X), else in an x, y plane; header-less files have no names."""
    keys = [k for k, _ in layout.fields()]
    if res.kind == "polar" and plane is not None:
        return PLANES[plane.lower()]
    if res.kind != "xy" or not keys:
        return ("x", "y")
    named = [coordinate_kind(keys[i]) for i in res.idx]   # 'X act' is the coordinate x
    return tuple(c[0] if c else keys[i] or f"column {i}" for i, c in zip(res.idx, named))


def read_runs(path, *, columns=None, plane=None, unit: str | None = None, skip_rows: int = 0,
              angle_unit: str | None = None, nominal_radius: float | None = None, nominal_center=(0.0, 0.0),
              need_nominal_radius: bool = True, min_arc_deg: float | None = None,
              one_revolution: bool = False) -> CircularRuns:
    """One measurement file in any instrument layout (:func:`resolve`): x, y columns or angle + radial
    deviation / radius, holding one run or both directions (a ``direction`` or ``run`` column; rows of each
    run in the order measured). Lengths in the header's unit or ``unit`` (a contradiction is an error),
    returned in mm; angle + deviation are placed about ``nominal_center`` with ``nominal_radius`` (mm; with
    ``need_nominal_radius`` false the deviations alone are evaluated, :func:`polar_to_points`). ``min_arc_deg``: the
    smallest arc the caller evaluates; angles read as degrees that span less and look like radians are refused
    naming the angle unit (:func:`radians_as_degrees`), angles read as radians that turn more than
    :data:`MAX_RADIAN_REVOLUTIONS` times are refused as degrees (:func:`degrees_as_radians`); ``one_revolution`` (a
    closed profile): angles going on past one revolution are refused naming the lines to keep
    (:func:`beyond_one_revolution`).

    The angle + deviation layout follows what ballbar and roundness software lists as its data (sample angle
    and radial deviation per point, e.g. the Renishaw Ballbar 20 "data" view and its text export); we found
    no public specification of those exports, so the column names accepted are ours (:data:`ROLES`;
    confidence: low for byte-for-byte compatibility, high for the content)."""
    layout = sniff(path, skip_rows)
    name = layout.name
    res = resolve(layout, columns, plane)
    notes = [res.note] if res.note else []
    au = None
    if res.kind == "polar":
        au = angle_unit_of(layout, res.idx[0], angle_unit)
        if nominal_radius is None and need_nominal_radius and res.polar_value == "deviation":
            raise DataFileError(f"{name}: an angle + radial-deviation file needs --nominal-radius to place the points")
        lu = length_unit(layout, [res.idx[1]], unit)
        assumed = unit is None and column_unit(layout, res.idx[1], "length") is None
    else:
        lu = length_unit(layout, res.idx, unit)
        assumed = unit is None and all(column_unit(layout, k, "length") is None for k in res.idx)
    strings = (res.direction,) if res.direction is not None else ()
    if res.direction is None and len(blocks := data_blocks(layout, gaps := [])) > 1:
        raise DataFileError(two_blocks(layout, blocks, gaps))   # before the numbers: a line ',' is a separator
    cols = read_columns(layout, res.idx + (res.offsets or []), skip_rows=skip_rows, strings=strings)
    f = to_mm(1.0, lu)
    if res.kind == "polar":
        if au == "deg" and (why := radians_as_degrees(layout, res.idx[0], cols[res.idx[0]], angle_unit,
                                                      min_arc_deg)):
            if min_arc_deg is not None:
                raise DataFileError(why)
            notes.append(why)   # a fit of an arc: it may be one
        if au == "rad" and (why := degrees_as_radians(layout, res.idx[0], cols[res.idx[0]], angle_unit)):
            raise DataFileError(why)
        hint = (round_degrees_as_radians(layout, res.idx[0], cols[res.idx[0]], angle_unit)
                if au == "rad" and res.direction is None else None)
        ang = cols[res.idx[0]] if au == "rad" else np.radians(cols[res.idx[0]])
        if one_revolution and res.direction is None and (
                why := beyond_one_revolution(layout, res.idx[0], ang, cols[res.idx[1]])):
            raise DataFileError(f"{why}; {hint}" if hint else why)
        if hint:
            notes.append(hint)
        if assumed and res.polar_value == "deviation":
            notes.append(_unit_assumed(layout, res.idx[1], cols[res.idx[1]]))
        if res.polar_value == "deviation":
            warn_too_small(layout, res.idx[1], cols[res.idx[1]] * f, lu, unit)
        pts, note = polar_to_points(ang, cols[res.idx[1]] * f, res.polar_value, nominal_radius, nominal_center,
                                    name=name)
        if res.polar_value == "radius":
            warn_radius_like_deviation(layout, res.idx[1], cols[res.idx[1]] * f, lu)
        if note:
            notes.append(note)
    else:
        pts = np.empty((len(cols[res.idx[0]]), 2), dtype=np.float64)
        pts[:, 0], pts[:, 1] = cols[res.idx[0]], cols[res.idx[1]]
        if f != 1.0:
            pts *= f
        if (dev := read_offsets(layout, res, cols)) is not None:
            pts += dev
        circle = profile[1] if (profile := profile_circle(pts)) else None   # fitted once for both checks
        if one_revolution and res.direction is None and (why := xy_beyond_one_revolution(layout, pts, circle)):
            raise DataFileError(why)
        warn_too_small_xy(layout, res.idx, pts, (cols[res.idx[0]], cols[res.idx[1]]), lu, unit, circle)
    axes = _axes(layout, res, plane)
    if res.kind == "polar" and plane is not None:
        notes.append(f"angle + radial deviation in the {''.join(axes).upper()} plane (--plane {plane.lower()}): the "
                     f"angle turns from +{axes[0].upper()} towards +{axes[1].upper()}")
    if res.direction is None:
        return CircularRuns([("file", pts)], name, res.kind, lu, notes, au, axes, assumed, res.note)
    labels = pd.Series(cols[res.direction]).astype(str).str.strip()
    runs = []
    for lab in pd.unique(labels):
        mask = (labels == lab).to_numpy()
        low = lab.lower()
        tag = "cw" if low in CW_WORDS else "ccw" if low in CCW_WORDS else lab
        runs.append((tag, pts[mask]))
    if len(runs) > 2:
        raise DataFileError(f"{name}: {len(runs)} runs in the direction/run column ({', '.join(l for l, _ in runs)}); "
                            "a circular test has two (CW and CCW)")
    return CircularRuns(runs, name, res.kind, lu,
                        notes + [f"{len(runs)} run(s) read from the column {layout.header[res.direction]!r}"], au, axes,
                        assumed, res.note)


def radians_as_degrees(layout: Layout, k: int, angles, angle_unit: str | None,
                       min_arc_deg: float | None) -> str | None:
    """The error line when the angle column ``k``, read as degrees, spans less than ``min_arc_deg`` while every angle
    lies within +-2 pi and they span at least pi: a revolution written in radians (0 to 6.28, or -3.14 to 3.14) read
    as a 6° arc, which a roundness evaluation then refused as open ('no point between 6.3° and 0.0°'); without
    ``min_arc_deg`` (a fit, which may be of an arc) the same line as a note, asked. None otherwise."""
    a = np.asarray(angles, dtype=float)
    if a.size < 3 or not np.isfinite(a).all():
        return None
    lo, hi = float(a.min()), float(a.max())
    turn = 2 * np.pi * (1 + 1e-9)
    if not (-turn <= lo and hi <= turn and np.pi <= hi - lo):
        return None
    col = layout.header[k] if layout.header else f"column {k}"
    todo = ("give --angle-unit rad" if angle_unit is None and column_unit(layout, k, "angle") is None else
            "give --angle-unit rad, not deg" if angle_unit == "deg" else f"correct the header of {col!r} to [rad]")
    need = f" (less than the {min_arc_deg:g}° needed)" if min_arc_deg is not None else ""
    return (f"{layout.name}: the angles of {col!r} run from {lo:g} to {hi:g}: read as degrees they cover {hi - lo:.3g}°"
            f"{need}, each within ±2π; are they in radians? {todo}")


#: angles read as radians spanning more than this many revolutions are refused as degrees (:func:`degrees_as_radians`):
#: a closed profile turns once (< 2 pi + a step), a circular-test run once plus its lead-in, lead-out and overrun, a
#: file of both runs in one angle column (one unwrapped each way) twice that; a revolution in degrees spans 360 "rad"
#: (57 revolutions), an ISO 230-4 partial arc of 90 deg 14, and any arc in degrees over 4 x 2 pi = 25.1 deg is caught
MAX_RADIAN_REVOLUTIONS = 4


def _degrees_fix(layout: Layout, k: int) -> tuple[str, str]:
    """(the name of angle column ``k``, what to do to read it in degrees): the option when --angle-unit said
    radians, else its header."""
    col = layout.header[k] if layout.header else f"column {k}"
    return col, ("give --angle-unit deg, not rad" if column_unit(layout, k, "angle") is None else
                 f"correct the header of {col!r} to [deg]")


def degrees_as_radians(layout: Layout, k: int, angles, angle_unit: str | None) -> str | None:
    """The error line when the angle column ``k``, read as radians (its header's unit or --angle-unit rad), spans
    more than :data:`MAX_RADIAN_REVOLUTIONS` revolutions: angles in degrees (0 to 359.9) read as radians wind the
    profile 57 times round, and the 50-UPR filter then left a 0.34 µm RONt of a 4.08 µm part (circular test: G 1.43
    instead of 5.08 µm), exit 0. The counterpart of :func:`radians_as_degrees`; None otherwise."""
    a = np.asarray(angles, dtype=float)
    if a.size < 2 or not np.isfinite(a).all():
        return None
    span = float(a.max() - a.min())
    turns = span / (2 * np.pi)
    if turns <= MAX_RADIAN_REVOLUTIONS:
        return None
    col, todo = _degrees_fix(layout, k)
    return (f"{layout.name}: the angles of {col!r} span {span:.6g} rad ({turns:.3g} revolutions; a profile or a "
            f"circular-test run turns about once): they look like degrees; {todo}")


#: the round steps of degrees (°) an angle column is written in whose equal steps :func:`round_degrees_as_radians` names
ROUND_DEGREE_STEPS = (0.01, 0.02, 0.05, 0.1, 0.2, 0.25, 0.5, 1.0, 2.0, 2.5, 5.0, 10.0)


def round_degrees_as_radians(layout: Layout, k: int, angles, angle_unit: str | None) -> str | None:
    """A hint (asked, not an error) when the angle column ``k``, read as radians, turns more than once (an arc in
    degrees between 6.3° and the 25.1° beyond which :func:`degrees_as_radians` refuses) in equal steps of a round
    number of degrees (:data:`ROUND_DEGREE_STEPS`), every angle a whole multiple of it: 0, 0.1, ..., 20 under
    'Angle [rad]' is a 20° arc read as 3.2 revolutions (fit: radius 50.00041 for 49.99716 mm, exit 0, no word).
    Radian data over more than a revolution is sampled at 2 pi i / N, not at round decimals; one revolution or less
    is not named (a revolution in steps of 0.1 rad looks the same). None otherwise."""
    a = np.asarray(angles, dtype=float)
    if a.size < 3 or not np.isfinite(a).all():
        return None
    d = np.abs(np.diff(a))
    step = float(np.median(d))
    lo, hi = float(a.min()), float(a.max())
    if not hi - lo > 2 * np.pi + step:
        return None
    s = next((s for s in ROUND_DEGREE_STEPS if abs(step - s) <= 1e-9 * s), None)
    if s is None or not np.all(np.abs(d - s) <= 1e-6 * s) or not np.all(np.abs(a / s - np.rint(a / s)) <= 1e-6):
        return None
    col, todo = _degrees_fix(layout, k)
    return (f"the angles of {col!r} run from {lo:g} to {hi:g} in equal steps of {s:g}: read as radians they turn "
            f"{(hi - lo) / (2 * np.pi):.3g} times; if they are degrees (a {hi - lo:g}° arc), {todo}")


def two_blocks(layout: Layout, blocks: list, gaps: list | None = None) -> str:
    """The error line of a file of one profile (or run) holding ``blocks`` of data lines separated by blank lines,
    lines of separators only or comment lines (``gaps``, :func:`datasets.io.columns.data_blocks`): two diameters or
    heights of a part exported one after the other were read as one profile (RONt 3.01 µm 'ok' for two circles 20 µm
    apart in radius: the 50-UPR filter removed the zigzag between them)."""
    shown = ", ".join(f"{a}-{b}" for a, b in blocks[:4]) + (", ..." if len(blocks) > 4 else "")
    kinds = [k for gap in (gaps or [["blank"]]) for k in gap]
    comments = [k for k in kinds if isinstance(k, tuple)]
    what = [w for w, there in (("blank lines", "blank" in kinds), ("lines of separators only", "separators" in kinds),
                               ("comment lines", comments)) if there]
    label = f" ({comments[0][1]!r}, line {comments[0][0]})" if comments else ""
    return (f"{layout.name}: {len(blocks)} blocks of points separated by {' and '.join(what)}{label} (lines {shown}): "
            "one profile per file (a part's diameters or heights one after the other?); save each block in its own "
            "file (a circular test's two runs: or label them in a Direction column)")


#: an angle within this of one revolution from the first point's (rad) is the first point's angle
SAME_ANGLE_RAD = 1e-9


def xy_beyond_one_revolution(layout: Layout, points, circle: tuple | None = None) -> str | None:
    """:func:`beyond_one_revolution` of an x, y closed profile: the polar angles of its points about their circle's
    centre (:func:`circle_through`), in the file's order. A trace recorded over 371.9° in steps of 0.10003° (no angle
    repeated, so the evaluation's check of two points at one angle passed) was evaluated as one profile, RONt 4.3873
    µm 'ok'. One point past (a closing point measured again) is left to :func:`drop_closing_repeat` and the
    evaluation, as before: its polar angle about a fitted centre may fall either side of the first's. ``circle``:
    (xc, yc, r) of the points if already computed."""
    if (profile := profile_circle(points, circle)) is None:
        return None
    p, (xc, yc, _) = profile
    ang = np.arctan2(p[:, 1] - yc, p[:, 0] - xc)
    return beyond_one_revolution(layout, None, ang, np.hypot(p[:, 0] - xc, p[:, 1] - yc), single=False)


def beyond_one_revolution(layout: Layout, k: int | None, angles_rad, values, single: bool = True) -> str | None:
    """The error line when the angles of a closed profile (column ``k``, in radians, in the file's order) go on past
    one revolution from the first point: instruments record a little more than 360° to check closure (0 to 369.9°),
    and the roundness evaluation refused that as 'two points lie at the same polar angle (point 3666) ... (drop a
    repeated closing point)'. Names the file's lines beyond and the lines of the first revolution to keep; one point
    at the first one's angle with another value is named as such. None when the angles do not run one way (the
    evaluation decides), or the only point past is the first repeated (:func:`drop_closing_repeat` drops it), or is
    any single point without ``single`` (:func:`xy_beyond_one_revolution`); ``k`` None: x, y points, no column."""
    a = np.unwrap(np.asarray(angles_rad, dtype=float))
    if a.size < 4 or not np.isfinite(a).all():
        return None
    step = np.diff(a)
    sign = 1.0 if step[0] > 0 else -1.0
    if not (np.all(step * sign > 0)):
        return None
    swept = (a - a[0]) * sign
    past = np.flatnonzero(swept >= 2 * np.pi - SAME_ANGLE_RAD)
    v = np.asarray(values, dtype=float)
    if not past.size or (past.size == 1 and (not single or (past[0] == a.size - 1 and v[-1] == v[0]))):
        return None
    from datasets.io.columns import _data_fields
    lines = [n for n, _ in _data_fields(layout, [])]
    where = "line" if len(lines) == a.size else "point"
    if len(lines) != a.size:
        lines = list(range(1, a.size + 1))
    col = "" if k is None else layout.header[k] if layout.header else f"column {k}"
    first, keep = lines[0], lines[past[0] - 1]
    if past.size == 1:
        return (f"{layout.name} {where} {lines[past[0]]}: its angle ({col!r}) lies at the same polar angle as the first "
                f"point's ({where} {first}), one revolution on, with another value; a closed profile has one point per "
                f"angle: drop {where} {lines[past[0]]}")
    covered, step = float(np.degrees(swept[-1])), float(np.degrees(np.median(np.abs(step))))
    gon = ("; if the angles are in gon (400 a revolution), multiply the column by 0.9 and name its unit deg"
           if k is not None and 400 - 3 * step <= covered < 400 + step else "")
    about = " (the points' polar angles about their circle's centre)" if k is None else ""
    return (f"{layout.name}: the profile covers {covered:.6g}°{about}, more than one revolution ({past.size} "
            f"points at or beyond 360° from the first, {where}s {lines[past[0]]}-{lines[past[-1]]}); a roundness profile "
            f"is one revolution (ISO 12181-1): keep {where}s {first}-{keep}{gon}")


def read_profile(path, *, columns=None, plane=None, unit: str | None = None, skip_rows: int = 0,
                 angle_unit: str | None = None, nominal_radius: float | None = None,
                 min_arc_deg: float | None = None) -> CircularRuns:
    """One closed profile (roundness, a fit) in any instrument layout (:func:`read_runs`); deviations without
    ``nominal_radius`` are evaluated alone. A file holding two runs is refused (one profile is needed).
    ``min_arc_deg``: as :func:`read_runs` (a closed profile: 360, whose angles may not go on past one revolution,
    :func:`beyond_one_revolution`)."""
    got = read_runs(path, columns=columns, plane=plane, unit=unit, skip_rows=skip_rows, angle_unit=angle_unit,
                    nominal_radius=nominal_radius, need_nominal_radius=False, min_arc_deg=min_arc_deg,
                    one_revolution=min_arc_deg is not None and min_arc_deg >= 360.0)
    if len(got.runs) != 1:
        raise DataFileError(f"{got.source}: holds {len(got.runs)} runs ({', '.join(l for l, _ in got.runs)}); "
                            "give a file with one profile")
    pts, note = drop_closing_repeat(got.runs[0][1])
    if note is not None:
        got.runs[0] = (got.runs[0][0], pts)
        got.notes.append(note)
    return got


#: a last point within this many units of roundoff of the coordinates' size from the first repeats it (an x, y file's
#: exact repeat; an angle + deviation file's 360° point, whose sine is -2.4e-16, not 0, at the same deviation)
CLOSING_REPEAT_ULPS = 16


def drop_closing_repeat(points) -> tuple[np.ndarray, str | None]:
    """(``points`` without a last point that repeats the first, a note saying so; or ``points`` and None): a closed
    trace as many instruments export it, its first point written again at the end (x, y equal, or 360° at the
    0° deviation) is one position measured once; kept, it is two points at one polar angle, which a roundness
    evaluation refuses (ISO 12181 profiles have one point per angle) and a fit weights twice."""
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or len(pts) < 4 or not np.isfinite(pts[[0, -1]]).all():
        return pts, None
    size = float(np.max(np.abs(pts[[0, -1]])))
    if not np.all(np.abs(pts[-1] - pts[0]) <= CLOSING_REPEAT_ULPS * np.finfo(float).eps * size):
        return pts, None
    return pts[:-1], (f"the last point repeats the first (a closed trace written back to its start): dropped, "
                      f"{len(pts) - 1} points evaluated")


CW_WORDS = {"cw", "g02", "g2", "clockwise", "-", "-1"}
CCW_WORDS = {"ccw", "g03", "g3", "counterclockwise", "counter-clockwise", "anticlockwise", "+", "+1", "1"}
