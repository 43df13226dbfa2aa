"""Algebraic Chebyshev circle (Witzgall & Howard 1998): a linear program."""
from __future__ import annotations

import numpy as np

from methods._registry import register
from methods._validation import check_choice, check_positive
from methods.circle import _zone as z
from methods.circle._frame import Frame
from methods.circle._global import alternating_contacts

SOLVERS = ("highs", "clarabel")


def _lp_rows(x, y, idx):
    """|e_i| <= t for e_i = z_i - 2a x_i - 2b y_i + w, variables (a, b, w, t), as G v <= h."""
    zz = x[idx] ** 2 + y[idx] ** 2
    up = np.column_stack([-2 * x[idx], -2 * y[idx], np.ones(len(idx)), -np.ones(len(idx))])
    lo = np.column_stack([2 * x[idx], 2 * y[idx], -np.ones(len(idx)), -np.ones(len(idx))])
    return np.vstack([up, lo]), np.concatenate([-zz, zz])


@register("circle.chebyshev_lp", kind="convex program",
          summary="Algebraic Chebyshev fit: min max |(x-a)^2 + (y-b)^2 - rho^2|, an LP (HiGHS or clarabel)",
          reference="Witzgall & Howard, Int. J. Flex. Manuf. Syst. 10 (1998) 5-25 (ref. 18 of the roundness paper)")
def chebyshev_lp(points, *, solver="highs", active_size=16, max_rounds=50):
    """Minimise t over (a, b, w) subject to |z_i - 2a x_i - 2b y_i + w| <= t, z_i = x_i^2 + y_i^2 and
    w = a^2 + b^2 - rho^2: the largest algebraic residual, linear in (a, b, w, t). Equivalently the
    zone about (a, b) of least R^2 - r^2 (R^2 = rho^2 + t, r^2 = rho^2 - t), which Witzgall & Howard
    found to be very close to the minimum zone. Active set on the extreme points with a final check of
    every point; the LP's four contacts give the exact centre, certified by conv(outer contact points)
    meeting conv(inner contact points) (the LP's optimality condition, searched among tied contacts): the
    LP is convex, so this certifies the global optimum of the algebraic objective over all (a, b, w)
    (``extra['certified'] == "global"``), not the minimum zone.
    ``radius`` = rho = sqrt((R^2 + r^2)/2); ``form_error`` = R - r about (a, b)."""
    name = "circle.chebyshev_lp"
    check_choice("solver", solver, SOLVERS, name)
    k = int(check_positive("active_size", active_size, name))
    max_rounds = int(check_positive("max_rounds", max_rounds, name))
    frame = Frame.of(points)
    x, y = frame.x, frame.y

    def local_solve(out, inn, c):
        idx = np.union1d(out, inn)
        G, h = _lp_rows(x, y, idx)
        cost = np.array([0.0, 0.0, 0.0, 1.0])
        if solver == "highs":
            from scipy.optimize import linprog  # imported on first use (light import)

            res = linprog(cost, A_ub=G, b_ub=h, bounds=[(None, None)] * 3 + [(0, None)], method="highs")
            if res.status != 0:
                raise z.SolverFailure(f"HiGHS: {res.message}")
            return res.x[:2], 1, int(res.nit), [res.x[3]]
        sol, _, it = z.clarabel_solve(cost, list(G), list(h), [z.clarabel.NonnegativeConeT(len(h))])
        return sol[:2], 1, it, [sol[3]]

    def exact(act, c):
        r = z.radii(x[act], y[act], c)
        order = np.argsort(r)
        m = min(act.size, 8)
        cands = z.zone_candidates(x, y, act[order[::-1][:m]], act[order[:m]], c)
        hi, lo = z.candidate_extremes(x, y, act, cands.C, squared=True)
        return z.pick(cands, hi - lo, minimise=True)

    def certify(c, oc, ic):
        r = z.radii(x, y, c)
        if r.max() - r.min() <= z.ZERO_WIDTH:
            return True, "points lie on one circle (zero algebraic residual)"
        ok = z.hulls_meet(np.column_stack([x[list(oc)], y[list(oc)]]) - c, np.column_stack([x[list(ic)], y[list(ic)]]) - c)
        if not ok:  # ties (symmetric lobes): look for an alternating choice among the tied contacts
            r2 = r * r
            tol = 4e-14 * r2.max()
            tied_out, tied_in = np.flatnonzero(r2 >= r2.max() - tol), np.flatnonzero(r2 <= r2.min() + tol)
            ok = alternating_contacts(x, y, c, tied_out, tied_in, z.hulls_meet, normalise=False) is not None
        return ok, ("optimal: conv(outer contacts) meets conv(inner contacts)" if ok else
                    "LP contacts do not satisfy the optimality condition")

    return z.fit_zone(points, frame, start=z.kasa_normal(x, y), local_solve=local_solve, exact=exact,
                      certify=certify, sides=("outer", "inner"), k=k, max_rounds=max_rounds,
                      radius_rule=lambda r, c: float(np.sqrt(0.5 * (r.max() ** 2 + r.min() ** 2))))
