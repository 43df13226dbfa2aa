"""Translating, rotating or scaling the data transforms every method's result accordingly."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import methods
from method_ids import method_ids

ALL = method_ids("circle")


@st.composite
def noisy_circles(draw):
    n = draw(st.integers(6, 80))
    cx, cy = draw(st.floats(-1e3, 1e3)), draw(st.floats(-1e3, 1e3))
    radius = draw(st.floats(0.5, 500.0))
    span = draw(st.floats(np.pi / 2, 2 * np.pi))
    start = draw(st.floats(0, 2 * np.pi))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    t = start + np.sort(rng.uniform(0, span, n))
    r = radius * (1 + rng.normal(0, 1e-3, n))
    return np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t)])


def _tol(method_id, radius):
    # Nelder–Mead stops where value comparisons stop resolving the optimum, which depends on the
    # orientation of its simplex; the other methods are invariant to rounding.
    return (1e-6 if method_id == "circle.nelder_mead" else 1e-9) * radius


@pytest.mark.parametrize("method_id", ALL)
@settings(max_examples=20, deadline=None)
@given(pts=noisy_circles(), shift=st.tuples(st.floats(-1e4, 1e4), st.floats(-1e4, 1e4)),
       angle=st.floats(0, 2 * np.pi), scale=st.floats(1e-2, 1e2))
def test_similarity_equivariance(method_id, pts, shift, angle, scale):
    base = methods.fit(method_id, pts)
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, -s], [s, c]])
    moved = scale * pts @ rot.T + shift
    res = methods.fit(method_id, moved)
    if method_id == "circle.max_inscribed" and not base.converged:
        # an arc has no MIC: the refusal itself must be invariant
        assert not res.converged and "partial arc" in base.message and "partial arc" in res.message
        return
    assert base.converged, base.message
    assert res.converged, res.message
    want_center = scale * rot @ np.array(base.center) + shift
    # plus the rounding of the coordinates themselves (a tiny circle far away is coarsely represented)
    tol = _tol(method_id, scale * base.radius) + 64 * np.finfo(float).eps * (np.abs(moved).max() + np.abs(pts).max() * scale)
    assert np.abs(np.array(res.center) - want_center).max() <= tol
    assert abs(res.radius - scale * base.radius) <= tol
    assert abs(res.form_error - scale * base.form_error) <= 4 * tol


@pytest.mark.parametrize("method_id", ALL)
def test_point_order_does_not_matter(method_id, rng):
    t = rng.uniform(0, 2 * np.pi, 50)
    pts = np.column_stack([3 + 2 * np.cos(t), -1 + 2 * np.sin(t)]) + rng.normal(0, 1e-3, (50, 2))
    a = methods.fit(method_id, pts)
    b = methods.fit(method_id, pts[::-1])
    tol = _tol(method_id, 2.0)
    assert np.abs(np.array(a.center) - b.center).max() <= tol and abs(a.radius - b.radius) <= tol
