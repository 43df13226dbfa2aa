"""The two magnification algorithms of Ibaraki & Matsubara (2009), vectorised with shapely.

Both map each measured point p(k) to p~(k) = r~(k) + eta (p(k) - r~(k)) for a reference point r~(k).
* ``magnify.nearest`` (their sec. 1, the conventional algorithm): r~(k) = the nearest point of R.
* ``magnify.offset`` (their sec. 2): offset R by -delta and +delta (contour-parallel offsets, exact round
  joins), take the closest point q~(k) on an offset, and r~(k) = where the line from q~(k) through p(k)
  meets R. ``selection="nearest_of_both"`` is step (2) as printed ("on either of the offset
  trajectories"); the default ``"same_side"`` takes q~(k) on the offset on p(k)'s side of R. The printed
  rule jumps near corners: just inside the delta x delta corner square the far offset's straight edge
  (distance delta + e) is nearer than the near offset's corner (distance up to delta sqrt 2), so q~ and
  with it r~ switch from a perpendicular to a radial projection (README, study ``magnification``).
  Points whose line misses R (beyond the ends of an open reference) use the nearest point of R;
  ``extra['nearest_point_used']`` counts them.
"""
from __future__ import annotations

import numpy as np

from methods._errors import InvalidInputError
from methods._registry import register
from methods.magnify.results import MagnifyFit
from methods._validation import check_choice, check_positive
from methods.magnify.data import MagnifyInput, continuity, self_intersections, validate
from methods._lazy import lazy_module

shapely = lazy_module("shapely")


def _signed_error(line, pts_geom, pts):
    """Nearest reference points, distances and the side (+1 left, -1 right of the direction of R)."""
    d = shapely.line_locate_point(line, pts_geom)
    r = shapely.get_coordinates(shapely.line_interpolate_point(line, d))
    eps = 1e-7 * line.length
    before = shapely.get_coordinates(shapely.line_interpolate_point(line, np.clip(d - eps, 0, line.length)))
    after = shapely.get_coordinates(shapely.line_interpolate_point(line, np.clip(d + eps, 0, line.length)))
    t = after - before  # the local direction; at a vertex the chord across it (the bisector's normal)
    v = pts - r
    side = np.sign(t[:, 0] * v[:, 1] - t[:, 1] * v[:, 0])
    return r, np.hypot(*v.T), side


def _nearest_on(geom, pts_geom):
    return shapely.get_coordinates(shapely.shortest_line(geom, pts_geom))[0::2]


def _eta(eta, method_id) -> float:
    """The magnification: a finite positive number (nan, inf, 0, -5 and 'abc' are refused)."""
    return float(check_positive("eta", eta, method_id))


def _finish(data: MagnifyInput, r, eta, extra, message, err):
    """The result. ``err``: the contouring errors, each measured point's distance from R (the magnification
    paper's contouring error, whichever method maps it); ``residuals`` and ``form_error`` (their largest) are
    these for every method. The distance |p - r~| to the point r~ the method magnifies about is another
    quantity: at a corner magnified radially (the offset method) it is the distance to the corner, larger than
    the contouring error; its largest is ``extra['max_magnified_distance']``."""
    p = data.measured
    mag = r + eta * (p - r)
    e_max = float(np.max(err))
    return MagnifyFit(points=mag, reference_points=r, form_error=e_max, residuals=err,
                      converged=bool(np.isfinite(mag).all()), message=message,
                      extra={**extra, "max_contouring_error": e_max,
                             "max_magnified_distance": float(np.nanmax(np.hypot(*(p - r).T))),
                             "continuity": continuity(mag, p, eta), "self_intersections": self_intersections(mag)})


@register("magnify.nearest", kind="closed form", validator=validate,
          summary="Conventional magnification: r~ = nearest point of the reference, p~ = r~ + eta (p - r~)",
          reference="Ibaraki & Matsubara, Precis. Eng. 33 (2009) 322-326, sec. 1 steps (1)-(3)")
def nearest(data, *, eta=1000.0):
    """The commercial software's algorithm: discontinuous wherever the nearest point of R jumps (corners,
    finely segmented paths)."""
    eta = _eta(eta, "magnify.nearest")
    line = data.line
    pts_geom = shapely.points(data.measured)
    r, err, _ = _signed_error(line, pts_geom, data.measured)
    return _finish(data, r, float(eta), {}, "nearest-point magnification", err)


@register("magnify.offset", kind="closed form", validator=validate,
          summary="Contour-parallel-offset magnification (offsets at +-delta, line from the offset point to p meets R)",
          reference="Ibaraki & Matsubara, Precis. Eng. 33 (2009) 322-326, sec. 2 steps (1)-(4), eq. 1")
def offset(data, *, eta=1000.0, delta=None, delta_emax=None, selection="same_side"):
    """Steps (1)-(4) of the paper with offsets from shapely (exact, round joins). The offset distance must
    exceed the largest contouring error e_max: give it as ``delta`` (data units) or as ``delta_emax``, a
    multiple of e_max (default: ``delta_emax=2``, the paper's condition). ``selection``: ``"same_side"``
    (default, continuous at corners) or ``"nearest_of_both"`` (step (2) as printed)."""
    eta = _eta(eta, "magnify.offset")
    check_choice("selection", selection, ("same_side", "nearest_of_both"), "magnify.offset")
    if delta is not None and delta_emax is not None:
        raise InvalidInputError("magnify.offset: give delta (data units) or delta_emax (a multiple of the largest "
                                "contouring error), not both")
    if delta_emax is not None:
        delta_emax = float(check_positive("delta_emax", delta_emax, "magnify.offset"))
    line = data.line
    pts_geom = shapely.points(data.measured)
    r0, err, side = _signed_error(line, pts_geom, data.measured)
    emax = float(err.max())
    delta = (2.0 if delta_emax is None else delta_emax) * emax if delta is None else float(delta)
    if not delta > emax:
        exc = InvalidInputError(f"magnify.offset: delta = {delta:g} must be larger than the largest contouring "
                                f"error ({emax:g}, data units); choose a larger delta")
        exc.delta_emax = (delta, emax)   # the CLI says them in its units
        raise exc
    q_left = line.offset_curve(delta, join_style="round")
    q_right = line.offset_curve(-delta, join_style="round")
    for q_side, name in ((q_left, "left"), (q_right, "right")):
        if q_side.is_empty:
            raise InvalidInputError(f"magnify.offset: delta = {delta:g} is too large for this reference: its {name} "
                                    "offset vanishes (delta exceeds the size of its features); choose a smaller --delta")
    a, b = _nearest_on(q_left, pts_geom), _nearest_on(q_right, pts_geom)
    if selection == "same_side":
        use_left = side > 0
        on_line = side == 0
    else:
        da, db = np.hypot(*(a - data.measured).T), np.hypot(*(b - data.measured).T)
        use_left = da <= db
        on_line = np.zeros(len(da), dtype=bool)
    q = np.where(use_left[:, None], a, b)
    # step (3): the line from q through p meets R; the ray q + s (p - q) for s in [0, 3 delta / |p - q|]
    u = data.measured - q
    norm = np.hypot(*u.T)
    far = q + u / np.where(norm > 0, norm, 1.0)[:, None] * (3.0 * delta)
    rays = shapely.linestrings(np.stack([q, far], axis=1))
    hits = shapely.intersection(rays, line)
    empty = shapely.is_empty(hits)
    r = np.full_like(data.measured, np.nan)
    if (~empty).any():
        r[~empty] = _nearest_on_each(hits[~empty], pts_geom[~empty])
    r[on_line] = data.measured[on_line]
    # Beyond the ends of an open reference (or on its end point, by rounding) the ray can miss R: there
    # the offsets end and the construction is undefined, and the nearest point of R is used (counted).
    miss = empty & ~on_line
    r[miss] = r0[miss]
    return _finish(data, r, float(eta), {"delta": delta, "selection": selection, "nearest_point_used": int(miss.sum())},
                   f"offset magnification ({selection})", err)


def _nearest_on_each(geoms, pts_geom):
    """For each (geometry, point) pair, the point of the geometry nearest to the point."""
    return shapely.get_coordinates(shapely.shortest_line(geoms, pts_geom))[0::2]
