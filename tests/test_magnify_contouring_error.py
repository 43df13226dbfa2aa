"""The contouring error of a magnified plot is each measured point's distance from the reference path (Ibaraki &
Matsubara 2009, sec. 1), whichever method magnifies it: the offset method's |p - r~| (at a corner magnified
radially, the distance to the corner) is reported apart, under its own name. And a measured file in µm with a
reference in mm is read, each in its header's unit. ``--delta`` below the largest contouring error is refused in the
option's terms, with units (the refusal echoed the method's bare data-unit numbers: 'delta = 0.005 must be larger than
the largest contouring error (0.0056)', mm unsaid, for --delta 5um)."""
import json

import numpy as np
import pytest

import methods
from cli_calls import cli, one_error_line
from methods.magnify import MagnifyInput


def l_path_with_a_cut_corner():
    """An L path (corner at (100, 0) mm) and the same path measured with its corner cut: the corner point moved
    about 8 µm along the bisector, the cut fading out over 10 mm on both legs."""
    s = np.linspace(0, 1, 201)
    ref = np.r_[np.c_[s * 100, 0 * s], np.c_[100 + 0 * s[1:], s[1:] * 100]]
    meas = ref.copy()
    cut = np.clip(0.008 - np.hypot(*(ref - [100, 0]).T) * 0.0008, 0, None)
    meas[:, 0] -= cut * 0.7
    meas[:, 1] += cut * 0.7
    return ref, meas


def polyline_distance(points, polyline):
    """Each point's distance from the polyline (the nearest point of each segment, the least over segments)."""
    a, b = polyline[:-1], polyline[1:]
    ab = b - a
    ap = points[:, None, :] - a[None]
    t = np.clip((ap * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
    return np.hypot(*(ap - t[..., None] * ab).transpose(2, 0, 1)).min(axis=1)


@pytest.mark.parametrize("method_id", ["magnify.offset", "magnify.nearest"])
def test_contouring_error_is_the_distance_from_the_path(method_id):
    ref, meas = l_path_with_a_cut_corner()
    res = methods.fit(method_id, MagnifyInput(ref, meas), eta=500)
    e = polyline_distance(meas, ref)
    np.testing.assert_allclose(res.residuals, e, rtol=0, atol=1e-12)
    assert res.form_error == pytest.approx(e.max(), abs=1e-12) == res.extra["max_contouring_error"]
    lever = np.hypot(*(meas - res.reference_points).T)
    assert res.extra["max_magnified_distance"] == lever.max()
    if method_id == "magnify.offset":   # magnified radially about the corner, farther than the path
        assert lever.max() > 1.4 * e.max()


def test_nearest_method_unchanged():
    """The conventional method magnifies about the nearest point of the path: its |p - r~| is the contouring error."""
    ref, meas = l_path_with_a_cut_corner()
    res = methods.fit("magnify.nearest", MagnifyInput(ref, meas), eta=500)
    lever = np.hypot(*(meas - res.reference_points).T)
    np.testing.assert_array_equal(res.residuals, lever)
    assert res.form_error == lever.max() == res.extra["max_magnified_distance"]
    np.testing.assert_allclose(res.points, res.reference_points + 500 * (meas - res.reference_points), rtol=0, atol=0)
    np.testing.assert_allclose(lever, polyline_distance(meas, ref), rtol=0, atol=1e-12)


def write(path, xy, unit, fmt="%.6f"):
    np.savetxt(path, xy, fmt=fmt, delimiter=",", header=f"x [{unit}],y [{unit}]", comments="")
    return path


def test_cli_prints_the_distance_from_the_path(tmp_path):
    ref, meas = l_path_with_a_cut_corner()
    r, m = write(tmp_path / "ref.csv", ref, "mm"), write(tmp_path / "meas.csv", meas, "mm")
    e = polyline_distance(np.loadtxt(m, delimiter=",", skiprows=1), np.loadtxt(r, delimiter=",", skiprows=1)).max()
    for method in ("offset", "nearest"):
        out = cli("magnify", r, m, "--eta", 500, "--method", method)
        assert out.returncode == 0, out.stderr
        assert f"largest contouring error {e * 1e3:.3f} µm (distance from the reference path)" in out.stdout, out.stdout
    out = cli("magnify", r, m, "--eta", 500)
    lever = methods.fit("magnify.offset", MagnifyInput(ref, meas), eta=500).extra["max_magnified_distance"]
    assert f"up to {lever * 1e3:.3f} µm from the measured point" in out.stdout


def test_measured_in_um_with_a_reference_in_mm(tmp_path):
    """Each file in its header's unit, converted to mm: the same magnified points as both files in mm."""
    ref, meas = l_path_with_a_cut_corner()
    r = write(tmp_path / "ref.csv", ref, "mm")
    m_mm, m_um = write(tmp_path / "meas.csv", meas, "mm"), write(tmp_path / "meas_um.csv", meas * 1e3, "um", "%.3f")
    a, b = (cli("magnify", r, m, "--eta", 500, "--json") for m in (m_mm, m_um))
    assert a.returncode == 0 and b.returncode == 0, b.stderr
    da, db = json.loads(a.stdout), json.loads(b.stdout)
    np.testing.assert_allclose(db["points"], da["points"], rtol=0, atol=1e-9)
    assert db["units"]["input_unit"] == "µm" and db["units"]["reference_unit"] == "mm"
    text = cli("magnify", r, m_um, "--eta", 500)
    assert "input unit µm (converted to mm)" in text.stdout and "reference in mm" in text.stdout


def test_a_too_small_delta_is_refused_in_micrometres(tmp_path):
    ref, meas = l_path_with_a_cut_corner()
    r, m = write(tmp_path / "ref.csv", ref, "mm"), write(tmp_path / "meas.csv", meas, "mm")
    e_um = polyline_distance(np.loadtxt(m, delimiter=",", skiprows=1),
                             np.loadtxt(r, delimiter=",", skiprows=1)).max() * 1e3
    for delta in ("5um", "0.005"):
        called = cli("magnify", r, m, "--eta", 500, "--delta", delta)
        one_error_line(called, f"--delta 5 µm must be larger than the largest contouring error ({e_um:.4g} µm)",
                       "choose a larger --delta")
        assert "0.005" not in called.stderr, called.stderr
    code, out, err = cli("magnify", r, m, "--eta", 500, "--delta", f"{2 * e_um:.3g}um")
    assert code == 0, err
