"""Angles written in radians but read as degrees (--angle-unit deg, or a header saying deg) are named as such.

A revolution in radians (0 to 6.28) read as degrees is a 6° arc: roundness refused it as open ('no point between
6.3° and 0.0° (a gap of 354°)') without naming the likely cause. Now the line asks whether the angles are in radians
and says what to give; fit (which may fit an arc) notes it."""
from __future__ import annotations


import numpy as np
import pytest

from cli_calls import cli, one_error_line


def polar_file(path, angles, deviation_um, header="Angle,Radial deviation [um]", direction=None):
    cols = [angles, deviation_um] if direction is None else [direction, angles, deviation_um]
    with open(path, "w") as fh:
        fh.write(header + "\n")
        for row in zip(*cols):
            fh.write(",".join(str(v) if isinstance(v, str) else f"{v:.6f}" for v in row) + "\n")
    return path


@pytest.mark.parametrize("start", [0.0, -np.pi], ids=["0..2pi", "-pi..pi"])
def test_roundness_names_radians_read_as_degrees(tmp_path, start):
    t = np.linspace(start, start + 2 * np.pi, 720, endpoint=False)
    p = polar_file(tmp_path / "polar_rad.csv", t, 2.0 * np.cos(3 * t))
    one_error_line(cli("roundness", p, "--angle-unit", "deg"), "are they in radians?", "give --angle-unit rad")
    code, out, err = cli("roundness", p, "--angle-unit", "rad")   # read as radians: a closed profile, evaluated
    assert code == 0 and "RONt" in out, err


def test_header_saying_deg_is_named(tmp_path):
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    p = polar_file(tmp_path / "polar_rad.csv", t, 2.0 * np.cos(3 * t), header="Angle [deg],Radial deviation [um]")
    one_error_line(cli("roundness", p), "are they in radians?", "correct the header of 'Angle [deg]' to [rad]")


def test_circular_test_names_radians_read_as_degrees(tmp_path):
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    angles = np.r_[t[::-1], t]
    runs = np.r_[["cw"] * len(t), ["ccw"] * len(t)]
    p = polar_file(tmp_path / "ballbar.csv", angles, 3.0 * np.cos(2 * angles),
                   header="Direction,Angle,Radial deviation [um]", direction=runs)
    one_error_line(cli("circular-test", p, "--nominal-radius", 150, "--angle-unit", "deg"),
                   "are they in radians?", "less than the 90° needed")


def test_fit_notes_it_and_a_real_small_arc_in_degrees_is_not_refused(tmp_path):
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    p = polar_file(tmp_path / "polar_rad.csv", t, 2.0 * np.cos(3 * t))
    code, out, err = cli("fit", "circle.gauss_newton", p, "--angle-unit", "deg", "--nominal-radius", 50)
    assert "note: " in out and "are they in radians?" in out, (out, err)
    deg = np.linspace(0, 120, 121)     # a 120° arc in degrees: nothing to ask
    q = polar_file(tmp_path / "arc_deg.csv", deg, 2.0 * np.cos(np.radians(3 * deg)))
    code, out, err = cli("fit", "circle.gauss_newton", q, "--angle-unit", "deg", "--nominal-radius", 50)
    assert code == 0 and "radians" not in out + err, (out, err)
