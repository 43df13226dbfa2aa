"""Form-error family: minimum zone, Chebyshev LP, MIC, MCC — exact against exhaustive enumeration."""
from itertools import combinations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.path import Path

import datasets
import methods
from datasets.synthetic import circle_points
from method_ids import method_specs

ZONE = ["circle.minimum_zone", "circle.chebyshev_lp", "circle.max_inscribed", "circle.min_circumscribed"]


def _centres(P, idx_a, idx_b, idx_c, idx_d):
    a, b, c, d = P[idx_a], P[idx_b], P[idx_c], P[idx_d]
    n1, n2 = b - a, d - c
    h1 = 0.5 * np.einsum("ij,ij->i", n1, a + b)
    h2 = 0.5 * np.einsum("ij,ij->i", n2, c + d)
    det = n1[:, 0] * n2[:, 1] - n1[:, 1] * n2[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        C = np.column_stack([(h1 * n2[:, 1] - n1[:, 1] * h2) / det, (n1[:, 0] * h2 - h1 * n2[:, 0]) / det])
    return C[np.isfinite(C).all(axis=1)]


def enumerate_zone_centres(P):
    """Every candidate centre of a minimum zone: for each 4-subset, the 3 ways of splitting it into
    2 + 2 (bisector intersections) and the circumcentres of its 4 triples (3 + 1 and 1 + 3)."""
    quads = np.array(list(combinations(range(len(P)), 4)))
    out = []
    for (i, j), (k, l) in (((0, 1), (2, 3)), ((0, 2), (1, 3)), ((0, 3), (1, 2))):
        out.append(_centres(P, quads[:, i], quads[:, j], quads[:, k], quads[:, l]))
    tri = np.array(list(combinations(range(len(P)), 3)))
    out.append(_centres(P, tri[:, 0], tri[:, 1], tri[:, 1], tri[:, 2]))
    return np.vstack(out), tri


def radii_matrix(P, C):
    return np.hypot(P[None, :, 0] - C[:, 0:1], P[None, :, 1] - C[:, 1:2])


def brute_force(P):
    """Exhaustive optima over all contact configurations: MZC width, algebraic Chebyshev value,
    MCC radius, MIC radius (centres inside the profile polygon)."""
    P = P - P.mean(axis=0)  # the same translation-free numbers for any position
    C, tri = enumerate_zone_centres(P)
    r = radii_matrix(P, C)
    mz = (r.max(axis=1) - r.min(axis=1)).min()
    cheb = (r.max(axis=1) ** 2 - r.min(axis=1) ** 2).min()
    pair = np.array(list(combinations(range(len(P)), 2)))
    single = np.vstack([0.5 * (P[pair[:, 0]] + P[pair[:, 1]]), C])
    rs = radii_matrix(P, single)
    mcc = rs.max(axis=1).min()
    order = np.argsort(np.arctan2(P[:, 1], P[:, 0]))  # the profile: points in angular order about the centroid
    inside = Path(P[order]).contains_points(single)
    mic = rs.min(axis=1)[inside].max()
    return mz, cheb, mcc, mic


def check_against_brute_force(P):
    mz, cheb, mcc, mic = brute_force(P)
    res = {m: methods.fit(m, P) for m in ZONE}
    for m, r in res.items():
        assert r.converged, f"{m}: {r.message}"
        assert r.extra["certified"]
    assert res["circle.minimum_zone"].form_error == pytest.approx(mz, rel=1e-9, abs=1e-12)
    cz = res["circle.chebyshev_lp"]
    assert cz.outer_radius ** 2 - cz.inner_radius ** 2 == pytest.approx(cheb, rel=1e-9, abs=1e-12)
    assert res["circle.min_circumscribed"].radius == pytest.approx(mcc, rel=1e-12)
    assert res["circle.max_inscribed"].radius == pytest.approx(mic, rel=1e-12)
    return res


@pytest.mark.parametrize("name", ["roundness_set1", "roundness_set2", "roundness_set3"])
def test_published_sets_match_exhaustive_enumeration(name):
    check_against_brute_force(datasets.load(name).points)


@st.composite
def near_circles(draw):
    n = draw(st.integers(5, 11))
    seed = draw(st.integers(0, 2**32 - 1))
    noise = draw(st.sampled_from([1e-4, 1e-3, 1e-2, 5e-2]))
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    t[0::max(1, n // 4)] = np.linspace(0, 2 * np.pi, len(t[0::max(1, n // 4)]), endpoint=False)  # surround the centre
    r = 1 + rng.normal(0, noise, n)
    centre = rng.uniform(-1e3, 1e3, 2)
    scale = 10 ** rng.uniform(-1, 3)
    return centre + scale * np.column_stack([r * np.cos(t), r * np.sin(t)])


@settings(max_examples=60, deadline=None)
@given(P=near_circles())
def test_random_small_sets_match_exhaustive_enumeration(P):
    check_against_brute_force(P)


def test_published_table1_set2():
    """Roundness paper, table 1, set 2: Voronoi (minimum zone) 1.6711, MIC 1.7287, MCC 1.7382."""
    pts = datasets.load("roundness_set2").points
    pub = datasets.load("roundness_set2").published
    assert round(methods.fit("circle.minimum_zone", pts).form_error, 4) == pub["Voronoi (minimum zone)"]
    assert round(methods.fit("circle.max_inscribed", pts).form_error, 4) == pub["MIC"]
    assert round(methods.fit("circle.min_circumscribed", pts).form_error, 4) == pub["MCC"]


@pytest.mark.parametrize("name", ["roundness_set1", "roundness_set2", "roundness_set3"])
def test_minimum_zone_is_never_wider_than_any_other_centre(name, rng):
    pts = datasets.load(name).points
    mz = methods.fit("circle.minimum_zone", pts).form_error
    for spec in method_specs("circle"):
        other = methods.fit(spec.id, pts)
        assert mz <= other.form_error * (1 + 1e-12), spec.id
    # and no random centre near it does better
    c = np.array(methods.fit("circle.minimum_zone", pts).center)
    for scale in (1e-2, 1e-4, 1e-7):
        C = c + rng.normal(0, scale, (2000, 2))
        r = radii_matrix(pts, C)
        assert (r.max(axis=1) - r.min(axis=1)).min() >= mz * (1 - 1e-12)


@pytest.mark.parametrize("method_id", ["circle.minimum_zone", "circle.chebyshev_lp", "circle.min_circumscribed",
                                       "circle.max_inscribed"])
def test_exact_circle_gives_zero_width(method_id):
    pts = circle_points((1200.0, 650.0), 299.0, 720)
    res = methods.fit(method_id, pts)
    assert res.converged, res.message
    assert res.form_error <= 1e-9
    assert np.abs(np.array(res.center) - (1200, 650)).max() <= 1e-8 and abs(res.radius - 299) <= 1e-8


@pytest.mark.parametrize("span_deg", [180, 90, 30])
@pytest.mark.parametrize("method_id", ["circle.minimum_zone", "circle.chebyshev_lp"])
def test_partial_arcs(method_id, span_deg, rng):
    span = np.radians(span_deg)
    exact = circle_points((1200.0, 650.0), 299.0, 400, arc=(0.3, 0.3 + span), endpoint=True)
    res = methods.fit(method_id, exact)
    assert res.converged, res.message
    assert res.form_error <= 1e-9 and abs(res.radius - 299.0) <= 1e-6
    noisy = circle_points((1200.0, 650.0), 299.0, 400, arc=(0.3, 0.3 + span), noise=0.002, rng=rng, endpoint=True)
    res = methods.fit(method_id, noisy)
    assert res.converged, res.message
    lsq = methods.fit("circle.gauss_newton", noisy)
    assert res.form_error <= lsq.form_error * (1 + 1e-12) if method_id == "circle.minimum_zone" else True
    assert 0 < res.form_error < 0.03


@pytest.mark.parametrize("span_deg", [180, 90, 30])
def test_partial_arcs_mcc_and_mic(span_deg, rng):
    span = np.radians(span_deg)
    pts = circle_points((0.0, 0.0), 10.0, 200, arc=(0.0, span), noise=1e-3, rng=rng, endpoint=True)
    mcc = methods.fit("circle.min_circumscribed", pts)
    assert mcc.converged
    chord = np.hypot(*(pts[0] - pts[-1]))
    assert mcc.radius <= 10.01 and mcc.radius >= 0.5 * chord * (1 - 1e-12)
    mic = methods.fit("circle.max_inscribed", pts)
    assert not mic.converged and "partial arc" in mic.message


def test_contacts_and_json(tmp_path):
    import json

    from cli_calls import cli
    out = cli("fit", "circle.minimum_zone", "roundness_set2", "--json")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    assert d["outer_radius"] - d["inner_radius"] == pytest.approx(d["form_error"], abs=1e-12)
    assert len(d["contacts"]["outer"]) + len(d["contacts"]["inner"]) == 4
    pts = datasets.load("roundness_set2").points
    r = np.hypot(*(pts - d["center"]).T)
    np.testing.assert_allclose(r[d["contacts"]["outer"]], d["outer_radius"], rtol=1e-12)
    np.testing.assert_allclose(r[d["contacts"]["inner"]], d["inner_radius"], rtol=1e-12)


def test_chebyshev_solvers_agree_and_match_full_lp():
    """Second algorithm: HiGHS on every point (no active set) and clarabel give the same optimum."""
    from scipy.optimize import linprog
    pts = circle_points((5.0, -3.0), 2.0, 500, noise=1e-3, rng=np.random.default_rng(7))
    a = methods.fit("circle.chebyshev_lp", pts, solver="highs")
    b = methods.fit("circle.chebyshev_lp", pts, solver="clarabel")
    assert np.abs(np.array(a.center) - b.center).max() < 1e-12
    m = pts.mean(axis=0)
    u = pts - m
    zz = (u ** 2).sum(axis=1)
    G = np.vstack([np.column_stack([-2 * u, np.ones(500), -np.ones(500)]),
                   np.column_stack([2 * u, -np.ones(500), -np.ones(500)])])
    full = linprog([0, 0, 0, 1], A_ub=G, b_ub=np.concatenate([-zz, zz]), bounds=[(None, None)] * 3 + [(0, None)],
                   method="highs")
    assert np.abs(full.x[:2] + m - a.center).max() < 1e-7
    assert 0.5 * (a.outer_radius ** 2 - a.inner_radius ** 2) == pytest.approx(full.x[3], rel=1e-6)


def test_solver_failure_is_a_result_not_a_fallback(monkeypatch):
    import clarabel
    real = clarabel.DefaultSettings

    def starved():
        s = real()
        s.max_iter = 1
        return s

    monkeypatch.setattr(clarabel, "DefaultSettings", starved)
    pts = circle_points((0, 0), 1, 50, noise=1e-2, rng=np.random.default_rng(1))
    for method_id in ("circle.minimum_zone", "circle.min_circumscribed", "circle.max_inscribed"):
        res = methods.fit(method_id, pts)
        assert not res.converged and "clarabel" in res.message and "MaxIterations" in res.message


def test_large_data_only_extreme_points_reach_the_solver(rng):
    pts = circle_points((1200.0, 650.0), 299.0, 200_000, noise=0.003, rng=rng)
    for method_id in ZONE:
        res = methods.fit(method_id, pts)
        assert res.converged, f"{method_id}: {res.message}"
        assert res.extra["active_points"] < 200
        r = np.hypot(*(pts - res.center).T)
        assert r.max() - r.min() == pytest.approx(res.form_error, rel=1e-12)


def test_candidate_extremes_are_those_of_the_whole_distance_matrix():
    """_zone.candidate_extremes forms the (K, M) distances a block of candidates at a time (peak memory): its
    largest and smallest distance per candidate are bitwise those of the whole matrix, squared or not, for K
    around the block size and for an N that makes the blocks a single row."""
    from methods.circle import _zone as z
    rng = np.random.default_rng(12)
    for n, m, k in ((3358, 40, 1000), (300, 100, 7), (20, 20, 1), (50_000, 9, 30_000)):
        x, y = rng.standard_normal(n), rng.standard_normal(n)
        act = rng.choice(n, m, replace=False)
        C = rng.standard_normal((k, 2)) * 3
        R = np.sqrt((x[act][None, :] - C[:, 0:1]) ** 2 + (y[act][None, :] - C[:, 1:2]) ** 2)
        hi, lo = z.candidate_extremes(x, y, act, C)
        assert np.array_equal(hi, R.max(axis=1)) and np.array_equal(lo, R.min(axis=1))
        hi2, lo2 = z.candidate_extremes(x, y, act, C, squared=True)
        assert np.array_equal(hi2, (R ** 2).max(axis=1)) and np.array_equal(lo2, (R ** 2).min(axis=1))


def test_every_candidate_centre_is_equidistant_from_its_configuration():
    """_zone.zone_candidates and circle_candidates keep only the candidates' centres and rebuild a configuration's
    point indices on demand (Candidates.row): each centre must be equidistant from the points its row names (the
    2 + 2 bisectors meet, the 3-point circumcentres, the 2-point midpoints), every kind of row must occur, and the
    rows must be distinct configurations."""
    from methods.circle import _zone as z
    rng = np.random.default_rng(20)
    x, y = rng.standard_normal(40), rng.standard_normal(40)
    outer, inner = np.arange(0, 8), np.arange(8, 16)
    for cands, kinds in ((z.zone_candidates(x, y, outer, inner, np.zeros(2)), {2, 3, 1}),
                         (z.circle_candidates(x, y, outer, np.zeros(2), "outer"), {2, 3}),
                         (z.circle_candidates(x, y, inner, np.zeros(2), "inner"), {0})):
        assert len(cands) > 50  # none near the origin: every finite centre is kept
        seen, rows = set(), set()
        for k in range(len(cands)):
            row = cands.row(k)
            members, n_outer = [int(i) for i in row[:-1] if i >= 0], int(row[-1])
            seen.add(n_outer)
            rows.add(tuple(row))
            d = np.hypot(x[members] - cands.C[k, 0], y[members] - cands.C[k, 1])
            if len(row) == 5 and len(members) == 4:  # equal among the outer and among the inner contacts
                for g in (members[:n_outer], members[n_outer:]):  # outer contacts, inner contacts
                    dg = np.hypot(x[g] - cands.C[k, 0], y[g] - cands.C[k, 1])
                    assert np.ptp(dg) <= 1e-9 * dg.max()
            else:
                assert np.ptp(d) <= 1e-9 * d.max()
        assert kinds <= seen and len(rows) == len(cands)


def test_least_width_by_rotating_calipers_equals_every_pair_normal():
    """_global.least_width_exact (rotating calipers on Qhull's hull) against the minimum over every pair of
    points' normal directions of the extent along it (all pairs; no hull): within WIDTH_ROUNDING eps max|coordinate|
    of it (the margin the certificate subtracts), on noisy arcs, clouds, near-lines and regular polygons."""
    from methods.circle._global import WIDTH_ROUNDING, least_width_exact
    rng = np.random.default_rng(7)
    for t in range(400):
        m = int(rng.integers(3, 120))
        if t % 4 == 0:
            x, y = rng.standard_normal((2, m))
        elif t % 4 == 1:
            th = rng.uniform(0, rng.uniform(0.01, 6.3), m)
            r = 1 + rng.standard_normal(m) * 10 ** rng.uniform(-8, -1)
            x, y = r * np.cos(th), r * np.sin(th)
        elif t % 4 == 2:
            x = rng.uniform(size=m)
            y = 0.3 * x + 1e-6 * rng.standard_normal(m)
        else:
            th = 2 * np.pi * np.arange(m) / m
            x, y = np.cos(th), np.sin(th)
        i, j = np.array(list(combinations(range(m), 2))).T
        ex, ey = x[j] - x[i], y[j] - y[i]
        n = np.hypot(ex, ey)
        nx, ny = -ey[n > 0] / n[n > 0], ex[n > 0] / n[n > 0]
        proj = nx[:, None] * x[None, :] + ny[:, None] * y[None, :]
        brute = float((proj.max(axis=1) - proj.min(axis=1)).min())
        w = least_width_exact(x, y)
        ulps = np.finfo(float).eps * max(np.abs(x).max(), np.abs(y).max())
        assert abs(w - brute) <= WIDTH_ROUNDING * ulps, (t, w, brute)


def test_box_bounds_by_blocks_are_those_of_all_boxes_at_once():
    """_global.box_values bounds the branch and bound's boxes a block at a time (peak memory): bitwise the values
    computed for all boxes at once (the distance intervals, the pair bound, the centre values)."""
    from methods.circle import _global as g
    rng = np.random.default_rng(3)
    xs, ys = rng.standard_normal(37), rng.standard_normal(37)
    cx, cy = rng.uniform(-2, 2, 500), rng.uniform(-2, 2, 500)
    dmin, dmax, dc = g.box_distance_bounds(cx, cy, 0.05, xs, ys)
    whole_zone = np.maximum(dmin.max(axis=1) - dmax.min(axis=1), g.pair_bound(cx, cy, 0.05, xs, ys, dc))
    for budget in (1, 37, 100, 1024, 10 ** 6):
        bound, centre = g.box_values(cx, cy, 0.05, xs, ys, True, budget)
        assert np.array_equal(bound, whole_zone) and np.array_equal(centre, dc.max(axis=1) - dc.min(axis=1))
        bound, centre = g.box_values(cx, cy, 0.05, xs, ys, False, budget)
        assert np.array_equal(bound, dmax.min(axis=1)) and np.array_equal(centre, dc.min(axis=1))
