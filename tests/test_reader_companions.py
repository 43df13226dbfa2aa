"""x, y files with further coordinate columns: the nominal path plus deviations (``X [mm];Y [mm];dX [µm];dY [µm]``,
a grid-encoder export) or nominal and actual side by side (``X,Y,X act,Y act``, ``X,Y,Xm,Ym``, a CMM export). The
reader took the first two names and evaluated the nominal circle: G 0.11 µm for a 7 µm trace, exit 0, no word.
The expected figures here are computed from the generating deviations with plain NumPy."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from datasets.io import DataFileError, read_points, read_profile, read_runs


N, R = 360, 100.0


def trace(sign, seed=4):
    """Nominal and actual points of a 2-lobe 3 µm circle with 0.2 µm noise (the review's recipe, fewer points)."""
    rng = np.random.default_rng(seed)
    t = sign * np.arange(N) * 2 * np.pi / N
    dr = 0.003 * np.cos(2 * t) + rng.normal(0, 2e-4, N)
    nom = np.c_[R * np.cos(t), R * np.sin(t)]
    act = np.c_[(R + dr) * np.cos(t), (R + dr) * np.sin(t)]
    return np.round(nom, 4), np.round(act, 7)


def kgm_file(path, sign=1, dev_unit="µm"):
    nom, act = trace(sign)
    f = 1000.0 if dev_unit == "µm" else 1.0
    d = (act - nom) * f
    head = f"X [mm];Y [mm];dX [{dev_unit}];dY [{dev_unit}]" if dev_unit else "X [mm];Y [mm];dX;dY"
    path.write_text(head + "\n" + "\n".join(f"{a:.4f};{b:.4f};{c:.7f};{e:.7f}" for (a, b), (c, e) in zip(nom, d)) + "\n",
                    encoding="utf-8")
    return path, nom + d / f


def nomact_file(path, names=("X", "Y", "X act", "Y act")):
    """Nominal then actual x, y; a first name 'Point' adds a point label column in front."""
    nom, act = trace(1)
    label = [f"P{k}," for k in range(N)] if names[0] == "Point" else [""] * N
    path.write_text(",".join(names) + "\n" + "\n".join(f"{p}{a:.4f},{b:.4f},{c:.7f},{e:.7f}"
                                                       for p, (a, b), (c, e) in zip(label, nom, act)) + "\n",
                    encoding="utf-8")
    return path, act


def ptp_radius_um(pts, centre=(0.0, 0.0)):
    return float(np.ptp(np.hypot(pts[:, 0] - centre[0], pts[:, 1] - centre[1]))) * 1000.0


def test_deviation_columns_are_added_to_the_nominal_in_their_own_unit(tmp_path):
    for unit in ("µm", "mm"):
        path, want = kgm_file(tmp_path / f"kgm_{unit}.csv", dev_unit=unit)
        got = read_points(path)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
        assert ptp_radius_um(got) > 5.0          # the trace, not the 4-decimal rounding of the nominal circle
        runs = read_runs(path, nominal_radius=R)
        np.testing.assert_allclose(runs.runs[0][1], want, rtol=0, atol=1e-9)
        assert "nominal plus deviation" in runs.columns_note and runs.axes == ("x", "y")


@pytest.mark.parametrize("names", [("X", "Y", "X act", "Y act"), ("X", "Y", "Xm", "Ym"),
                                   ("Point", "X nominal", "Y nominal", "X actual", "Y actual")])
def test_actual_columns_are_read_not_the_nominal(tmp_path, names):
    path, act = nomact_file(tmp_path / "cmm.csv", names)
    got = read_profile(path)
    np.testing.assert_allclose(got.runs[0][1], act, rtol=0, atol=1e-9)
    assert got.columns_note.startswith("read the actual columns") and got.axes == ("x", "y")


def test_unplaceable_numeric_columns_are_refused_and_columns_chooses(tmp_path):
    path, _ = nomact_file(tmp_path / "odd.csv", ("X", "Y", "Xq", "Yq"))
    with pytest.raises(DataFileError, match=r"besides 'X', 'Y' the header has the numeric column\(s\) 'Xq', 'Yq'.*"
                                             r"--columns NAME NAME"):
        read_points(path)
    np.testing.assert_allclose(read_points(path, ("Xq", "Yq")), trace(1)[1], atol=1e-9)   # the user's choice
    out = cli("roundness", path, "--cutoff", "none")
    one_error_line(out, "'Xq', 'Yq'", "--columns")


def test_point_numbers_times_and_angles_beside_x_y_are_not_unread_coordinates(tmp_path):
    nom, act = trace(1)
    path = tmp_path / "log.csv"
    path.write_text("Point;Time [s];X [mm];Y [mm];Angle [deg]\n" + "\n".join(
        f"{k};{0.01 * k:.2f};{a:.7f};{b:.7f};{np.degrees(np.arctan2(b, a)):.4f}" for k, (a, b) in enumerate(act)) + "\n")
    np.testing.assert_allclose(read_points(path), act, atol=1e-9)


def test_a_deviation_column_without_unit_is_refused(tmp_path):
    path, _ = kgm_file(tmp_path / "nounit.csv", dev_unit="")
    with pytest.raises(DataFileError, match=r"the deviation column 'dX' names no unit"):
        read_points(path)


def test_a_second_length_column_of_a_polar_file_is_refused(tmp_path):
    path = tmp_path / "pol.csv"
    a = np.arange(0, 360, 1.0)
    path.write_text("Angle (deg);Deviation (um);Deviation filtered (um)\n"
                    + "\n".join(f"{v:.1f};{np.cos(2 * np.radians(v)):.4f};{0.9 * np.cos(2 * np.radians(v)):.4f}"
                                for v in a) + "\n")
    with pytest.raises(DataFileError, match=r"'Deviation filtered \(um\)'; give --columns ANGLE DEVIATION"):
        read_profile(path)
    assert len(read_profile(path, columns=("Angle", "Deviation filtered")).runs[0][1]) == len(a)


def test_circular_test_of_a_deviation_export_gives_the_trace_G(tmp_path):
    (cw, want_cw), (ccw, want_ccw) = kgm_file(tmp_path / "cw.csv", -1), kgm_file(tmp_path / "ccw.csv", 1)
    out = cli("circular-test", cw, ccw, "--nominal-radius", R, "--nominal-center", 0, 0, "--json")
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    # G is the radial span about the least-squares centre (ISO 230-4); with the true centre at 0 it differs
    # from the span about (0, 0) by far less than the 7 µm trace
    g_cw, g_ccw = (got[k] * 1000.0 for k in ("G_cw", "G_ccw"))
    assert abs(g_cw - ptp_radius_um(want_cw)) < 0.05 and abs(g_ccw - ptp_radius_um(want_ccw)) < 0.05
    assert any("nominal plus deviation" in n for n in got["notes"])
