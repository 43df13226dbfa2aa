"""Minimum-zone circles (MZC): the thinnest annulus of two concentric circles holding all points."""
from __future__ import annotations

import numpy as np

from methods._registry import register
from methods._validation import check_choice, check_positive
from methods.circle import _zone as z
from methods.circle._frame import Frame


def linearised_inner_rows(x, y, inn, ck, r_column: int, nvar: int):
    """Rows of r <= |p_j - ck| + g_j.(c - ck) (g_j the gradient of |p_j - c| at ck) for A v + s = b,
    s >= 0: a lower bound of the convex |p_j - c|, so a solution is feasible for the true constraint."""
    dx, dy = x[inn] - ck[0], y[inn] - ck[1]
    rk = np.sqrt(dx * dx + dy * dy)
    gx, gy = -dx / rk, -dy / rk
    rows = np.zeros((len(inn), nvar))
    rows[:, 0], rows[:, 1], rows[:, r_column] = -gx, -gy, 1.0
    return list(rows), list(rk - gx * ck[0] - gy * ck[1])


def outer_cone_rows(x, y, out, R_column: int, nvar: int):
    """Second-order cones (R, x_i - cx, y_i - cy) in Q^3, i.e. |p_i - c| <= R."""
    rows, rhs = [], []
    for i in out:
        e_r, e_x, e_y = np.zeros(nvar), np.zeros(nvar), np.zeros(nvar)
        e_r[R_column], e_x[0], e_y[1] = -1.0, 1.0, 1.0
        rows += [e_r, e_x, e_y]
        rhs += [0.0, x[i], y[i]]
    return rows, rhs, [z.clarabel.SecondOrderConeT(3) for _ in out]


def check_ccp_params(name, active_size, max_rounds, max_ccp, ccp_tol, trust_radius):
    """The shared settings of the convex-concave zone methods: (active_size, max_rounds, max_ccp) as ints."""
    for key, val in (("ccp_tol", ccp_tol), ("trust_radius", trust_radius)):
        check_positive(key, val, name)
    return (int(check_positive("active_size", active_size, name)), int(check_positive("max_rounds", max_rounds, name)),
            int(check_positive("max_ccp", max_ccp, name)))


def convex_concave(solve_once, c, max_ccp, ccp_tol, objective_of):
    """Repeat a linearised convex program until the centre moves less than ccp_tol."""
    solves = iters = 0
    history = []
    for _ in range(max_ccp):
        sol, it = solve_once(c)
        solves += 1
        iters += it
        history.append(objective_of(sol))
        step = float(np.hypot(sol[0] - c[0], sol[1] - c[1]))
        c = sol[:2]
        if step <= ccp_tol:
            break
    return c, solves, iters, history


@register("circle.minimum_zone", kind="convex program",
          summary="Minimum zone (MZC): SOCP (clarabel) + linearised inner circle, exact contacts, active set",
          reference="ISO 230-4 circular deviation G; ISO 12181; roundness paper sec. 1-2 (MRAD / Voronoi column of table 1)")
def minimum_zone(points, *, active_size=16, max_rounds=50, max_ccp=30, ccp_tol=1e-8, trust_radius=0.5,
                 global_search="always"):
    """Minimum radial separation of two concentric circles enclosing all points (ISO 230-4's G).

    Non-convex (the inner circle), solved by a scheme that converges to the exact optimum:

    1. Active set: only the ``active_size`` outermost and innermost points about the current centre
       (Kåsa's to start) enter the solver; after each solve every point is checked in one vectorised
       pass and the worst violators join the active set, until none is left.
    2. Each active problem: min R - r with second-order cones |p_i - c| <= R and the inner constraint
       linearised at the current centre (convex-concave procedure, trust region |c - ck| <= delta);
       repeated until the centre moves less than ``ccp_tol`` (unit frame; the exact centre comes from
       step 3, so the convex programs need only find the contacts).
    3. Exactness: the solution has four contacts (2 outer + 2 inner, 3 + 1 or 1 + 3); the centre is
       solved in closed form over the configurations of the near-extreme points and the best is kept.
    4. Local certificate: the convex hulls of the outer and inner contact directions intersect (the
       alternation condition of Rivlin; Ventura & Yeralan 1989), tested over every choice among tied
       contacts (so symmetric lobed profiles find their alternating set). This proves a LOCAL optimum.
    5. Global certificate (``global_search="always"``, the default): a branch and bound over the centre
       (:mod:`methods.circle._global`) proves that no centre gives a zone narrower by more than
       1e-10 x width + 1e-13 x the data's RMS radius + the returned centre's float resolution (the best of the
       7 x 7 floats about the optimum: far from the origin an ulp of the centre can exceed the rest; the message
       states the sum in data units, docs/certificates.md), over ALL of R^2 whenever the points are not nearly
       straight (a far-field bound excludes every centre beyond a computed distance), else over a disc of
       10 data radii about the centroid (the message states it). A better centre found there restarts
       the local solver from it. Cost: the boxes use only the active points plus the few points that
       are extreme about a box centre (one vectorised pass each).

    ``extra['certified']`` is "global" (step 5 succeeded), "local" (only step 4) or False; ``converged``
    is True for either certificate; the message says which, over which region, and why.

    ``radius`` is the mid radius (R + r)/2; ``inner_radius``, ``outer_radius``, ``form_error`` = R - r,
    ``contacts`` = {"outer": [...], "inner": [...]} (point indices). ``iterations`` counts convex
    programs solved, ``nfev`` clarabel's interior-point iterations. A solver that does not reach an
    optimal status gives ``converged=False`` with clarabel's words.
    """
    name = "circle.minimum_zone"
    k, max_rounds, max_ccp = check_ccp_params(name, active_size, max_rounds, max_ccp, ccp_tol, trust_radius)
    check_choice("global_search", global_search, ("always", "never"), name)
    frame = Frame.of(points)
    x, y = frame.x, frame.y

    def local_solve(out, inn, c):
        def once(ck):  # variables (cx, cy, R, r): min R - r
            rows, rhs = linearised_inner_rows(x, y, inn, ck, 3, 4)
            tr_rows, tr_b = z.trust_rows(ck, trust_radius, 4)
            cone_rows, cone_b, cones = outer_cone_rows(x, y, out, 2, 4)
            sol, _, it = z.clarabel_solve([0.0, 0.0, 1.0, -1.0], rows + tr_rows + cone_rows, rhs + tr_b + cone_b,
                                          [z.clarabel.NonnegativeConeT(len(rows) + 4)] + cones)
            return sol, it
        return convex_concave(once, c, max_ccp, ccp_tol, lambda s: s[2] - s[3])

    def exact(act, c):
        r = z.radii(x[act], y[act], c)
        order = np.argsort(r)
        m = min(act.size, 8)
        cands = z.zone_candidates(x, y, act[order[::-1][:m]], act[order[:m]], c)
        hi, lo = z.candidate_extremes(x, y, act, cands.C)
        return z.pick(cands, hi - lo, minimise=True)

    return z.fit_zone(points, frame, start=z.kasa_normal(x, y), local_solve=local_solve, exact=exact,
                      certify=z.certify_hulls(x, y), sides=("outer", "inner"), k=k, max_rounds=max_rounds,
                      radius_rule=lambda r, c: 0.5 * (r.max() + r.min()), proof="zone", global_search=global_search)
