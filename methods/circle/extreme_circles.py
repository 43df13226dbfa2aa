"""Minimum circumscribed (MCC) and maximum inscribed (MIC) circles of a roundness profile."""
from __future__ import annotations

import numpy as np

from methods._registry import register
from methods.circle.results import zone_result
from methods.result_base import radial_distances
from methods._validation import check_choice, check_positive
from methods.circle import _zone as z
from methods.circle._frame import Frame
from methods.circle.minimum_zone import check_ccp_params, convex_concave, linearised_inner_rows, outer_cone_rows


#: sizes of the candidate pool (most extreme active points) tried in turn by the exact step
POOL_SIZES = (8, 16, 32, 64)


def _best_single_sided(x, y, act, c, side):
    """Exact centre from the 2- and 3-point circles of the ``m`` most extreme active points about the
    solver's centre c, best over the active set. On a smooth (filtered) profile many neighbours of one
    contact have nearly equal radii, so the 8 most extreme may all lie near one or two contacts and miss
    the third: the pick then depends on the last bit of the data. The pool grows (POOL_SIZES) until the
    picked circle's tied contacts surround its centre (the optimality condition), so the exact step no
    longer stops on a wrong configuration that a one-ulp change of the data would have avoided. When no pool
    does, the points are ranked again about the picked (exact) centre and the pools tried again (up to
    RECENTRE times): about the solver's centre, accurate to ~1e-8, the points of one flat peak can outrank every
    point of the opposite one (an ovality of 1e-7 of the radius sampled at 0.05 deg)."""
    best = None
    for _ in range(RECENTRE + 1):
        r = z.radii(x[act], y[act], c)
        order = np.argsort(r)
        ranked = order[::-1] if side == "outer" else order
        for m in POOL_SIZES:
            m = min(act.size, m)
            idx = act[ranked[:m]]
            cands = z.circle_candidates(x, y, idx, c, side)
            hi, lo = z.candidate_extremes(x, y, act, cands.C)
            pick = (z.pick(cands, hi, minimise=True) if side == "outer" else z.pick(cands, lo, minimise=False))
            if best is None or _better(x, y, act, pick[0], best[0], side):
                best = pick
            if _surrounds(x, y, act, best[0], side):
                return best
            if m >= act.size:
                break
        if np.array_equal(best[0], c):
            break
        c = best[0]
    return best


#: times :func:`_best_single_sided` ranks the points again about its best exact centre
RECENTRE = 2


def _better(x, y, act, a, b, side) -> bool:
    """Is centre a strictly better than centre b over the active points (smaller enclosing / larger empty circle)?"""
    ra, rb = z.radii(x[act], y[act], a), z.radii(x[act], y[act], b)
    return ra.max() < rb.max() if side == "outer" else ra.min() > rb.min()


def _surrounds(x, y, act, c, side) -> bool:
    """Do the active points tied at centre c (within :func:`methods.circle._zone.tie_tolerance` of the extreme
    radius, the final check's slack) surround it?"""
    r = z.radii(x[act], y[act], c)
    extreme = r.max() if side == "outer" else r.min()
    tol = z.tie_tolerance(extreme)
    tied = act[r >= extreme - tol] if side == "outer" else act[r <= extreme + tol]
    return z.surrounding_contacts(x, y, c, tied) is not None


def largest_angular_gap(x, y, c) -> float:
    """Largest angle (radians) between consecutive points seen from c: >= pi means the points lie in
    a half-plane through c and do not surround it."""
    t = np.sort(np.arctan2(y - c[1], x - c[0]))
    return float(max(np.diff(t).max(initial=0.0), 2 * np.pi - (t[-1] - t[0])))


def _mcc_certify(x, y):
    """The hull certificate of :func:`methods.circle._zone.certify_hulls`, its message stating what was checked
    and to which tolerance (KKT of the convex program min R s.t. |p_i - c| <= R)."""
    hull = z.certify_hulls(x, y)

    def certify(c, oc, ic):
        ok, message = hull(c, oc, ic)
        if ok:
            message += (f"; checked: every point within (1 + {z.CHECK_RTOL:g}) x the contacts' radius, so no circle "
                        f"holding all points is smaller by more than {z.CHECK_RTOL:g} x the radius")
        return ok, message
    return certify


@register("circle.min_circumscribed", kind="convex program",
          summary="Minimum circumscribed circle (MCC): SOCP (clarabel) on an active set, exact contacts",
          reference="roundness paper sec. 1 (MDTD, table 1 column MCC); Elzinga & Hearn, Transp. Sci. 6 (1972) 379-394")
def min_circumscribed(points, *, active_size=16, max_rounds=50):
    """Smallest circle containing all points: min R s.t. |p_i - c| <= R (second-order cones, one
    convex program, global optimum). Only the outermost points reach clarabel (active set with a final
    check of every point); the centre is then solved exactly from its 2 (diameter) or 3 contacts and
    certified by the centre lying in the convex hull of the points within 1e-12 of the largest radius (the final
    check's slack), or, when the extreme points lie nearly on a semicircle, by the smallest circle of a pair or
    triple of the outermost points (a lower bound) within 1e-12 of R: the program is convex, so this is a
    global certificate over all centres (``extra['certified'] == "global"``): no circle holding all points is
    smaller by more than 1e-12 x R (docs/certificates.md).
    ``radius`` = R; ``form_error`` = R - min_i |p_i - c| (roundness about the MCC centre)."""
    name = "circle.min_circumscribed"
    k = int(check_positive("active_size", active_size, name))
    max_rounds = int(check_positive("max_rounds", max_rounds, name))
    frame = Frame.of(points)
    x, y = frame.x, frame.y

    def local_solve(out, inn, c):  # variables (cx, cy, R): min R
        rows, rhs, cones = outer_cone_rows(x, y, out, 2, 3)
        sol, _, it = z.clarabel_solve([0.0, 0.0, 1.0], rows, rhs, cones)
        return sol[:2], 1, it, [sol[2]]

    start = z.kasa_normal(x, y)
    result = z.fit_zone(points, frame, start=start, local_solve=local_solve,
                        exact=lambda act, c: _best_single_sided(x, y, act, c, "outer"),
                        certify=_mcc_certify(x, y), sides=("outer",), k=k, max_rounds=max_rounds,
                        radius_rule=lambda r, c: r.max())
    gap = largest_angular_gap(x, y, start)
    result.extra["angular_gap_deg"] = float(np.degrees(gap))
    if gap >= np.pi:   # the MCC is right (and certified), but it is not the arc's circle
        result.extra.setdefault("notes", []).append(partial_arc_note("the minimum circumscribed circle", gap))
    return result


def partial_arc_note(what: str, gap: float) -> str:
    """The note of a circle that holds a partial arc (largest angular gap ``gap`` rad >= pi about the points'
    algebraic centre) but is not the arc's circle: the MCC of a 90 deg arc has the chord as its diameter."""
    return (f"the points do not surround a centre (largest angular gap {np.degrees(gap):.1f}° >= 180°, a partial "
            f"arc): {what} holds the arc but is not its circle, and its form error is not the arc's roundness; "
            "use circle.minimum_zone or a least-squares fit (circle.gauss_newton)")


@register("circle.max_inscribed", kind="convex program",
          summary="Maximum inscribed circle (MIC): sequential LP (clarabel) on an active set, exact contacts",
          reference="roundness paper sec. 1 (MİTD, table 1 column MIC); Toussaint, Int. J. Comput. Inf. Sci. 12 (1983) 347-358")
def max_inscribed(points, *, active_size=16, max_rounds=50, max_ccp=30, ccp_tol=1e-8, trust_radius=0.5,
                  global_search="always"):
    """Largest circle with no point inside it, centred among the points: max r s.t. |p_i - c| >= r.
    The constraint is reverse-convex: each step maximises r under its linearisation at the current
    centre (a lower bound, so feasible), an LP solved by clarabel inside a trust region, until the
    centre settles; the centre is then solved exactly from its 2 or 3 contacts and certified by lying
    in their convex hull. Points that do not surround a centre (a partial arc) have no inscribed
    circle: the result says so with ``converged=False``.
    ``radius`` = r; ``form_error`` = max_i |p_i - c| - r (roundness about the MIC centre).

    The MIC is defined for centres inside the profile polygon (the points joined in angular order
    about their centroid): a centre outside it has no inscribed circle. It is multimodal (every Voronoi
    vertex inside its Delaunay triangle is a local maximum; sparse noisy profiles have several close
    together), so the local certificate (the tied contacts surround the centre) proves a LOCAL maximum
    only. With ``global_search="always"`` (default) a branch and bound over the centre
    (:mod:`methods.circle._global`) proves that no centre inside the profile polygon gives an empty
    circle larger by more than 1e-10 x r + 1e-13 x the data's RMS radius + the returned centre's float
    resolution (the message states the sum in data units; docs/certificates.md); a better centre restarts the
    local solver there, and a local centre outside the polygon is never returned as a MIC.
    ``extra['certified']``: "global", "local" or False; ``converged`` is True for either certificate."""
    name = "circle.max_inscribed"
    k, max_rounds, max_ccp = check_ccp_params(name, active_size, max_rounds, max_ccp, ccp_tol, trust_radius)
    frame = Frame.of(points)
    x, y = frame.x, frame.y

    def local_solve(out, inn, c):
        def once(ck):  # variables (cx, cy, r): min -r
            rows, rhs = linearised_inner_rows(x, y, inn, ck, 2, 3)
            tr_rows, tr_b = z.trust_rows(ck, trust_radius, 3)
            sol, _, it = z.clarabel_solve([0.0, 0.0, -1.0], rows + tr_rows, rhs + tr_b,
                                          [z.clarabel.NonnegativeConeT(len(rows) + 4)])
            return sol, it
        return convex_concave(once, c, max_ccp, ccp_tol, lambda s: s[2])

    start = z.kasa_normal(x, y)
    gap = largest_angular_gap(x, y, start)
    if gap >= np.pi:
        center, _ = frame.circle_to_data(np.array([start[0], start[1], 1.0]))
        r = radial_distances(points, center)
        return zone_result(points, center, r.min(), {"outer": [], "inner": []}, converged=False,
                           message=(f"the points do not surround a centre (largest angular gap {np.degrees(gap):.1f} deg "
                                    ">= 180 deg, a partial arc): a maximum inscribed circle does not exist"),
                           extra={"certified": False, "angular_gap_deg": float(np.degrees(gap))})
    check_choice("global_search", global_search, ("always", "never"), name)
    hull = z.certify_hulls(x, y)

    def certify(c, oc, ic):
        ok, message = hull(c, oc, ic)
        if not ok:
            message += ("; the inscribed circle grows without bound when the points do not surround a "
                        "centre (a partial arc has no MIC)")
        return ok, message

    result = z.fit_zone(points, frame, start=start, local_solve=local_solve,
                        exact=lambda act, c: _best_single_sided(x, y, act, c, "inner"),
                        certify=certify, sides=("inner",), k=k, max_rounds=max_rounds,
                        radius_rule=lambda r, c: r.min(), proof="inscribed", global_search=global_search)
    result.extra["angular_gap_deg"] = float(np.degrees(gap))
    if not result.converged and gap > np.radians(150):
        result.message += (f"; the points barely surround a centre (largest angular gap {np.degrees(gap):.1f} deg): "
                           "the inscribed circle of such a partial arc is ill-defined")
    return result
