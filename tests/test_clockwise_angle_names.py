"""An angle column whose name says clockwise ('Angle CW (deg)', 'CW angle [deg]', 'Winkel im Uhrzeigersinn [°]').

Since any angle-unit column is the angle, such a column was read counter-clockwise: a clockwise instrument's profile
came out mirrored (roundness centre y of the wrong sign, same RONt), a ballbar export's runs swapped and its
squareness of the wrong sign, exit 0. The name may also mean the clockwise run's angle, so it is refused in one line
asking for the convention. Counter-clockwise names (CCW, counter-clockwise, anticlockwise, gegen den Uhrzeigersinn)
read as 'Angle [deg]' does: same centres, same circular-test figures."""
from __future__ import annotations

import numpy as np
import pytest

from cli_calls import cli, one_error_line

CW_NAMES = ["Angle CW (deg)", "CW angle [deg]", "Angle (clockwise) [deg]", "Angle, clockwise [°]",
            "Winkel im Uhrzeigersinn [°]", "Angle_CW [rad]", "AngleCW [deg]", "CWAngle [deg]"]
CCW_NAMES = ["Angle CCW (deg)", "CCW angle [deg]", "Angle (counter-clockwise) [deg]", "Angle counter clockwise [deg]",
             "Anticlockwise angle [deg]", "Angle (anti-clockwise) [°]", "Winkel gegen den Uhrzeigersinn [°]",
             "Cwt angle [deg]", "AngleCCW [deg]", "CounterClockwise angle [deg]", "WinkelGegenUhrzeigersinn [°]"]


def profile_file(path, name):
    """A 360-point profile with 2 µm of 3-lobing and 1 µm of eccentricity towards +y (centre y +0.001 mm)."""
    deg = np.arange(360.0)
    dev = 2.0 * np.cos(np.radians(3 * deg)) + 1.0 * np.sin(np.radians(deg))
    ang = np.radians(deg) if "[rad]" in name else deg
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"{name};Deviation [um]\n" + "".join(f"{a:.6f};{d:.6f}\n" for a, d in zip(ang, dev)))
    return path


def mzci_centre(out):
    row = next(ln.split() for ln in out.splitlines() if ln.startswith("minimum zone circles (MZCI)"))
    return float(row[8]), float(row[9])


def ballbar_file(path, name):
    """Both runs of a circular test in one file (a direction column), angles counter-clockwise, with a squareness-like
    sin 2a term and 2-lobing."""
    path.parent.mkdir(parents=True, exist_ok=True)
    deg = np.arange(0, 360, 1.0)
    rows = [(run, a, 3 * np.cos(np.radians(2 * a)) + 1.5 * np.sin(np.radians(2 * a)) + (0.4 if run == "CW" else 0))
            for run, angles in (("CW", deg[::-1]), ("CCW", deg)) for a in angles]
    path.write_text(f"Direction;{name};Deviation [um]\n" + "".join(f"{r};{a:.3f};{d:.4f}\n" for r, a, d in rows))
    return path


@pytest.mark.parametrize("name", CW_NAMES)
def test_a_clockwise_angle_column_is_refused(tmp_path, name):
    p = profile_file(tmp_path / "cw.csv", name)
    for args in (("roundness", p), ("fit", "circle.minimum_zone", p, "--nominal-radius", 10)):
        one_error_line(cli(*args), f"column {name!r} names a clockwise direction", "negate them",
                       "reads angles counter-clockwise", "name the column 'Angle [")
    one_error_line(cli("roundness", p, "--columns", name, "Deviation [um]"), "names a clockwise direction")


def test_a_clockwise_angle_column_of_a_circular_test_is_refused(tmp_path):
    p = ballbar_file(tmp_path / "bb_cw.csv", "Angle CW [deg]")
    one_error_line(cli("circular-test", p, "--nominal-radius", 150), "'Angle CW [deg]' names a clockwise direction")


@pytest.mark.parametrize("name", CCW_NAMES)
def test_a_counter_clockwise_angle_column_reads_as_angle(tmp_path, name):
    """Same centre as under 'Angle [deg]' (y positive, the eccentricity's side), and the same circular test."""
    code, ref, err = cli("roundness", profile_file(tmp_path / "ref" / "p.csv", "Angle [deg]"))
    assert code == 0, err
    code, out, err = cli("roundness", profile_file(tmp_path / "named" / "p.csv", name))
    assert code == 0, err
    assert mzci_centre(out) == mzci_centre(ref) and mzci_centre(ref)[1] == pytest.approx(0.001, abs=2e-4)
    code, ref, err = cli("circular-test", ballbar_file(tmp_path / "ref" / "bb.csv", "Angle [deg]"), "--nominal-radius", 150)
    assert code == 0 and "squareness" in ref, err
    code, out, err = cli("circular-test", ballbar_file(tmp_path / "named" / "bb.csv", name), "--nominal-radius", 150)
    assert code == 0 and out == ref, err
