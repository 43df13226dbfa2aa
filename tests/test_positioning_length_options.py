"""positioning's --interval and --reference take a length with its unit as the other length options do (100mm,
0.1m, 3.937in, 100000um); a bare number is mm, as documented. Before, both took a bare float only: '--interval
0.1m' was refused by argparse ('invalid float value')."""
import pytest

from cli_calls import cli, one_error_line
from conftest import REPO

EXAMPLE = REPO / "docs" / "examples" / "positioning.csv"


def table(tmp_path, name, *options):
    out = tmp_path / f"{name}.csv"
    got = cli("positioning", EXAMPLE, "--deviation-unit", "um", "--compensation", "csv", out,
              "--compensation-from", "mean", *options)
    assert got.returncode == 0, got.stderr
    return out.read_text(encoding="utf-8"), got.stdout


@pytest.mark.parametrize("option, bare, with_unit", [("--interval", "100", ["100mm", "0.1m", "100000um"]),
                                                     ("--reference", "500", ["500mm", "0.5m", "500000um"])])
def test_a_length_with_its_unit_gives_the_table_of_the_bare_mm(tmp_path, option, bare, with_unit):
    plain, _ = table(tmp_path, "bare", option, bare)
    for k, text in enumerate(with_unit):
        assert table(tmp_path, f"u{k}", option, text)[0] == plain, text


def test_an_interval_in_inches_is_converted_to_mm(tmp_path):
    written, said = table(tmp_path, "in", "--interval", "1.5in")
    assert "every 38.1 mm" in said
    assert "points every 38.100000 mm" in written


@pytest.mark.parametrize("option, text, words", [
    ("--interval", "10cm", "argument --interval: '10cm': unknown unit 'cm'"),
    ("--reference", "abc", "argument --reference: 'abc' is not a number: give a number in mm or with its unit"),
    ("--interval", "10,5", "a decimal comma; write the number with a point, e.g. --interval 10.5"),
])
def test_a_length_that_cannot_be_read_is_refused_in_one_line(tmp_path, option, text, words):
    one_error_line(cli("positioning", EXAMPLE, "--deviation-unit", "um", "--compensation", "csv", tmp_path / "x.csv",
                       option, text), words)
