"""The x, y profile checks of the readers (a trace past one revolution, a profile spanning less than an instrument
resolves) start from one helper, :func:`datasets.io.polar.profile_circle`: nothing to check for fewer than 4 points,
a value that is not finite or no circle; else the points and their circle, computed once."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from datasets.io.layout import Layout
from datasets.io.polar import circle_through, profile_circle, warn_too_small_xy
from datasets.io.runs import xy_beyond_one_revolution


def ring(n=12, radius=10.0):
    t = 2 * np.pi * np.arange(n) / n
    return np.c_[radius * np.cos(t), radius * np.sin(t)]


@pytest.mark.parametrize("points", [ring(3), np.r_[ring(8), [[np.nan, 0.0]]], np.r_[ring(8), [[np.inf, 0.0]]],
                                    np.arange(8.0)], ids=["3 points", "nan", "inf", "1-D"])
def test_nothing_to_check(points):
    assert profile_circle(points) is None
    layout = Layout(name="p.csv", sep=",", decimal_comma=False, header=["x", "y"], header_line=1, first_data_line=2,
                    ncol=2, comment="#")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert warn_too_small_xy(layout, (0, 1), points, (np.arange(3.0), np.arange(3.0)), "mm", None) is False
    assert xy_beyond_one_revolution(layout, points) is None


def test_the_points_and_their_circle():
    p, circle = profile_circle(ring().tolist())
    assert isinstance(p, np.ndarray) and p.dtype == float and p.shape == (12, 2)
    assert circle == circle_through(ring())
    np.testing.assert_allclose(circle, (0.0, 0.0, 10.0), atol=1e-12)
    given = (1.0, 2.0, 3.0)                       # a circle computed already is used as it is
    assert profile_circle(ring(), given)[1] == given
    assert profile_circle(ring(), (np.nan, np.nan, np.nan)) is None   # no circle: nothing to check
    layout = Layout(name="p.csv", sep=",", decimal_comma=False, header=["x", "y"], header_line=1, first_data_line=2,
                    ncol=2, comment="#")
    assert xy_beyond_one_revolution(layout, ring(), (np.nan, np.nan, np.nan)) is None


@pytest.mark.parametrize("points", [np.c_[np.arange(10.0), 2 * np.arange(10.0)], np.ones((6, 2))],
                         ids=["collinear", "coincident"])
def test_points_on_a_line_have_no_circle(points):
    """Exactly collinear (or coincident) points have no circle: the least-squares system is rank-deficient, and its
    minimum-norm solution was a finite made-up circle ((i, 2i): centre (2.5, 5), r 3.82) that the checks measured
    the profile about."""
    assert np.isnan(circle_through(points)).all()
    assert profile_circle(points) is None
