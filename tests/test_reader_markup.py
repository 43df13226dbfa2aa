"""XML, HTML and JSON given as a points file are told by their first characters, as spreadsheets and archives are.

An XML ballbar export read as a table gave 'line 2: 2 fields where the header (line 1) has 3' or 'which two
columns? the header has <?xml, ...'; fitbench's own --json result given back to it gave 'a header but no data lines'.
And a positioning file's pandas error named pandas' line ('Expected 2 fields in line 4'), not the file's."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from conftest import REPO
from datasets.io import not_text


XML = ('<?xml version="1.0" encoding="utf-8"?>\n<!-- exported -->\n<BallbarTest>\n  <Header Radius="150"/>\n'
       '  <Data><Point a="0" d="0.001"/></Data>\n</BallbarTest>\n')
COMMANDS = [("fit", "circle.kasa"), ("roundness",), ("circular-test", "--nominal-radius", "150"), ("positioning",),
            ("multilaterate",)]


def command(cmd, path):
    return [cmd[0], *cmd[1:2], path, *cmd[2:]] if cmd[0] == "fit" else [cmd[0], path, *cmd[1:]]


@pytest.mark.parametrize("cmd", COMMANDS, ids=lambda c: c[0])
@pytest.mark.parametrize("text", [XML, '<BallbarTest version="2">\n<Data>1,2</Data>\n</BallbarTest>\n'],
                         ids=["prolog", "no-prolog"])
def test_xml_is_named_with_its_root_element(tmp_path, cmd, text):
    p = tmp_path / "test.b5r"
    p.write_text(text, encoding="utf-8")
    one_error_line(cli(*command(cmd, p)), "test.b5r is an XML file (root <BallbarTest>", "export the measured points")


def test_utf16_xml_and_html(tmp_path):
    p = tmp_path / "test.xml"
    p.write_text(XML, encoding="utf-16")
    assert "is an XML file (root <BallbarTest>" in not_text(p)
    h = tmp_path / "page.csv"
    h.write_text("<!DOCTYPE html>\n<html><body><table><tr><td>1</td></tr></table></body></html>\n")
    assert "is an HTML page" in not_text(h)


@pytest.fixture(scope="module")
def own_result(tmp_path_factory):
    """fitbench's own --json result of the shipped circular-test example."""
    code, out, err = cli("circular-test", REPO / "docs/examples/cw.csv", REPO / "docs/examples/ccw.csv",
                         "--nominal-radius", 150, "--json")
    assert code == 0, err
    p = tmp_path_factory.mktemp("own") / "result.json"
    p.write_text(out)
    assert "units" in json.loads(out)
    return p


@pytest.mark.parametrize("cmd", COMMANDS, ids=lambda c: c[0])
def test_fitbench_own_json_result_is_named(own_result, cmd):
    one_error_line(cli(*command(cmd, own_result)), "result.json is JSON (a fitbench result",
                   "give the file of measured points")


def test_other_json_is_named_and_an_ini_preamble_is_not_json(tmp_path):
    p = tmp_path / "points.json"
    p.write_text(json.dumps([[1.0, 2.0], [3.0, 4.0], [5.0, 1.0]]))
    one_error_line(cli("fit", "circle.kasa", p), "points.json is a JSON file, not a text table")
    ini = tmp_path / "ini.csv"
    pts = np.array([[np.cos(t), np.sin(t)] for t in np.linspace(0, 6, 20)])
    ini.write_text("[General]\nMachine=VMC\n\nx,y\n" + "\n".join(f"{x:.6f},{y:.6f}" for x, y in pts) + "\n")
    assert not_text(ini) is None
    one_error_line(cli("fit", "circle.kasa", ini), "--skip-rows 3")


def test_positioning_parser_error_names_the_files_line(tmp_path):
    p = tmp_path / "laser.rtl"
    p.write_text("Machine: VMC-1\nAxis: X\nDate: 2026-11-20\n\nTarget,Run 1,Run 2\n0,0.001,0.002\n100,0.003,0.004\n"
                 "200,0.002,0.001\n")
    called = cli("positioning", p)
    one_error_line(called, "laser.rtl line 5: 3 fields where the header (line 1) has 2", "--skip-rows 4")
    assert "Expected" not in called.stderr and "line 4" not in called.stderr


def _table_below(path, first_lines: str, n: int = 40):
    """A R50 circle's x, y table in mm below ``first_lines`` (an instrument's preamble)."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rows = "".join(f"{50 * np.cos(a):.9f},{50 * np.sin(a):.9f}\n" for a in t)
    path.write_text(f"{first_lines}\nx [mm],y [mm]\n{rows}", encoding="utf-8")
    return path


@pytest.mark.parametrize("first", ["<Operator: J. Smith>", "<Probe 3>", "{Probe 3}", "{Operator: J. Smith}"])
def test_a_preamble_starting_with_a_bracket_is_not_markup(tmp_path, first):
    """A text table whose first line starts with '<' + a letter or '{' was refused as XML or JSON whatever the
    options ('is an XML file (root <Operator:>...'); it is neither, and --skip-rows 1 reads it."""
    p = _table_below(tmp_path / "trace.csv", first)
    assert not_text(p) is None and not_text(p, skip_rows=1) is None
    code, out, err = cli("fit", "circle.kasa", p, "--skip-rows", 1, "--json")
    assert code == 0, err
    assert json.loads(out)["radius"] == pytest.approx(50.0, abs=1e-6)


@pytest.mark.parametrize("cmd", [("fit", "circle.kasa"), ("roundness",)], ids=lambda c: c[0])
def test_a_line_skip_rows_skips_is_never_refused_as_markup(tmp_path, cmd):
    """A preamble that is markup ('<Operator>J. Smith</Operator>', a JSON object) is refused without --skip-rows,
    saying which lines to skip, and read with it."""
    for first, what in (("<Operator>J. Smith</Operator>\n<Date>2026-11-26</Date>", "is an XML file (root <Operator>"),
                        ('{"operator": "J. Smith"}\n{"probe": 3}', None)):
        p = _table_below(tmp_path / "trace.csv", first, n=720)
        if what:
            one_error_line(cli(*command(cmd, p)), what, "if lines 1-2 are a preamble above a table, give --skip-rows 2")
        code, out, err = cli(*command(cmd, p), "--skip-rows", 2)
        assert code == 0 and "error" not in err, err


def test_json_only_when_it_parses_and_xml_only_when_it_looks_like_markup(tmp_path):
    p = tmp_path / "r.json"
    p.write_text('{"radius": 50.0,\n "points": [[1, 2], [3, 4]]}\n')
    assert "is a JSON file" in not_text(p)
    p.write_text('{radius: 50.0}\n1,2\n')
    assert not_text(p) is None
    for text in ('<Part no="7"/>\n<Data>1,2</Data>\n', '<!DOCTYPE part [<!ENTITY a "b">]>\n<part>\n<x>1</x>\n</part>\n',
                 '<Part>\n  <x>1</x>\n</Part>\n', '<Part>text</Part>\n', '<?xml version="1.0"?>\n1,2\n'):
        p.write_text(text)
        assert "is an XML file" in not_text(p), text
    for text in ("<Operator: J. Smith>\n1,2\n", "<Part>\nx,y\n1,2\n", '<Part no=7>\n<a>\n', "<Probe 3> <x>\n"):
        p.write_text(text)
        assert not_text(p) is None, text
    p.write_text("Machine: VMC\n<Operator>J. Smith</Operator>\n1,2\n")
    assert not_text(p) is None and "XML" in not_text(p, skip_rows=1)


def test_positioning_reads_below_a_markup_preamble_it_skips(tmp_path):
    """The table reader of positioning and multilateration (its own path, not the points reader's)."""
    p = tmp_path / "axis.csv"
    p.write_text('<Machine id="VMC-1">laser test</Machine>\n'
                 + (REPO / "docs/examples/positioning.csv").read_text(encoding="utf-8"), encoding="utf-8")
    one_error_line(cli("positioning", p), "is an XML file (root <Machine>", "give --skip-rows 1")
    code, out, err = cli("positioning", p, "--skip-rows", 1, "--json")
    code0, out0, _ = cli("positioning", REPO / "docs/examples/positioning.csv", "--json")
    assert code == code0 == 0, err
    assert json.loads(out)["A"] == json.loads(out0)["A"]


@pytest.mark.parametrize("cmd", [("fit", "circle.kasa"), ("roundness",)], ids=lambda c: c[0])
@pytest.mark.parametrize("first", ["{Probe 3}", "Probe 3", "[General]", "<Operator: J. Smith>"])
def test_a_preamble_line_above_the_header_is_hinted_at(tmp_path, cmd, first):
    """One preamble line above a profile's header, no --skip-rows: the refusal says to skip it, whatever the
    refusal ('{Probe 3}' got 'cannot tell the unit of column '{Probe'', with no word of the preamble)."""
    p = tmp_path / "lt2.csv"
    p.write_text(f"{first}\n" + (REPO / "docs/examples/profile.csv").read_text(encoding="utf-8"), encoding="utf-8")
    one_error_line(cli(*command(cmd, p)),
                   "if line 1 is an instrument's preamble, give --skip-rows 1 (the first row of numbers is line 3)")
    code, out, err = cli(*command(cmd, p), "--skip-rows", 1)
    assert code == 0 and "error" not in err, err


def test_a_preamble_line_above_a_circular_test_s_header_is_hinted_at(tmp_path):
    files = []
    for name in ("cw.csv", "ccw.csv"):
        files.append(tmp_path / name)
        files[-1].write_text("{Probe 3}\n" + (REPO / "docs/examples" / name).read_text(encoding="utf-8"), encoding="utf-8")
    one_error_line(cli("circular-test", *files, "--nominal-radius", 150), "cw.csv: ",
                   "if line 1 is an instrument's preamble, give --skip-rows 1 (the first row of numbers is line 3)")
    code, out, err = cli("circular-test", *files, "--nominal-radius", 150, "--skip-rows", 1)
    assert code == 0 and "error" not in err, err
