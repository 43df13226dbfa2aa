"""Global certificates of the minimum zone and the MIC against an independent exhaustive enumeration
(written here; it shares no code with methods.circle._global or _zone)."""
from itertools import combinations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import methods


def _centre_through(a, b, c, d):
    """Solve |z-a| = |z-b|, |z-c| = |z-d| by Cramer's rule (loops over index tuples: test code only)."""
    M = np.array([[b[0] - a[0], b[1] - a[1]], [d[0] - c[0], d[1] - c[1]]])
    rhs = 0.5 * np.array([b @ b - a @ a, d @ d - c @ c])
    if abs(np.linalg.det(M)) < 1e-14 * (np.abs(M).max() ** 2 + 1e-300):
        return None
    return np.linalg.solve(M, rhs)


def reference(P):
    """Exhaustive: minimum-zone width over all 2+2, 3+1, 1+3 centres; MIC radius over all circumcentres
    inside the profile polygon and all bisector/polygon-edge crossings."""
    from matplotlib.path import Path
    P = P - P.mean(axis=0)
    n = len(P)
    cands = []
    for q in combinations(range(n), 4):
        for (i, j, k, l) in ((0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2)):
            z = _centre_through(P[q[i]], P[q[j]], P[q[k]], P[q[l]])
            if z is not None:
                cands.append(z)
    circ = []
    for t in combinations(range(n), 3):
        z = _centre_through(P[t[0]], P[t[1]], P[t[1]], P[t[2]])
        if z is not None:
            circ.append(z)
    C = np.array(cands + circ)
    R = np.linalg.norm(P[None, :, :] - C[:, None, :], axis=2)
    mz = (R.max(axis=1) - R.min(axis=1)).min()
    poly = P[np.argsort(np.arctan2(P[:, 1], P[:, 0]))]
    Ci = np.array(circ)
    inside = Path(np.vstack([poly, poly[:1]])).contains_points(Ci)
    mic_c = list(Ci[inside])
    for e in range(n):
        s0, s1 = poly[e], poly[(e + 1) % n]
        for i, j in combinations(range(n), 2):
            nrm = P[j] - P[i]
            den = nrm @ (s1 - s0)
            if abs(den) < 1e-300:
                continue
            t = (0.5 * (P[j] @ P[j] - P[i] @ P[i]) - nrm @ s0) / den
            if 0 <= t <= 1:
                mic_c.append(s0 + t * (s1 - s0))
    M = np.array(mic_c)
    mic = np.linalg.norm(P[None, :, :] - M[:, None, :], axis=2).min(axis=1).max()
    return mz, mic


@st.composite
def profiles(draw):
    n = draw(st.integers(5, 24))
    seed = draw(st.integers(0, 2**32 - 1))
    kind = draw(st.sampled_from(["lobes", "random", "clusters", "ties", "two_arcs"]))
    rng = np.random.default_rng(seed)
    if kind == "ties":
        t = np.arange(n) * 2 * np.pi / n
    elif kind == "clusters":
        t = np.concatenate([rng.normal(c, 0.05, n // 3 + 1) for c in (0.0, 2.1, 4.2)])[:n]
    elif kind == "two_arcs":
        t = np.concatenate([rng.uniform(0, 1.2, n // 2), rng.uniform(np.pi, np.pi + 1.2, n - n // 2)])
    else:
        t = np.sort(rng.uniform(0, 2 * np.pi, n))
        t[::max(1, n // 4)] = np.linspace(0, 2 * np.pi, len(t[::max(1, n // 4)]), endpoint=False)
    lobes = draw(st.integers(2, 7))
    amp = draw(st.sampled_from([1e-3, 1e-2, 0.05]))
    r = 10 + (amp * 10 * np.cos(lobes * t) if kind in ("lobes", "ties") else rng.normal(0, amp * 10, len(t)))
    centre = rng.uniform(-100, 100, 2)
    return centre + np.column_stack([r * np.cos(t), r * np.sin(t)])


def check(P):
    mz, mic = reference(P)
    z = methods.fit("circle.minimum_zone", P)
    assert z.extra["certified"] == "global" and z.converged, z.message
    assert z.form_error == pytest.approx(mz, rel=1e-9, abs=1e-12)
    m = methods.fit("circle.max_inscribed", P)
    if m.extra.get("angular_gap_deg", 0) >= 180:
        return
    assert m.extra["certified"] == "global" and m.converged, m.message
    assert m.radius == pytest.approx(mic, rel=1e-9)


@settings(max_examples=40, deadline=None)
@given(P=profiles())
def test_random_and_adversarial_profiles_are_globally_certified(P):
    check(P)


def test_issue_15_reproduction_is_the_global_optimum():
    P = np.array([[90.497956, 35.704324], [84.553751, 32.249277], [89.414272, 33.958251],
                  [101.902308, 31.249986], [105.84896, 28.085133], [109.001617, 33.26123]])
    res = methods.fit("circle.minimum_zone", P)
    assert res.extra["certified"] == "global", res.message
    assert res.form_error == pytest.approx(5.17575, abs=1e-5)
    assert res.form_error == pytest.approx(reference(P)[0], rel=1e-9)


def test_symmetric_lobes_find_alternating_contacts():
    t = np.arange(8) * 2 * np.pi / 8
    r = 10 + 0.1 * np.cos(4 * t)
    P = np.column_stack([r * np.cos(t), r * np.sin(t)])
    for mid in ("circle.minimum_zone", "circle.max_inscribed"):
        res = methods.fit(mid, P)
        assert res.converged and res.extra["certified"] == "global", res.message
        assert res.form_error == pytest.approx(0.2, rel=1e-9)


def test_mic_stays_inside_the_data():
    rng = np.random.default_rng(5)
    for _ in range(10):
        t = np.sort(rng.uniform(0, 2 * np.pi, 9))
        P = np.column_stack([10 * np.cos(t), 10 * np.sin(t)]) + rng.normal(0, 0.3, (9, 2))
        res = methods.fit("circle.max_inscribed", P)
        if res.converged:
            assert res.radius <= 10 * 1.2 and np.hypot(*res.center) <= 10


def test_dense_trace_is_globally_certified():
    rng = np.random.default_rng(3358)
    t = rng.uniform(0, 2 * np.pi, 3358)
    P = np.column_stack([1200 + 299 * np.cos(t), 650 + 299 * np.sin(t)]) + rng.normal(0, 0.005, (3358, 2))
    for mid in ("circle.minimum_zone", "circle.max_inscribed"):
        res = methods.fit(mid, P)
        assert res.extra["certified"] == "global", res.message
