"""Minimum-zone circles (MZC): the thinnest annulus of two concentric circles holding all points."""
from __future__ import annotations

import clarabel
import numpy as np

from methods._registry import register
from methods._result import zone_result
from methods._validation import check_positive
from methods.circle import _zone as z
from methods.circle._frame import Frame


def _socp(x, y, out, inn, ck, delta):
    """One convex subproblem (variables cx, cy, R, r): min R - r subject to |p_i - c| <= R (second-order
    cones, outer set) and r <= |p_j - ck| + g_j.(c - ck) (the inner constraint linearised at ck, a lower
    bound of the convex |p_j - c|, so every solution is feasible for the true problem), |c - ck| <= delta."""
    dx, dy = x[inn] - ck[0], y[inn] - ck[1]
    rk = np.sqrt(dx * dx + dy * dy)
    gx, gy = -dx / rk, -dy / rk  # gradient of |p - c| at ck
    rows = [np.array([-a, -b, 0.0, 1.0]) for a, b in zip(gx, gy)]
    rhs = list(rk - gx * ck[0] - gy * ck[1])
    tr_rows, tr_b = z.trust_rows(ck, delta, 4)
    rows += tr_rows
    rhs += tr_b
    cones = [clarabel.NonnegativeConeT(len(rhs))]
    for i in out:
        rows += [np.array([0.0, 0.0, -1.0, 0.0]), np.array([1.0, 0.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0, 0.0])]
        rhs += [0.0, x[i], y[i]]
        cones.append(clarabel.SecondOrderConeT(3))
    sol, _, iters = z.clarabel_solve([0.0, 0.0, 1.0, -1.0], rows, rhs, cones)
    return sol, iters


def _enumerate(x, y, act, c, m):
    """Exact centre among contact configurations of the m outermost and m innermost active points
    about c: 2 outer + 2 inner (bisector intersection), 3 + 1 and 1 + 3 (circumcentres). Returns the
    centre of least width over the active points and its (outer, inner) contact indices."""
    r = z.radii(x[act], y[act], c)
    order = np.argsort(r)
    inner_c, outer_c = act[order[:m]], act[order[::-1][:m]]
    P = np.column_stack([x, y])
    cands, configs = [], []  # configs rows: 4 point indices + number of outer contacts (2, 3 or 1)
    po, pi = z.pairs(outer_c), z.pairs(inner_c)
    if len(po) and len(pi):
        a = np.repeat(po, len(pi), axis=0)
        b = np.tile(pi, (len(po), 1))
        cands.append(z.bisector_centres(P[a[:, 0]], P[a[:, 1]], P[b[:, 0]], P[b[:, 1]]))
        configs.append(np.column_stack([a, b, np.full(len(a), 2)]))
    for tri, singles, n_outer in ((z.triples(outer_c), inner_c, 3), (z.triples(inner_c), outer_c, 1)):
        if len(tri):
            cc = z.bisector_centres(P[tri[:, 0]], P[tri[:, 1]], P[tri[:, 1]], P[tri[:, 2]])
            t = np.tile(tri, (len(singles), 1))
            s = np.repeat(singles, len(tri))
            cands.append(np.tile(cc, (len(singles), 1)))
            rows = np.column_stack([t, s]) if n_outer == 3 else np.column_stack([s, t])
            configs.append(np.column_stack([rows, np.full(len(t), n_outer)]))
    C = np.vstack(cands)
    ax, ay = x[act], y[act]
    dx = ax[None, :] - C[:, 0:1]
    dy = ay[None, :] - C[:, 1:2]
    rr = np.sqrt(dx * dx + dy * dy)
    width = rr.max(axis=1) - rr.min(axis=1)
    width[~np.isfinite(width)] = np.inf
    best = int(np.argmin(width))
    row = np.vstack(configs)[best]
    n_outer = int(row[4])
    return C[best], (tuple(int(i) for i in row[:n_outer]), tuple(int(i) for i in row[n_outer:4]))


@register("circle.minimum_zone", kind="convex program",
          summary="Minimum zone (MZC): SOCP (clarabel) + linearised inner circle, exact contacts, active set",
          reference="ISO 230-4 circular deviation G; ISO 12181; roundness paper sec. 1-2 (MRAD / Voronoi column of table 1)")
def minimum_zone(points, *, active_size=16, max_rounds=50, max_ccp=30, ccp_tol=1e-10, trust_radius=0.5):
    """Minimum radial separation of two concentric circles enclosing all points (ISO 230-4's G).

    Non-convex (the inner circle), solved by a scheme that converges to the exact optimum:

    1. Active set: only the ``active_size`` outermost and innermost points about the current centre
       (Kåsa's to start) enter the solver; after each solve every point is checked in one vectorised
       pass and the worst violators join the active set, until none is left.
    2. Each active problem: min R - r with second-order cones |p_i - c| <= R and the inner constraint
       linearised at the current centre (convex-concave procedure, a trust region |c - ck| <= delta);
       repeated until the centre moves less than ``ccp_tol`` (unit frame).
    3. Exactness: the solution has four contacts (2 outer + 2 inner, 3 + 1 or 1 + 3); the centre is
       solved in closed form over the configurations of the near-extreme points and the best is kept.
    4. Certificate: the convex hulls of the outer and inner contact directions intersect (the
       alternation condition of Rivlin; Ventura & Yeralan 1989): ``extra['certified']``.

    ``radius`` is the mid radius (R + r)/2; ``inner_radius``, ``outer_radius``, ``form_error`` = R - r,
    ``contacts`` = {"outer": [...], "inner": [...]} (point indices). ``iterations`` counts convex
    programs solved, ``nfev`` clarabel's interior-point iterations. A solver that does not reach an
    optimal status gives ``converged=False`` with clarabel's words.
    """
    name = "circle.minimum_zone"
    k = int(check_positive("active_size", active_size, name))
    max_rounds = int(check_positive("max_rounds", max_rounds, name))
    max_ccp = int(check_positive("max_ccp", max_ccp, name))
    check_positive("ccp_tol", ccp_tol, name)
    check_positive("trust_radius", trust_radius, name)
    frame = Frame.of(points)
    x, y = frame.x, frame.y
    n = len(x)
    c = z.kasa_normal(x, y)
    r_all = z.radii(x, y, c)
    out = z.extremes(r_all, max(k, 4), True)
    inn = z.extremes(r_all, max(k, 4), False)
    history, solves, ipm_iters = [], 0, 0
    converged, message, certified, contacts = False, f"active set not settled within max_rounds={max_rounds}", False, ((), ())
    rounds = 0
    for rounds in range(1, max_rounds + 1):
        ck = c
        try:
            for _ in range(max_ccp):
                sol, iters = _socp(x, y, out, inn, ck, trust_radius)
                solves += 1
                ipm_iters += iters
                history.append((sol[2] - sol[3]) * frame.scale)
                step = float(np.hypot(sol[0] - ck[0], sol[1] - ck[1]))
                ck = sol[:2]
                if step <= ccp_tol:
                    break
        except z.SolverFailure as exc:
            message = f"{exc} (solve {solves + 1}, round {rounds}); no result is claimed"
            break
        act = np.union1d(out, inn)
        c, (oc, ic) = _enumerate(x, y, act, ck, m=min(act.size, 8))
        r_all = z.radii(x, y, c)
        r_out = max(r_all[list(oc)])
        r_in = min(r_all[list(ic)])
        over = r_all - r_out * (1 + z.CHECK_RTOL) - 1e-15
        under = r_in * (1 - z.CHECK_RTOL) - 1e-15 - r_all
        if (over > 0).any() or (under > 0).any():  # final check of every point failed: grow the active set
            out = z.add_violators(out, over, k)
            inn = z.add_violators(inn, under, k)
            continue
        contacts = (oc, ic)
        width_unit = r_out - r_in
        if width_unit <= 1e-13:
            certified, message = True, "points lie on one circle (zone width at rounding level)"
        else:
            certified = z.hulls_meet(z.directions(x, y, list(oc), c), z.directions(x, y, list(ic), c))
            message = ("optimal: contacts alternate (conv(outer) meets conv(inner) directions)" if certified else
                       "stationary zone whose contacts do not satisfy the alternation condition")
        converged = certified
        break
    center, _ = frame.circle_to_data(np.array([c[0], c[1], 1.0]))
    r_data = z.radii(points[:, 0], points[:, 1], center)
    mid = 0.5 * (r_data.max() + r_data.min())
    return zone_result(points, center, mid, {"outer": sorted(contacts[0]), "inner": sorted(contacts[1])},
                       converged=converged, message=message, iterations=solves, nfev=ipm_iters, history=history,
                       extra={"certified": certified, "rounds": rounds, "active_points": int(np.union1d(out, inn).size)})
