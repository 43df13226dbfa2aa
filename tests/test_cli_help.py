"""The help texts say what the user typed and what each option of that subcommand takes: ``fitbench run --help``
printed ``usage: python -m experiments.run``; ``--run-directions`` rendered its choices as ``{up,down,up,down,down,up}``;
``magnify --columns`` offered angle files, which magnify refuses; ``fit``'s METHOD_ID had no help and its ``--json``
no units; docs/cli.md gave the fit JSON's ``history`` in "data units" where it holds squared lengths."""
import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest

from fitbench.cli import main

DOCS = Path(__file__).resolve().parents[1] / "docs"


def help_of(*args) -> str:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([*args, "--help"])
        except SystemExit as exc:
            code = exc.code
    assert code == 0 and not err.getvalue(), err.getvalue()
    return " ".join(out.getvalue().split())


@pytest.mark.parametrize("command", ["run", "report", "verify"])
def test_the_experiment_subcommands_name_the_command_typed(command):
    text = help_of(command)
    assert text.startswith(f"usage: fitbench {command} ") and "python -m experiments" not in text.split("options:")[0]


def test_an_experiment_subcommand_error_names_the_command_typed(capsys):
    assert main(["verify", "--no-such-option"]) == 2
    err = capsys.readouterr().err
    assert "fitbench verify: error: unrecognized arguments: --no-such-option" in err and "Traceback" not in err


def test_the_module_form_keeps_its_own_name(capsys):
    from experiments.verify import main as verify_main
    with pytest.raises(SystemExit):
        verify_main(["--help"])
    assert capsys.readouterr().out.startswith("usage: python -m experiments.verify ")


def test_run_directions_shows_its_four_choices_readably():
    text = help_of("positioning")
    assert "--run-directions {up|down|up,down|down,up}" in text and "{up,down,up,down,down,up}" not in text


def test_magnify_columns_offers_x_y_only_and_fit_offers_angles():
    def columns_help(command):
        text = help_of(command)
        i = text.index("--columns A B", text.index("options:"))
        return text[i:text.index("--plane", i)]
    assert "angle" not in columns_help("magnify") and "x y (default: from the header)" in columns_help("magnify")
    assert "an angle and a radial deviation" in columns_help("fit")


def test_fit_help_names_where_method_ids_come_from_and_the_json_units():
    text = help_of("fit")
    args = text[text.index("positional arguments:"):]
    assert "METHOD_ID the method, e.g. circle.gauss_newton ('fitbench list' shows every method" in args
    assert "--json print the result as one JSON object (mm, rad; see its 'units')" in text


def test_the_history_of_a_fit_is_its_objective_in_squared_data_units_as_the_docs_say(tmp_path):
    """circle.nelder_mead's history ends at the sum of squared radial residuals (mm² for a file in mm); a file in µm
    gives the same history (it is in mm², read after conversion), so the unit is the JSON's length squared."""
    t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    r = 50.0 + 0.002 * np.cos(3 * t)
    pts = np.c_[100.0 + r * np.cos(t), -20.0 + r * np.sin(t)]
    mm, um = tmp_path / "mm.csv", tmp_path / "um.csv"
    np.savetxt(mm, pts, delimiter=",", header="x [mm],y [mm]", comments="", fmt="%.9f")
    np.savetxt(um, pts * 1e3, delimiter=",", header="x [um],y [um]", comments="", fmt="%.6f")
    got = {}
    for path in (mm, um):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            assert main(["fit", "circle.nelder_mead", str(path), "--json"]) == 0
        got[path] = json.loads(out.getvalue())
    d = got[mm]
    assert d["units"]["length"] == "mm"
    assert d["history"][-1] == pytest.approx(float(np.sum(np.square(d["residuals"]))), rel=1e-9)
    assert got[um]["history"][-1] == pytest.approx(d["history"][-1], rel=1e-6)
    text = " ".join((DOCS / "cli.md").read_text(encoding="utf-8").split())
    assert "`history` (the objective per iteration, in its own unit: the data unit squared for the sums of " \
           "squares of gauss_newton, levenberg_marquardt and nelder_mead, e.g. mm²" in text


@pytest.mark.parametrize("argv, prog", [(["positioning", "x.csv", "--run-directions", "sideways"], "fitbench positioning"),
                                        (["fit"], "fitbench fit"), (["nosuch"], "fitbench")])
def test_an_argument_error_points_at_the_help_of_the_subcommand_that_refused(capsys, argv, prog):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("fitbench: error: ") and err.rstrip().endswith(f"(see '{prog} --help')"), err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


@pytest.mark.parametrize("argv, prog, extras", [
    (["positioning", "x.csv", "--bogus"], "fitbench positioning", "--bogus"),
    (["fit", "circle.gauss_newton", "p.csv", "--nominal-radius", "20", "--nominal-center", "1", "2"], "fitbench fit",
     "--nominal-center 1 2"),
    (["roundness", "--bogus=3", "p.csv", "extra"], "fitbench roundness", "--bogus=3 extra"),
    (["list", "--bogus"], "fitbench list", "--bogus")])
def test_an_option_the_subcommand_does_not_know_points_at_its_help(capsys, argv, prog, extras):
    """argparse reports unknown options from the top-level parser: they pointed at 'fitbench --help', which lists
    no option of any subcommand."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.strip() == f"fitbench: error: unrecognized arguments: {extras} (see '{prog} --help')", err

