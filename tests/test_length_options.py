"""Length and feed options take a unit as --mpe and --tolerance do: ``--nominal-radius 150mm``, ``--nominal-center
0mm 0mm``, ``--feed 2000mm/min`` (or 2m/min), ``--cyclic-pitch 10mm``, magnify's ``--delta 10um``; a bare number
keeps its unit (mm, mm/min). Before: argparse's "invalid float value: '150mm'", which did not say what to give."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line


@pytest.fixture
def runs(tmp_path):
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    r = 150 + 0.002 * np.cos(2 * t) + 0.001 * np.sin(3 * t)
    for name, sign in (("cw.csv", -1), ("ccw.csv", 1)):
        np.savetxt(tmp_path / name, np.column_stack([r * np.cos(sign * t), r * np.sin(sign * t)]), delimiter=",",
                   header="x,y", comments="")
    return "circular-test", tmp_path / "cw.csv", tmp_path / "ccw.csv"


def json_of(*args):
    out = cli(*args, "--json")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    d.pop("details", None)   # the command line as given
    d.pop("runtime_s", None)
    return d


def test_circular_test_options_with_units(runs):
    bare = json_of(*runs, "--nominal-radius", 150, "--nominal-center", 0, 0, "--feed", 2000, "--cyclic-pitch", 10)
    for radius, feed, pitch, centre in (("150mm", "2000mm/min", "10mm", "0mm"), ("0.15m", "2m/min", "10 mm", "0um"),
                                        ("150 mm", "33.333333333333336mm/s", "0.01m", "0")):
        given = json_of(*runs, "--nominal-radius", radius, "--nominal-center", centre, centre, "--feed", feed,
                        "--cyclic-pitch", pitch)
        assert given == bare, (radius, feed, pitch)


@pytest.mark.parametrize("option, value, words", [
    ("--nominal-radius", "150mmm", ("unknown unit 'mmm'", "a number in mm", "150mm")),
    ("--nominal-radius", "abc", ("'abc' is not a number", "a number in mm")),
    ("--nominal-radius", "150,5", ("a decimal comma", "--nominal-radius 150.5")),
    ("--feed", "2m/s", ("unknown unit 'm/s'", "a number in mm/min", "2m/min")),
    ("--cyclic-pitch", "10deg", ("unknown unit 'deg'", "a number in mm")),
])
def test_a_bad_value_says_what_to_give(runs, option, value, words):
    args = ["--nominal-radius", "150"] if option != "--nominal-radius" else []
    one_error_line(cli(*runs, *args, option, value), f"argument {option}", *words)


def test_nan_is_still_refused_by_the_numbers_check(runs):
    one_error_line(cli(*runs, "--nominal-radius", "nan"), "--nominal-radius must be a positive number")


def test_roundness_and_fit_nominal_radius_with_a_unit(tmp_path):
    a = np.arange(0.0, 360.0, 1.0)
    dev = 2.0 * np.cos(np.radians(3 * a)) + 0.5 * np.sin(np.radians(5 * a))
    p = tmp_path / "polar.csv"
    np.savetxt(p, np.column_stack([a, dev]), delimiter=",", header="Angle [deg],Deviation [um]", comments="")
    for cmd in (("roundness",), ("fit", "circle.kasa")):
        bare = json_of(*cmd, p, "--nominal-radius", 10)
        assert json_of(*cmd, p, "--nominal-radius", "10mm") == bare
        assert json_of(*cmd, p, "--nominal-radius", "10000um") == bare


def test_magnify_delta_with_a_unit(tmp_path):
    s = np.linspace(0, 10, 101)
    ref = np.column_stack([s, 0 * s])
    meas = np.column_stack([s, 0.002 * np.sin(s)])
    for name, xy in (("r.csv", ref), ("m.csv", meas)):
        np.savetxt(tmp_path / name, xy, delimiter=",", header="x [mm],y [mm]", comments="")
    bare = json_of("magnify", tmp_path / "r.csv", tmp_path / "m.csv", "--eta", 100, "--delta", 0.01)
    assert json_of("magnify", tmp_path / "r.csv", tmp_path / "m.csv", "--eta", 100, "--delta", "10um") == bare
