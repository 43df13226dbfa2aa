"""Magnified contouring errors: agreement on smooth paths, continuity at corners, loops, bad input."""
import json

import numpy as np
import pytest

import methods
from cli_calls import cli
from datasets.contouring import EXAMPLES, circle_glitches, corner_path, free_form
from methods import InvalidInputError
from methods.magnify import MagnifyInput


def test_straight_stretch_both_methods_agree(rng):
    ref = np.array([[0.0, 0.0], [100.0, 50.0]])
    s = np.linspace(5, 95, 500)
    normal = np.array([-50.0, 100.0]) / np.hypot(50, 100)
    meas = np.column_stack([s, s / 2]) + rng.normal(0, 0.01, 500)[:, None] * normal
    data = MagnifyInput(ref, meas)
    a = methods.fit("magnify.nearest", data, eta=500)
    b = methods.fit("magnify.offset", data, eta=500)
    np.testing.assert_allclose(a.points, b.points, atol=1e-9)
    # and the magnification is exactly r + eta (p - r) with r the foot of the perpendicular
    foot = np.column_stack([s, s / 2]) + ((meas - np.column_stack([s, s / 2])) @ (np.array([2.0, 1.0]) / np.sqrt(5)))[:, None] * np.array([2.0, 1.0]) / np.sqrt(5)
    np.testing.assert_allclose(a.reference_points, foot, atol=1e-9)


def test_smooth_curve_outside_both_methods_agree():
    """A circle given as a fine polyline, measured outside it: both methods agree to 1e-9 (away from the
    seam where the closed polyline starts and ends: it is treated as an open path with two ends there)."""
    ref, meas = circle_glitches(noise=0.0)
    data = MagnifyInput(ref, meas)
    a = methods.fit("magnify.nearest", data, eta=1000)
    b = methods.fit("magnify.offset", data, eta=1000)
    np.testing.assert_allclose(a.points[5:-5], b.points[5:-5], atol=1e-9)


@pytest.mark.parametrize("side, turn, jumps", [("inside", "left", True), ("outside", "left", False),
                                               ("outside", "right", False), ("inside", "right", True)])
def test_corners_conventional_jumps_offset_continuous(side, turn, jumps):
    """Paths inside and outside convex and concave corners (a left turn seen from the right is concave)."""
    data = MagnifyInput(*corner_path(side, turn))
    conv = methods.fit("magnify.nearest", data, eta=200).extra["continuity"]
    for delta_factor in (2.0, 10.0):
        emax = methods.fit("magnify.nearest", data, eta=200).form_error
        off = methods.fit("magnify.offset", data, eta=200, delta=delta_factor * emax)
        assert off.extra["continuity"] < 1.5, (delta_factor, off.extra)
    if jumps:
        assert conv > 5.0  # the metric says by how much: a jump of ~6 times the largest magnified step
    else:
        assert conv < 1.5  # outside a convex corner the nearest point is the vertex: radial, continuous


def test_printed_step_2_jumps_at_corners():
    """Step (2) as printed (the nearest point on either offset) picks the far offset near the corner."""
    data = MagnifyInput(*corner_path("inside", "left"))
    emax = methods.fit("magnify.nearest", data, eta=200).form_error
    printed = methods.fit("magnify.offset", data, eta=200, delta=10 * emax, selection="nearest_of_both")
    fixed = methods.fit("magnify.offset", data, eta=200, delta=10 * emax)
    assert printed.extra["continuity"] > 5.0 and fixed.extra["continuity"] < 0.5


def test_free_form_loops():
    """0.1 mm segments: the conventional plot's loops are counted; the offset plot has none once delta
    exceeds the magnified error (delta > eta e_max), and keeps them with delta = 2 e_max."""
    data = MagnifyInput(*free_form(wn=40.0))
    conv = methods.fit("magnify.nearest", data, eta=200)
    emax = conv.form_error
    assert conv.extra["self_intersections"] > 10
    assert methods.fit("magnify.offset", data, eta=200, delta=1.2 * 200 * emax).extra["self_intersections"] == 0
    assert methods.fit("magnify.offset", data, eta=200, delta=2 * emax).extra["self_intersections"] > 10


def test_all_examples_run():
    for name, make in EXAMPLES.items():
        data = MagnifyInput(*make())
        for method_id in ("magnify.nearest", "magnify.offset"):
            res = methods.fit(method_id, data, eta=100)
            assert res.converged and res.points.shape == data.measured.shape, name


@pytest.mark.parametrize("ref, meas, kw, match", [
    ([[0, 0], [10, 0]], [[1, 0.5], [2, 0.6]], {"delta": 0.5}, "must be larger than the largest contouring error"),
    ([[0, 0], [0, 0]], [[1, 0.5], [2, 0.6]], {}, "degenerate"),
    ([[0, 0]], [[1, 0.5], [2, 0.6]], {}, "at least 2 points"),
    ([[0, 0], [10, 0]], [[1, np.nan], [2, 0.6]], {}, "NaN"),
    ([[0, 0], [10, 0], [10, 10]], [[5, 0.1], [9, 0.2]], {"delta": 50.0}, "too large for this reference"),
])
def test_bad_input(ref, meas, kw, match):
    with pytest.raises(InvalidInputError, match=match):
        methods.fit("magnify.offset", (np.array(ref, float), np.array(meas, float)), eta=10, **kw)


def test_cli(tmp_path):
    ref, meas = corner_path("inside", "left", n=301)
    np.savetxt(tmp_path / "ref.csv", ref, delimiter=",", header="x,y", comments="")
    np.savetxt(tmp_path / "meas.csv", meas, delimiter=",", header="x,y", comments="")
    out = cli("magnify", tmp_path / "ref.csv", tmp_path / "meas.csv", "--eta", "200", "--json",
              "--plot", tmp_path / "m.png")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    assert len(d["points"]) == 301 and d["method"] == "magnify.offset"
    direct = methods.fit("magnify.offset", MagnifyInput(ref, meas), eta=200)
    np.testing.assert_allclose(d["points"], direct.points, atol=1e-12)
    assert (tmp_path / "m.png").stat().st_size > 5000
    bad = cli("magnify", tmp_path / "ref.csv", tmp_path / "meas.csv", "--eta", "200", "--delta", "0.001")
    assert bad.returncode == 2 and "larger than the largest contouring error" in bad.stderr and "Traceback" not in bad.stderr


def test_delta_as_a_multiple_of_the_largest_contouring_error():
    """delta_emax = k gives delta = k e_max, e_max being the nearest-point method's largest error (also reported
    by both methods as extra['max_contouring_error']); delta and delta_emax together are refused."""
    data = MagnifyInput(*free_form())
    nearest = methods.fit("magnify.nearest", data, eta=200)
    emax = nearest.form_error
    assert nearest.extra["max_contouring_error"] == emax
    by_multiple = methods.fit("magnify.offset", data, eta=200, delta_emax=1.2 * 200)
    by_length = methods.fit("magnify.offset", data, eta=200, delta=1.2 * 200 * emax)
    assert by_multiple.extra["delta"] == pytest.approx(1.2 * 200 * emax, rel=1e-15)
    assert by_multiple.extra["max_contouring_error"] == emax
    np.testing.assert_allclose(by_multiple.points, by_length.points, rtol=0, atol=1e-9)
    assert methods.fit("magnify.offset", data, eta=200).extra["delta"] == 2.0 * emax   # the default
    with pytest.raises(InvalidInputError, match="not both"):
        methods.fit("magnify.offset", data, eta=200, delta=1.0, delta_emax=2.0)
    with pytest.raises(InvalidInputError, match="must be larger than the largest contouring error"):
        methods.fit("magnify.offset", data, eta=200, delta_emax=0.5)
