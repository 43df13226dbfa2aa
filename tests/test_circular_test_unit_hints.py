"""Circular-test data off the nominal circle: the hint names the option that is wrong, in the unit the user gave.

A file in mm with --nominal-radius typed in µm, a file in mm read with --unit um, and a nominal centre far from the
data were each told the wrong thing: 'is the file in m? (--unit m)' (the hint was computed from the size in mm, not
from the declared unit), or a 'radius' that was the distance from the nominal centre, after a spurious 'runs given in
the wrong order' warning judged about that far centre."""
from __future__ import annotations

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from datasets.circular_test import circular_test, lola_hbg130
from methods import InvalidInputError
from methods.circular_test import evaluate


@pytest.fixture(scope="module")
def lola(tmp_path_factory):
    """The LOLA HBG 130 runs in mm: R 298.997 mm about (1200, 650) mm."""
    d = tmp_path_factory.mktemp("lola")
    cond, err = lola_hbg130()
    cw, ccw, _ = circular_test(cond, err, seed=2004)
    for name, pts in (("cw", cw), ("ccw", ccw)):
        np.savetxt(d / f"{name}.csv", pts, delimiter=",", header="x,y", comments="", fmt="%.9f")
    return d, cw, ccw


def test_nominal_radius_typed_in_micrometres_names_the_radius_not_the_file(lola):
    d, _, _ = lola
    called = cli("circular-test", d / "cw.csv", d / "ccw.csv", "--nominal-radius", 298997)
    one_error_line(called, "is --nominal-radius in µm?", "--nominal-radius 298.997", absent=("--unit m",))


def test_file_in_mm_read_as_micrometres_says_unit_mm(lola):
    d, _, _ = lola
    called = cli("circular-test", d / "cw.csv", d / "ccw.csv", "--nominal-radius", 298.997, "--unit", "um")
    one_error_line(called, "read as µm", "(--unit mm)", absent=("--unit m)",))


def test_far_nominal_centre_with_the_wrong_unit_is_said_before_any_run_swap(lola):
    d, _, _ = lola
    called = cli("circular-test", d / "cw.csv", d / "ccw.csv", "--nominal-radius", 298.997, "--unit", "um",
                 "--nominal-center", 1200, 650)
    one_error_line(called, "from --nominal-center (1200, 650) mm", "(--unit mm)",
                   absent=("wrong order", "swapped", "the data's radius"))


def test_wrong_nominal_centre_with_the_right_radius_says_check_the_centre(lola):
    d, _, _ = lola
    called = cli("circular-test", d / "cw.csv", d / "ccw.csv", "--nominal-radius", 298.997,
                 "--nominal-center", 1200, 65)
    one_error_line(called, "check --nominal-center", "centred at (1199.99, 650.01) mm",
                   absent=("wrong order", "--unit"))


def test_nominal_radius_and_centre_both_typed_in_micrometres(lola):
    d, _, _ = lola
    called = cli("circular-test", d / "cw.csv", d / "ccw.csv", "--nominal-radius", 298997,
                 "--nominal-center", 1200000, 650000)
    one_error_line(called, "are --nominal-radius and --nominal-center in µm?",
                   "--nominal-radius 298.997 --nominal-center 1200 650")


def test_file_in_micrometres_read_as_mm_still_says_unit_um(lola, tmp_path):
    _, cw, ccw = lola
    for name, pts in (("cw", cw), ("ccw", ccw)):
        np.savetxt(tmp_path / f"{name}.csv", pts * 1e3, delimiter=",", header="x,y", comments="", fmt="%.6f")
    called = cli("circular-test", tmp_path / "cw.csv", tmp_path / "ccw.csv", "--nominal-radius", 298.997,
                 "--nominal-center", 1200, 650)
    one_error_line(called, "is the file in µm? (--unit um)")


def test_api_hint_uses_the_declared_input_unit(lola):
    _, cw, ccw = lola
    with pytest.raises(InvalidInputError, match=r"read as µm.*\(--unit mm\)"):
        evaluate(cw * 1e-3, ccw * 1e-3, 298.997, conditions={"input_unit": "µm"})
    with pytest.raises(InvalidInputError, match="check --nominal-center"):
        evaluate(cw, ccw, 298.997, nominal_center=(1200.0, 65.0))
