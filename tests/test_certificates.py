"""Certificates and flags keep the promise printed beside them, checked by routes that share no code with the
methods: Welzl's smallest enclosing circle for the MCC; the minimum zone far from the origin against an
exhaustive enumeration in 50-digit arithmetic (mpmath) about the data; the ellipse Nelder–Mead stationarity
recomputed in 50 digits. See docs/certificates.md."""
from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

import methods


# ------------------------------------------------------------------ MCC / MCCI: near-ties on a semicircle

def welzl_mcc(P, seed=0, rtol=1e-13):
    """Smallest enclosing circle (Welzl 1991, the iterative move-to-front form), written here: (centre, radius).
    Containment with a relative slack ``rtol``, so the radius may fall short of the exact one by rtol x radius."""
    P = P[np.random.default_rng(seed).permutation(len(P))]
    s = P.mean(axis=0)
    P = [tuple(p) for p in (P - s)]

    def two(a, b):
        c = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)
        return c, float(np.hypot(a[0] - c[0], a[1] - c[1]))

    def three(a, b, c):
        d = 2 * (a[0] * (b[1] - c[1]) + b[0] * (c[1] - a[1]) + c[0] * (a[1] - b[1]))
        na, nb, nc = a[0] ** 2 + a[1] ** 2, b[0] ** 2 + b[1] ** 2, c[0] ** 2 + c[1] ** 2
        o = ((na * (b[1] - c[1]) + nb * (c[1] - a[1]) + nc * (a[1] - b[1])) / d,
             (na * (c[0] - b[0]) + nb * (a[0] - c[0]) + nc * (b[0] - a[0])) / d)
        return o, float(np.hypot(a[0] - o[0], a[1] - o[1]))

    def inside(c, r, p):
        return np.hypot(p[0] - c[0], p[1] - c[1]) <= r * (1 + rtol)

    c, r = P[0], 0.0
    for i in range(1, len(P)):
        if inside(c, r, P[i]):
            continue
        c, r = P[i], 0.0
        for j in range(i):
            if inside(c, r, P[j]):
                continue
            c, r = two(P[i], P[j])
            for k in range(j):
                if not inside(c, r, P[k]):
                    c, r = three(P[i], P[j], P[k])
    return np.array(c) + s, r


def oval_profile(amp, n, seed):
    """A 5 mm profile with an ovality of ``amp`` x the radius (and 0.3 amp of 3 lobes), n equal angles, centre
    within 100 mm of the origin: the two flat maxima are nearly opposite (the extreme points nearly on a
    semicircle) and dozens of their neighbours lie within 1e-12 of the largest radius (near-ties)."""
    rng = np.random.default_rng(seed)
    t = 2 * np.pi * np.arange(n) / n
    r = 5.0 * (1 + amp * np.cos(2 * t + rng.uniform(0, 6)) + 0.3 * amp * np.cos(3 * t + rng.uniform(0, 6)))
    c = rng.uniform(-100, 100, 2)
    return np.column_stack([c[0] + r * np.cos(t), c[1] + r * np.sin(t)])


# profiles that were labelled "contacts do not surround the centre" (converged=False): the first two with a
# radius equal to the smallest enclosing circle's to 4e-13 and 1.2e-12 relative, the third with a circle through
# three neighbouring points of one peak, 2.4e-7 too large (the points of the opposite peak never reached the
# exact step)
OVALS = [(1e-8, 7200, 2), (1e-7, 3600, 10), (1e-7, 7200, 0)]


@pytest.mark.parametrize("amp, n, seed", OVALS)
def test_mcc_of_near_tied_semicircle_extremes_is_found_and_certified(amp, n, seed):
    P = oval_profile(amp, n, seed)
    fit = methods.fit("circle.min_circumscribed", P)
    _, ref = welzl_mcc(P)
    assert fit.converged and fit.extra["certified"] == "global", fit.message
    # the promise: no enclosing circle smaller by more than 1e-12 x the radius (Welzl's may be 1e-13 short)
    assert fit.radius <= ref * (1 + 1e-12 + 1e-13), (fit.radius - ref) / ref
    assert fit.radius >= ref * (1 - 1e-13)


def test_dual_bound_of_all_points_is_the_smallest_enclosing_circle():
    """The MCC is fixed by 2 or 3 of the points, so the largest smallest-circle over all pairs and triples is the
    MCC itself (Welzl's radius), and over a subset it is a lower bound."""
    from methods.circle._zone import enclosing_lower_bound
    rng = np.random.default_rng(3)
    for n in (3, 5, 8, 12):
        for _ in range(20):
            P = rng.normal(size=(n, 2)) * rng.uniform(0.1, 10, 2) + rng.uniform(-50, 50, 2)
            _, ref = welzl_mcc(P, rtol=0.0)
            low, subset = enclosing_lower_bound(P[:, 0], P[:, 1], np.arange(n))
            assert ref * (1 - 1e-13) <= low <= ref, (n, low, ref)
            assert 2 <= len(subset) <= 3
            part, _ = enclosing_lower_bound(P[:, 0], P[:, 1], np.arange(n // 2 + 1))
            assert part <= ref


def test_roundness_mcci_of_near_tied_profile_is_converged():
    """The ISO 12181 evaluation reports the MCCI of such a profile as converged, with Welzl's radius."""
    P = oval_profile(1e-7, 3600, 10)
    ev = methods.fit("roundness.iso12181", P, cutoff_upr=None, reference="mcci")
    row = ev.references["mcci"]
    _, ref = welzl_mcc(P)
    assert ev.converged and row["converged"], row["message"]
    assert abs(row["radius"] - ref) <= 2e-12 * ref


# ------------------------------------------------------------------ minimum zone far from the origin

def _mp_width(P, c):
    """max - min of |p_i - c| in 50-digit arithmetic (every float is exact in it)."""
    with mp.workdps(50):
        r = [mp.sqrt((mp.mpf(float(p[0])) - c[0]) ** 2 + (mp.mpf(float(p[1])) - c[1]) ** 2) for p in P]
        return max(r) - min(r)


def _mp_equidistant(P, i, j, k, l):
    """The centre equidistant from P[i], P[j] and from P[k], P[l], in 50 digits about P[i] (a frame on the data)."""
    with mp.workdps(50):
        o = [mp.mpf(float(v)) for v in P[i]]
        a, b, c, d = ([mp.mpf(float(P[m][0])) - o[0], mp.mpf(float(P[m][1])) - o[1]] for m in (i, j, k, l))
        n1, n2 = (b[0] - a[0], b[1] - a[1]), (d[0] - c[0], d[1] - c[1])
        h1 = (b[0] ** 2 + b[1] ** 2 - a[0] ** 2 - a[1] ** 2) / 2
        h2 = (d[0] ** 2 + d[1] ** 2 - c[0] ** 2 - c[1] ** 2) / 2
        det = n1[0] * n2[1] - n1[1] * n2[0]
        return ((h1 * n2[1] - n1[1] * h2) / det + o[0], (n1[0] * h2 - h1 * n2[0]) / det + o[1])


def exhaustive_minimum_zone(P):
    """The minimum zone over all real centres (width, centre), by enumeration: the optimum has 2 + 2, 3 + 1 or
    1 + 3 contacts (Roy & Zhang 1992), so it is one of the centres equidistant from two pairs (circumcentres
    included). The configurations are ranked in float64 about the first point (differences of nearby floats:
    exact), and the best few are recomputed and evaluated in 50 digits."""
    from itertools import combinations
    Q = P - P[0]
    quads = [(i, j, k, l) for i, j, k, l in combinations(range(len(P)), 4)]
    rows = [(a, b, a, c) for a, b, c in combinations(range(len(P)), 3)]
    rows += [(q[s], q[t], q[u], q[v]) for q in quads for s, t, u, v in ((0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2))]
    idx = np.array(rows)
    n1, n2 = Q[idx[:, 1]] - Q[idx[:, 0]], Q[idx[:, 3]] - Q[idx[:, 2]]
    h1 = 0.5 * ((Q[idx[:, 1]] ** 2).sum(1) - (Q[idx[:, 0]] ** 2).sum(1))
    h2 = 0.5 * ((Q[idx[:, 3]] ** 2).sum(1) - (Q[idx[:, 2]] ** 2).sum(1))
    det = n1[:, 0] * n2[:, 1] - n1[:, 1] * n2[:, 0]
    with np.errstate(all="ignore"):
        C = np.column_stack([(h1 * n2[:, 1] - n1[:, 1] * h2) / det, (n1[:, 0] * h2 - h1 * n2[:, 0]) / det])
    ok = np.isfinite(C).all(axis=1)
    R = np.hypot(Q[None, :, 0] - C[ok, 0:1], Q[None, :, 1] - C[ok, 1:2])
    w = R.max(axis=1) - R.min(axis=1)
    order = np.argsort(w)[:40]
    best = None
    for row in idx[ok][order]:
        c = _mp_equidistant(P, *row)
        wc = _mp_width(P, c)
        if best is None or wc < best[0]:
            best = (wc, c)
    return best


def best_float_centre_excess(P, c_opt, w_opt, k=3):
    """The least excess over the optimum of the float centres within k ulps of the optimal centre."""
    def around(v):
        out = [float(v)]
        for _ in range(k):
            out = [np.nextafter(out[0], -np.inf)] + out + [np.nextafter(out[-1], np.inf)]
        return out
    with mp.workdps(50):
        return min(_mp_width(P, (mp.mpf(a), mp.mpf(b))) - w_opt for a in around(c_opt[0]) for b in around(c_opt[1]))


def far_set(seed, distance, n=13):
    """A lobed, noisy circle of radius 1 whose centre is ``distance`` radii from the origin."""
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    r = 1 + 0.01 * rng.standard_normal(n) + 0.01 * np.cos(3 * t + rng.uniform(0, 6))
    phi = rng.uniform(0, 2 * np.pi)
    return distance * np.array([np.cos(phi), np.sin(phi)]) + np.column_stack([r * np.cos(t), r * np.sin(t)])


def stated_bound(message):
    """The number the message promises: 'no centre ... by more than B data units'."""
    import re
    return float(re.search(r"by more than ([0-9.e+-]+) data units", message).group(1))


# far sets where, before, the zone about the returned centre exceeded the optimum by 1.24, 10.1, 38.9, 9.7, 282 and
# 806 times the stated bound, and the returned centre was 8.6, 4.2, 3.1, 7.0, 13.3 and 3.3 times worse than the
# best float centre (over the 48 sets of seeds 0-11 x the four distances: 1.0-806x in 40, now <= 0.996x in all,
# and the returned centre is the best float centre in all: the slow test)
FAR = [(8, 3e4), (4, 3e5), (8, 3e6), (11, 3e5), (5, 2e7), (6, 2e7)]
FAR_ALL = [pytest.param(s, d, marks=pytest.mark.slow) for s in range(12) for d in (3e4, 3e5, 3e6, 2e7)
           if (s, d) not in FAR]


@pytest.mark.parametrize("seed, distance", FAR + FAR_ALL)
def test_minimum_zone_bound_holds_far_from_the_origin(seed, distance):
    P = far_set(seed, distance)
    fit = methods.fit("circle.minimum_zone", P)
    assert fit.extra["certified"] == "global", fit.message
    bound = stated_bound(fit.message)
    w_opt, c_opt = exhaustive_minimum_zone(P)
    with mp.workdps(50):
        excess = float(_mp_width(P, (mp.mpf(fit.center[0]), mp.mpf(fit.center[1]))) - w_opt)
        best = float(best_float_centre_excess(P, c_opt, w_opt))
    assert -1e-15 <= excess <= bound, (excess, bound)
    # the returned centre is the best float centre about the optimum (to the certificate's own resolution) ...
    assert excess <= best + 1e-13, (excess, best)
    # ... and the bound is not vacuous: within the certificate's resolution of what the best float centre costs
    ulp = np.hypot(*np.spacing(np.abs(np.asarray(fit.center))))
    assert bound <= max(best, 0.0) + 2 * ulp * 1e-3 + 1e-11, (bound, best, ulp)
    assert fit.form_error == pytest.approx(float(w_opt) + excess, abs=4 * np.spacing(distance) + 1e-15)


# ------------------------------------------------------------------ ellipse Nelder–Mead: what "stationary" checked

def _mp_algebraic(P, p):
    """e_i = p_y^2 u^2 + p_x^2 v^2 - p_x^2 p_y^2 (circle/ellipse paper eq. 15; u, v in the ellipse frame, eq. 14),
    in 50 digits, data units."""
    px, py, g, xc, yc = p
    c, s = mp.cos(g), mp.sin(g)
    out = []
    for x, y in P:
        dx, dy = mp.mpf(float(x)) - xc, mp.mpf(float(y)) - yc
        u, v = dx * c + dy * s, dy * c - dx * s
        out.append(py * py * u * u + px * px * v * v - px * px * py * py)
    return out


def _mp_orthogonal(P, p):
    """Distances to the ellipse (semi-axes |p_x|, |p_y|), closest points by Newton on the foot-point equation
    (a^2 - b^2) sin t cos t - u a sin t + v b cos t = 0, in 50 digits."""
    px, py, g, xc, yc = p
    a, b = abs(px), abs(py)
    c, s = mp.cos(g), mp.sin(g)
    out = []
    for x, y in P:
        dx, dy = mp.mpf(float(x)) - xc, mp.mpf(float(y)) - yc
        u, v = dx * c + dy * s, dy * c - dx * s
        t = mp.atan2(a * v, b * u)
        for _ in range(60):
            st, ct = mp.sin(t), mp.cos(t)
            step = (((a * a - b * b) * st * ct - u * a * st + v * b * ct) /
                    ((a * a - b * b) * (ct * ct - st * st) - u * a * ct - v * b * st))
            t -= step
            if abs(step) < mp.mpf(10) ** -40:
                break
        out.append(mp.sqrt((u - a * mp.cos(t)) ** 2 + (v - b * mp.sin(t)) ** 2))
    return out


def mp_stationarity(residuals, P, p0):
    """(S, g^T (J^T J)^-1 g) at the data-unit parameters p0 in 50 digits: the objective and the decrease the
    Gauss–Newton model promises there (J by central differences of step 1e-20 relative: error ~1e-40)."""
    with mp.workdps(50):
        p = [mp.mpf(float(v)) for v in p0]
        r = mp.matrix(residuals(P, p))
        cols = []
        for k in range(5):
            h = mp.mpf(10) ** -20 * max(abs(p[k]), 1)
            up, dn = list(p), list(p)
            up[k] += h
            dn[k] -= h
            cols.append([(a - b) / (2 * h) for a, b in zip(residuals(P, up), residuals(P, dn))])
        J = mp.matrix([[cols[k][i] for k in range(5)] for i in range(len(P))])
        g = J.T * r
        return (r.T * r)[0], (g.T * mp.lu_solve(J.T * J, g))[0]


def near_circles(k, n, seed):
    """The circle/ellipse paper's geometry (299.0243 mm at (1200, 650) mm) with a - b from 0.5 um to 1 mm and
    1 um of noise: the angle is ill-conditioned and the objective's rounding bound is ~1e-9 of it."""
    from datasets.synthetic import ellipse_points
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(k):
        a = 299.0243
        out.append(ellipse_points((1200.0, 650.0), (a, a - 10 ** rng.uniform(-3.3, 0)), np.radians(rng.uniform(0, 180)),
                                  n, noise=1e-3, rng=rng))
    return out


@pytest.mark.parametrize("method_id, residuals, k", [("ellipse.algebraic_nm", _mp_algebraic, 4),
                                                     ("ellipse.geometric_nm", _mp_orthogonal, 3)])
def test_nelder_mead_stationarity_is_what_the_message_says_in_50_digits(method_id, residuals, k):
    """converged=True states the Gauss–Newton model's decrease and its tolerance (1e-10 + the objective's rounding
    bound, printed); recomputed in 50 digits at the returned parameters, the model's decrease is the printed one and
    within the tolerance. (Before, the message said only 'stationary point (Levenberg-Marquardt probe)' while the
    decrease still available was 3e-10-1.4e-9 of the objective: above the 1e-10 a reader takes from it.)"""
    import re
    for P in near_circles(k, 40, seed=34):
        fit = methods.fit(method_id, P)
        assert fit.converged, fit.message
        found = re.search(r"promises a further decrease of ([0-9.e+-]+) of the objective .* at most 1e-10 \+ "
                          r"([0-9.e+-]+) \(the rounding bound", fit.message)
        assert found, fit.message
        stated, allowance = float(found.group(1)), float(found.group(2))
        pp = fit.extra["paper_parameters"]
        S, gn = mp_stationarity(residuals, P, [pp["p_x"], pp["p_y"], pp["gamma"], pp["x_C"], pp["y_C"]])
        rel = float(gn / S)
        assert rel <= (1e-10 + allowance) * (1 + 1e-2), (rel, allowance)
        assert rel == pytest.approx(stated, rel=2e-2, abs=1e-13), (rel, stated)
        assert fit.extra["stationarity"]["relative_tolerance"] == pytest.approx(1e-10 + allowance, rel=1e-2)


def test_probe_is_not_stationary_when_the_model_promises_a_decrease_no_step_shows():
    """A point where the Gauss–Newton model promises a decrease of 50 % of S but no trial step lowers the computed
    S (an objective whose evaluation hides every decrease, as rounding does below its noise): the probe used to
    report 'stationary' (it found no decrease); the model's promise now decides."""
    from methods.ellipse._checks import stationarity_probe
    A = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    b = np.array([1.0, 1.0, 1.0])
    r0 = A @ np.zeros(2) - b

    def residuals(q):
        return r0.copy()  # every step "fails"

    probe = stationarity_probe(residuals, lambda q: A, np.zeros(2), noise=lambda r, q: 0.0)
    assert probe.decrease == 0.0
    assert probe.predicted == pytest.approx(2.0)
    assert not probe.stationary
    assert "promises a decrease of 6.67e-01 relative" in probe.reason()
