"""Degrees read as radians over an arc too short for the revolution count to tell (review16 V4).

An arc of 20° in degrees under an 'Angle [rad]' header (0.000, 0.100, ..., 20.000) turns 3.2 times read as radians,
under the 4 revolutions beyond which such angles are refused; `fit` gave radius 50.00041 mm (49.99716 mm in degrees),
exit 0, no word. Angles read as radians that turn more than once in equal steps of a round number of degrees from a
whole multiple of it are named (a note for fit, a hint in roundness's refusal): radian data over more than a
revolution is sampled at 2 pi i / N, not at round decimals."""
from __future__ import annotations

import numpy as np
import pytest

from cli_calls import cli, one_error_line


def arc_file(path, angles, header="Angle [rad];Deviation [um]", digits=3):
    dev = 0.5 + 0.02 * np.cos(7 * np.asarray(angles))
    path.write_text(header + "\n" + "".join(f"{a:.{digits}f};{d:.4f}\n" for a, d in zip(angles, dev)))
    return path


HINT = ("the angles of 'Angle [rad]' run from 0 to 20 in equal steps of 0.1: read as radians they turn 3.18 times; "
        "if they are degrees (a 20° arc), correct the header of 'Angle [rad]' to [deg]")


def test_a_short_arc_in_degrees_under_a_radian_header_is_named(tmp_path):
    p = arc_file(tmp_path / "arc20.csv", np.arange(201) * 0.1)
    code, out, err = cli("fit", "circle.gauss_newton", p, "--nominal-radius", 50)
    assert code == 0 and HINT in out + err, (out, err)
    one_error_line(cli("roundness", p), "more than one revolution", HINT)
    q = arc_file(tmp_path / "arc20_given.csv", np.arange(201) * 0.1, header="Angle;Deviation [um]")
    code, out, err = cli("fit", "circle.gauss_newton", q, "--nominal-radius", 50, "--angle-unit", "rad")
    assert code == 0 and "if they are degrees (a 20° arc), give --angle-unit deg, not rad" in out + err, (out, err)


@pytest.mark.parametrize("angles", [
    np.linspace(0, 6 * np.pi, 1080, endpoint=False),       # three revolutions sampled at 2 pi i / N
    np.arange(63) * 0.1,                                     # one revolution in steps of 0.1 rad
    np.r_[np.arange(100) * 0.1, 10.05, np.arange(101, 201) * 0.1],   # steps not all equal
])
def test_radians_that_do_not_look_like_round_degrees_are_not_named(tmp_path, angles):
    p = arc_file(tmp_path / "rad.csv", angles, digits=6)
    code, out, err = cli("fit", "circle.gauss_newton", p, "--nominal-radius", 50)
    assert code == 0 and "if they are degrees" not in out + err, (out, err)
