"""``--tolerance`` takes a unit as ``--mpe`` does (``A=10um``, ``A=0.01mm``; a bare number stays µm, as before), and a
bare number far below the figure it judges is warned about, naming mm: a drawing's ``A=0.01`` (0.010 mm) read as
0.01 µm gave "A 8.498 µm tolerance 0.01 µm FAIL" with no word, while ``A=10um`` was refused as "must be a number"."""
import json

import pytest

from cli_calls import cli, one_error_line
from positioning_tables import axis_csv
from profile_lines import circular_runs_file, profile_file


@pytest.fixture(scope="module")
def axis_file(tmp_path_factory):
    return axis_csv(tmp_path_factory.mktemp("pos"))[0]


def verdict_of(*args):
    out = cli(*args, "--json")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    return d["verdict"], d["warnings"], out.stderr


@pytest.mark.parametrize("text", ["10", "10um", "10 µm", "10µm", "0.01mm", "10000nm", "1e-2 mm"])
def test_a_tolerance_with_its_unit_is_the_same_tolerance(axis_file, text):
    verdict, said, err = verdict_of("positioning", axis_file, "--tolerance", f"A={text}")
    (check,) = verdict["checks"]
    assert check["tolerance_mm"] == pytest.approx(0.01, rel=1e-12) and check["figure"] == "A"
    assert check["result"] == ("PASS" if check["value_mm"] <= 0.01 else "FAIL")
    assert said == [] and "warning" not in err


def test_a_bare_tolerance_far_below_its_figure_is_warned_about_naming_mm(axis_file):
    verdict, said, err = verdict_of("positioning", axis_file, "--tolerance", "A=0.01")
    (check,) = verdict["checks"]
    assert check["tolerance_mm"] == pytest.approx(1e-5) and check["result"] == "FAIL"   # a bare number is µm still
    ratio = check["value_mm"] / 1e-5
    line = (f"--tolerance A=0.01 is read as 0.01 µm (a bare number is µm), and A is {check['value_mm'] * 1e3:.4g} µm, "
            f"{ratio:.3g} times it: is it in mm? give --tolerance A=0.01mm (10 µm), or --tolerance A=0.01um to keep µm")
    assert f"warning: {line}" in err and said == [line]
    # said in µm, or a bare tolerance the figure misses by less than 10 times: meant, no warning
    bare = f"{check['value_mm'] * 1e3 / 9.9:.6f}"
    for text in ("0.01um", bare):
        out = cli("positioning", axis_file, "--tolerance", f"A={text}")
        assert out.returncode == 0 and "warning" not in out.stderr, out.stderr


def test_a_bare_tolerance_ten_times_below_its_figure_is_warned_about(axis_file):
    """A drawing's 0.1 mm given bare (read as 0.1 µm) beside ``--mpe 2um``: the figure is 85 times it, a silent FAIL
    while the warning needed 100 times; from 10 times on it is warned about."""
    verdict, _, _ = verdict_of("positioning", axis_file, "--tolerance", "A=0.01um")
    a_um = verdict["checks"][0]["value_mm"] * 1e3
    for ratio in (10.001, 85.0):   # 10 times (to the 6 digits written) and the drawing's 0.1 mm
        text = f"{a_um / ratio:.6g}"
        verdict, said, err = verdict_of("positioning", axis_file, "--mpe", "2um", "--tolerance", f"A={text}")
        assert verdict["overall"] == "FAIL" and verdict["checks"][0]["tolerance_bare"] is True
        assert verdict["checks"][0]["tolerance_given"] == text
        assert len(said) == 1 and said[0].startswith(f"--tolerance A={text} is read as {float(text):g} µm")
        assert f"give --tolerance A={text}mm" in said[0] and f"warning: {said[0]}" in err


def test_roundness_and_circular_test_warn_about_a_bare_tolerance_in_mm(tmp_path):
    shaft = profile_file(tmp_path / "shaft.csv")
    out = cli("roundness", shaft, "--tolerance", "RONt=0.005")
    assert out.returncode == 0 and "warning: --tolerance RONt=0.005 is read as 0.005 µm" in out.stderr
    assert "give --tolerance RONt=0.005mm (5 µm)" in out.stderr
    out = cli("roundness", shaft, "--tolerance", "RONt=0.005mm")
    assert out.returncode == 0 and "warning" not in out.stderr and "tolerance 5 µm" in out.stdout
    runs = circular_runs_file(tmp_path / "runs.csv")
    out = cli("circular-test", runs, "--nominal-radius", 100, "--tolerance", "G=0.001")
    assert out.returncode == 0 and "warning: --tolerance G=0.001 is read as 0.001 µm" in out.stderr
    out = cli("circular-test", runs, "--nominal-radius", 100, "--tolerance", "G=0.05mm")
    assert out.returncode == 0 and "warning" not in out.stderr and "tolerance 50 µm" in out.stdout


@pytest.mark.parametrize("text, words", [
    ("A=2cm", ("--tolerance 'A=2cm': unknown unit 'cm'", "A=10um or A=0.01mm")),
    ("A=ten", ("--tolerance 'A=ten': give the tolerance as a length with its unit", "(a bare number is µm)")),
    ("A=-1um", ("--tolerance 'A=-1um': a tolerance must be positive",)),
    ("Q=1um", ("--tolerance 'Q=1um': give NAME=VALUE with NAME one of A, E", "VALUE in µm or with its unit")),
    ("A=10,5", ("--tolerance 'A=10,5': a decimal comma; write the number with a point, e.g. A=10.5",)),
    ("A=10,5 um", ("--tolerance 'A=10,5 um': a decimal comma; write the number with a point, e.g. A=10.5 um",)),
    ("A=1,000", ("--tolerance 'A=1,000': a comma in the number, a decimal comma or a thousands separator",
                 "write A=1.000 if it is decimal, A=1000 if it separates thousands")),
])
def test_a_bad_tolerance_is_one_line(axis_file, text, words):
    one_error_line(cli("positioning", axis_file, "--tolerance", text), *words)


def test_the_verdict_line_says_how_a_bare_tolerance_was_read(tmp_path):
    """The reviewer's command (docs' example file, ``--mpe 2um --tolerance A=0.1``): the warning comes before the
    figures on the terminal and is in the report's warnings box; the verdict line states the µm reading of the bare
    number, and a tolerance with its unit is printed as before."""
    from pathlib import Path
    from test_cli_warnings import report_text, terminal
    example = Path(__file__).resolve().parents[1] / "docs" / "examples" / "positioning.csv"
    code, shown = terminal("positioning", example, "--mpe", "2um", "--tolerance", "A=0.1")
    assert code == 0
    warning = shown.index("warning: --tolerance A=0.1 is read as 0.1 µm (a bare number is µm), and A is ")
    line = next(ln for ln in shown.splitlines() if ln.strip().startswith("A ") and "tolerance" in ln)
    assert warning < shown.index("verdict      FAIL") and "tolerance 0.1 µm (a bare number: µm)  FAIL" in line
    page = " ".join(report_text(tmp_path, "positioning", example, "--mpe", "2um", "--tolerance", "A=0.1").split())
    assert "warning: --tolerance A=0.1 is read as 0.1 µm (a bare number is µm), and A is " in page
    assert "give --tolerance A=0.1mm (100 µm)" in page and "tolerance 0.1 µm (a bare number: µm) FAIL" in page
    code, shown = terminal("positioning", example, "--mpe", "2um", "--tolerance", "A=0.1mm")
    assert code == 0 and "warning" not in shown and "tolerance 100 µm  PASS" in shown
    assert "a bare number" not in shown


def test_roundness_states_the_bare_reading_on_every_tolerance_line(tmp_path):
    shaft = profile_file(tmp_path / "shaft.csv")
    out = cli("roundness", shaft, "--tolerance", "RONt=5")
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("  RONt ")]
    assert out.returncode == 0 and len(lines) == 4
    assert all("tolerance 5 µm (a bare number: µm)" in ln for ln in lines), lines
    out = cli("roundness", shaft, "--tolerance", "RONt=5um")
    assert out.returncode == 0 and "a bare number" not in out.stdout and "tolerance 5 µm  PASS" in out.stdout


@pytest.mark.parametrize("option, text, fixed", [("--mpe", "2,5um", "2.5um"), ("--instrument-u", "0,5", "0.5")])
def test_a_decimal_comma_in_mpe_is_named(axis_file, option, text, fixed):
    """'--mpe 2,5um' was refused as "unknown unit ',5um'"."""
    one_error_line(cli("positioning", axis_file, option, text),
                   f"{option} '{text}': a decimal comma; write the number with a point, e.g. {option} {fixed}")


def test_the_help_gives_both_forms(capsys):
    from fitbench.cli import main
    for command in ("positioning", "roundness", "circular-test"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "--tolerance NAME=VALUE" in text
        assert "a tolerance in µm (a bare number) or with its unit (NAME=10um, NAME=0.01mm)" in text, command
        assert "a bare number that the figure it judges exceeds 10 times or more is warned about" in text, command
