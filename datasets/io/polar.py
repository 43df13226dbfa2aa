"""Angle + radial deviation (or radius) as x, y points (:func:`polar_to_points`): deviations without a
nominal radius are placed about a circle :data:`DEVIATION_ALONE_RADIUS_FACTOR` times their span (the limaçon
evaluation of roundness instruments, ISO 12181-1 clause 3); the angle column's unit (:func:`angle_unit_of`); a
deviation column without a unit is read as mm, with a warning beyond :data:`ASSUMED_DEVIATION_LIMIT_MM`; deviations
spanning less than :data:`SMALLEST_DEVIATION_SPAN_MM` are warned about naming the likely unit
(:func:`warn_too_small`)."""
from __future__ import annotations

import warnings

import numpy as np

from datasets.io.headers import column_unit
from datasets.io.layout import Layout
from datasets.io.numbers import DataFileError


def angle_unit_of(layout: Layout, k: int, angle_unit: str | None) -> str:
    """'deg' or 'rad' for the angle column ``k``: the header's unit or ``angle_unit`` (--angle-unit); a
    contradiction, or neither, is an error."""
    header = column_unit(layout, k, "angle")
    if angle_unit is not None and angle_unit not in ("deg", "rad"):
        raise DataFileError(f"--angle-unit must be deg or rad, got {angle_unit!r}")
    if header is not None and angle_unit is not None and header != angle_unit:
        raise DataFileError(f"{layout.name}: the header says column {layout.header[k]!r} is in {header} but "
                            f"--angle-unit says {angle_unit}; drop --angle-unit or correct the header")
    au = header or angle_unit
    if au is None:
        raise DataFileError(f"{layout.name}: is the angle column {layout.header[k] if layout.header else k!r} in "
                            "degrees or radians? name it 'angle [deg]' / 'angle [rad]' or give --angle-unit deg|rad")
    return au


#: deviations alone (no nominal radius) are placed about a radius this many times their span: the circle's
#: curvature then changes the RON parameters by about 1 / this factor (the limaçon approximation of
#: roundness instruments, ISO 12181-1 clause 3)
DEVIATION_ALONE_RADIUS_FACTOR = 1e6


def polar_to_points(angles_rad, values_mm, polar_value: str, nominal_radius: float | None,
                    nominal_center=(0.0, 0.0), name: str = "data") -> tuple[np.ndarray, str | None]:
    """Angle + radial deviation (about ``nominal_radius``) or radius, as x, y about ``nominal_center`` (mm),
    and a note when the deviations had no nominal radius. A radius (nominal + deviation) <= 0 is refused: the
    point would be placed on the opposite side of the centre and every form figure would be wrong."""
    note = None
    if polar_value == "radius":
        r = values_mm
    else:
        if nominal_radius is None:
            span = float(np.ptp(values_mm)) if values_mm.size else 0.0
            nominal_radius = max(DEVIATION_ALONE_RADIUS_FACTOR * span, 1.0)
            note = (f"radial deviations without a nominal radius: placed about a circle of {nominal_radius:.6g} mm "
                    f"({DEVIATION_ALONE_RADIUS_FACTOR:g} x their span; form parameters as an instrument's limaçon "
                    "evaluation; centre and radius are not the part's)")
        r = float(nominal_radius) + values_mm
    bad = np.flatnonzero(~(r > 0))
    if bad.size:
        k = int(np.argmin(r))
        if polar_value == "radius":
            raise DataFileError(f"{name}: a radius of {r[k]:.6g} mm (point {k + 1}); radii must be > 0 (if the column "
                                "holds radial deviations, name it 'Deviation' with its unit)")
        raise DataFileError(f"{name}: the nominal radius {float(nominal_radius):g} mm + the radial deviation "
                            f"{values_mm[k] * 1e3:.6g} µm (point {k + 1}) is {r[k]:.6g} mm <= 0; give the part's "
                            "nominal radius in mm (--nominal-radius)")
    cx, cy = (float(v) for v in nominal_center)
    return np.column_stack([cx + r * np.cos(angles_rad), cy + r * np.sin(angles_rad)]), note


#: radial deviations (of an angle + deviation file) read as mm because neither the header nor ``--unit`` gives a
#: unit, beyond which µm is the likelier unit: roundness and ballbar traces deviate by tens of µm, and an
#: instrument exporting µm without a unit (±0.8 µm read as ±0.8 mm) would turn RONt or G into mm
ASSUMED_DEVIATION_LIMIT_MM = 0.1


def _unit_assumed(layout: Layout, k: int, values) -> str:
    """The note saying a unit-less deviation column was read as mm; a :class:`~methods.units.UnitWarning` too
    when its deviations exceed :data:`ASSUMED_DEVIATION_LIMIT_MM` (the likely unit and the options named)."""
    from methods.units import UnitWarning
    col = repr(layout.header[k]) if layout.header else f"{k} (0-based)"
    v = np.abs(np.asarray(values, dtype=float))
    largest = float(np.max(v[np.isfinite(v)])) if np.isfinite(v).any() else 0.0
    if largest > ASSUMED_DEVIATION_LIMIT_MM:
        warnings.warn(f"radial deviations up to {largest:.6g} mm in {layout.name} (read as mm: the column {col} names "
                      f"no unit) are implausible for a circular test or a roundness trace (tens of µm); is the deviation "
                      f"column in µm? (--unit um), or give --unit mm to keep mm", UnitWarning, stacklevel=4)
    return f"the deviation column {col} names no unit: read as mm (give --unit um if it is in µm)"


#: radial deviations (of an angle + deviation file) spanning less than this (10 nm) are not a measured trace: a ballbar
#: resolves 0.1 µm (Renishaw QC20-W), the best roundness spindles run true to about 0.02 µm (their radial error
#: motion is in every trace), and a machine tool's circular path deviates by micrometres; the same 10 nm below which
#: positioning deviations are warned about (methods.positioning.data). Deviations in mm under a µm header (4 µm
#: written 0.004) span a few nm: G 0.01 µm, RONt 0.004 µm were printed, exit 0
SMALLEST_DEVIATION_SPAN_MM = 1e-5


def warn_too_small(layout: Layout, k: int, values_mm, unit: str, given: str | None) -> bool:
    """Warn (:class:`~methods.units.UnitWarning`) when the radial deviations ``values_mm`` (column ``k``, read in
    ``unit``; ``given``: --unit, or None) span less than :data:`SMALLEST_DEVIATION_SPAN_MM` but not 0 (an exact
    constant is a made-up trace, not a unit mistake), naming the unit 1000 times larger and where to declare it."""
    from methods.units import UnitWarning, canonical, mm_per
    v = np.asarray(values_mm, dtype=float)
    v = v[np.isfinite(v)]
    span = float(np.ptp(v)) if v.size else 0.0
    if not 0 < span < SMALLEST_DEVIATION_SPAN_MM:
        return False
    col = repr(layout.header[k]) if layout.header else f"{k} (0-based)"
    larger = {"nm": "µm", "µm": "mm", "mm": "m"}.get(unit)
    if column_unit(layout, k, "length") is not None:
        source, todo = f"as the header of {col} says", f"correct the header to [{larger}]"
    elif given is not None:
        source, todo = "as --unit says", f"give --unit {(larger or '').replace('µ', 'u')}"
    else:
        source, todo = f"the column {col} names no unit", f"give --unit {(larger or '').replace('µ', 'u')}"
    ask = f"is the column in {larger}? ({todo})" if larger else "check the column's unit"
    warnings.warn(f"radial deviations in {layout.name} span {span * 1e3:.3g} µm (read as {canonical(unit)}, {source}): "
                  f"below the 10 nm a ballbar or a roundness instrument resolves, not a measured trace; {ask}",
                  UnitWarning, stacklevel=4)
    return True


#: radii (of an angle + radius file) varying by more than this fraction of their median are not a roundness profile
#: or a circular path (RONt or a ballbar's deviations are micrometres on millimetres: below 1e-2 of the radius even
#: for a rough 1 mm pin): the 'Radius' column likely holds radial deviations offset to stay positive, as some form
#: testers export them (6.3 to 14.5 µm read as radii: a 10 µm circle, RONt 3.89 µm 'ok' of a 4.08 µm part)
RADIUS_SPAN_FRACTION = 0.1


def warn_radius_like_deviation(layout: Layout, k: int, radii_mm, unit: str) -> bool:
    """Warn (:class:`~methods.units.UnitWarning`) when the radii ``radii_mm`` of column ``k`` (read in ``unit``) vary
    by more than :data:`RADIUS_SPAN_FRACTION` of their median, naming the range and what to name the column."""
    from methods.units import UnitWarning, canonical, mm_per
    r = np.asarray(radii_mm, dtype=float)
    r = r[np.isfinite(r)]
    if r.size < 3:
        return False
    mid, span = float(np.median(r)), float(np.ptp(r))
    if not (mid > 0 and span > RADIUS_SPAN_FRACTION * mid):
        return False
    col = layout.header[k] if layout.header else f"column {k}"
    f = mm_per(unit)
    warnings.warn(f"radii in {layout.name} run from {r.min() / f:.6g} to {r.max() / f:.6g} {canonical(unit)} "
                  f"(column {col!r}): they vary by {span / mid:.0%} of themselves, no roundness profile or circular "
                  f"path does; does the column hold radial deviations? name it 'Deviation [{canonical(unit)}]' (and "
                  "give --nominal-radius for circular-test)", UnitWarning, stacklevel=4)
    return True


def circle_through(points) -> tuple[float, float, float]:
    """(xc, yc, r) of the algebraic least-squares circle of ``points`` (Kåsa 1976: x² + y² = 2 xc x + 2 yc y + c,
    about the centroid for conditioning): the centre the reader counts polar angles about and measures a radial
    span from, not a fit result. NaNs when the points are collinear."""
    p = np.asarray(points, dtype=float)
    m = p.mean(axis=0)
    q = p - m
    a = np.column_stack([2 * q, np.ones(len(q))])
    sol, _, rank, _ = np.linalg.lstsq(a, np.einsum("ij,ij->i", q, q), rcond=None)
    r2 = sol[2] + sol[0] ** 2 + sol[1] ** 2
    if rank < 3 or not (np.isfinite(sol).all() and r2 > 0):   # collinear (or coincident) points: no circle
        return np.nan, np.nan, np.nan
    return float(m[0] + sol[0]), float(m[1] + sol[1]), float(np.sqrt(r2))


def profile_circle(points, circle: tuple | None = None) -> tuple[np.ndarray, tuple] | None:
    """(the points as an (N, 2) float array, (xc, yc, r) of their circle: ``circle`` when already computed, else
    :func:`circle_through`) of an x, y profile a reader checks further, or None when there is nothing to check: not
    (N, 2), fewer than 4 points, a value that is not finite, or no circle (NaNs)."""
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or len(p) < 4 or not np.isfinite(p).all():
        return None
    circle = circle_through(p) if circle is None else circle
    return (p, circle) if np.isfinite(circle).all() else None


def decimal_step(values) -> float:
    """The largest power of ten of which every finite value is a whole multiple (0.001 for numbers written with three
    decimals), i.e. the rounding step of the numbers as written; 0 when none up to 1e-15 is (full binary floats)."""
    v = np.abs(np.asarray(values, dtype=float))
    v = v[np.isfinite(v)]
    if not v.size:
        return 0.0
    for d in range(-6, 16):
        s = v * 10.0 ** d
        if s.max() >= 2.0 ** 52:
            break
        if np.all(np.abs(s - np.rint(s)) <= 1e-6 + 8 * np.finfo(float).eps * s):
            return 10.0 ** -d
    return 0.0


#: an x, y profile's radial span about its circle must be at least this many steps of the numbers' rounding to be a
#: measured form (an exact circle written to 6 decimals spans 1 or 2 of them: a made-up profile, not a unit mistake)
SPAN_ROUNDING_STEPS = 20


def warn_too_small_xy(layout: Layout, idx, points_mm, written, unit: str, given: str | None,
                      circle: tuple | None = None) -> bool:
    """The x, y counterpart of :func:`warn_too_small`: warn (:class:`~methods.units.UnitWarning`) when the points'
    radial distances from their circle (:func:`circle_through`) span less than :data:`SMALLEST_DEVIATION_SPAN_MM`, but
    at least :data:`SPAN_ROUNDING_STEPS` steps of the rounding of the numbers ``written`` (the x and y columns as
    read, in ``unit``: :func:`decimal_step`) and 1e-9 of the radius (an exact circle's are roundoff): a 10 mm part's
    x, y in mm read as µm span 0.005 µm about a radius of 0.01 mm (RONt 0.0041 µm 'ok' was printed). Names the unit
    1000 times larger and where to declare it. ``circle``: (xc, yc, r) of the points if already computed."""
    from methods.units import UnitWarning, canonical
    if (profile := profile_circle(points_mm, circle)) is None:
        return False
    p, (xc, yc, r) = profile
    span = float(np.ptp(np.hypot(p[:, 0] - xc, p[:, 1] - yc)))
    if not (span < SMALLEST_DEVIATION_SPAN_MM and span > 1e-9 * r):
        return False
    from methods.units import to_mm
    if span < SPAN_ROUNDING_STEPS * to_mm(max(decimal_step(c) for c in written), unit):
        return False
    cols = [repr(layout.header[k]) if layout.header else f"{k} (0-based)" for k in idx]
    larger = {"nm": "µm", "µm": "mm", "mm": "m"}.get(canonical(unit))
    if any(column_unit(layout, k, "length") is not None for k in idx):
        source, todo = f"as the header of {' and '.join(cols)} says", f"correct the header to [{larger}]"
    elif given is not None:
        source, todo = "as --unit says", f"give --unit {(larger or '').replace('µ', 'u')}"
    else:
        source, todo = "the columns name no unit", f"give --unit {(larger or '').replace('µ', 'u')}"
    ask = f"is the file in {larger}? ({todo})" if larger else "check the file's unit"
    warnings.warn(f"the points' distances from the centre of their circle in {layout.name} span {span * 1e3:.3g} µm "
                  f"about a radius of {r:.6g} mm (read as {canonical(unit)}, {source}): below the 10 nm a roundness "
                  f"instrument, a CMM or a ballbar resolves, not a measured profile; {ask}", UnitWarning, stacklevel=4)
    return True
