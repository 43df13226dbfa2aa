"""A command's warnings come before its figures and go into what the user keeps: the ``--report`` page (a framed box
above the figures) and the ``--json`` result (``warnings``, beside ``notes``). Before, they were recorded and printed
when the command ended: after the whole table on the terminal ("radius 298999.97 mm" above "is the file in µm?"),
and never in the report ("max U(P_i) = 2309.401 µm" for ``--mpe 2`` with no word) nor in the JSON that
``fitbench history`` trends."""
import contextlib
import io
import json

import matplotlib
import numpy as np
import pytest

from cli_calls import cli
from fitbench.cli import main
from positioning_tables import axis_csv


def terminal(*args):
    """(exit status, stdout and stderr interleaved as a terminal shows them)."""
    both = io.StringIO()
    with contextlib.redirect_stdout(both), contextlib.redirect_stderr(both):
        code = main([str(a) for a in args])
    return code, both.getvalue()


def json_of(*args):
    """(exit status, the --json object, stderr)."""
    called = cli(*args, "--json")
    return called.returncode, json.loads(called.stdout), called.stderr


def report_text(tmp_path, *args) -> str:
    """The text of the one-page report of a command (written as SVG with its text kept as text)."""
    page = tmp_path / "report.svg"
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        code, shown = terminal(*args, "--report", page)
    assert code == 0, shown
    return page.read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def axis_file(tmp_path_factory):
    return axis_csv(tmp_path_factory.mktemp("pos"))[0]


@pytest.fixture(scope="module")
def trace_in_um(tmp_path_factory):
    """A 299 mm circle written in µm under a header without units (read as mm: R = 299000 'mm')."""
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    r = 299000.0 + 3.0 * np.cos(3 * t)
    path = tmp_path_factory.mktemp("fit") / "trace_um.csv"
    np.savetxt(path, np.c_[r * np.cos(t), r * np.sin(t)], delimiter=",", header="x,y", comments="", fmt="%.4f")
    return path


@pytest.fixture(scope="module")
def polar_without_unit(tmp_path_factory):
    """Angle + radial deviation in µm (2 µm lobes) under a deviation column that names no unit: read as mm."""
    t = np.arange(0, 360, 1.0)
    dev = 2.0 * np.cos(np.radians(3 * t)) + 0.3 * np.cos(np.radians(7 * t))
    path = tmp_path_factory.mktemp("polar") / "polar_nounit.csv"
    np.savetxt(path, np.c_[t, dev], delimiter=",", header="Angle [deg],Deviation", comments="", fmt="%.5f")
    return path


MPE_WARNING = "--mpe 2 is read as 2 mm (a bare number is mm)"


def test_the_unit_warning_of_fit_comes_before_the_figures(trace_in_um):
    code, shown = terminal("fit", "circle.gauss_newton", trace_in_um)
    assert code == 0
    warning = shown.index("warning: profile radii (half the points' span) up to 299000 mm (read as mm) are "
                          "implausible; is the file in µm? (--unit um)")
    assert warning < shown.index("radius ") and warning < shown.index("form error")


def test_the_warnings_of_fit_are_in_its_json(trace_in_um):
    code, d, err = json_of("fit", "circle.gauss_newton", trace_in_um)
    assert code == 0 and "implausible" in err
    assert [w for w in d["warnings"] if "is the file in µm? (--unit um)" in w] and d["units"]["length"] == "mm"


def test_a_bare_mpe_warning_is_in_the_positioning_json_and_report(axis_file, tmp_path):
    code, d, err = json_of("positioning", axis_file, "--mpe", "2")
    assert code == 0 and MPE_WARNING in err
    assert len(d["warnings"]) == 1 and d["warnings"][0].startswith(MPE_WARNING)
    assert f"warning: {MPE_WARNING}" in report_text(tmp_path, "positioning", axis_file, "--mpe", "2")
    code, d, err = json_of("positioning", axis_file, "--mpe", "2um")     # nothing to warn about: an empty list
    assert code == 0 and d["warnings"] == [] and "warning" not in err
    assert "warning:" not in report_text(tmp_path, "positioning", axis_file, "--mpe", "2um")


def test_the_implausible_deviation_warning_of_roundness_is_in_its_report_and_json(polar_without_unit, tmp_path):
    code, d, err = json_of("roundness", polar_without_unit)
    assert code == 0 and "(--unit um)" in err
    said = [w for w in d["warnings"] if "radial deviations up to" in w and "--unit um" in w]
    assert said and any("read as mm" in n for n in d["notes"])
    page = report_text(tmp_path, "roundness", polar_without_unit)
    assert "warning: radial deviations up to" in page
    code, shown = terminal("roundness", polar_without_unit)
    assert shown.index("warning: radial deviations up to") < shown.index("RONt [µm]")


def test_a_circular_test_warning_is_in_its_json_and_report(tmp_path):
    from profile_lines import circular_runs_file
    runs = circular_runs_file(tmp_path / "runs.csv")
    args = ("circular-test", runs, "--nominal-radius", 100, "--feed", 1)
    code, d, err = json_of(*args)
    assert code == 0 and "--feed 1 mm/min" in err
    assert [w for w in d["warnings"] if w.startswith("--feed 1 mm/min: one revolution")]
    assert "warning: --feed 1 mm/min" in report_text(tmp_path, *args)
