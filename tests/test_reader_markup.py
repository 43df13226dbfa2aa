"""XML, HTML and JSON given as a points file are told by their first characters, as spreadsheets and archives are.

An XML ballbar export read as a table gave 'line 2: 2 fields where the header (line 1) has 3' or 'which two
columns? the header has <?xml, ...'; fitbench's own --json result given back to it gave 'a header but no data lines'.
And a positioning file's pandas error named pandas' line ('Expected 2 fields in line 4'), not the file's."""
from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from datasets.io import not_text
from fitbench.cli.commands import main
from conftest import REPO


def cli(*args):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in args])
    return code, out.getvalue(), err.getvalue()


def one_line(code, err, *match):
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for m in match:
        assert m in err, err


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
    one_line(*cli(*command(cmd, p))[::2], "test.b5r is an XML file (root <BallbarTest>", "export the measured points")


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
    one_line(*cli(*command(cmd, own_result))[::2], "result.json is JSON (a fitbench result",
             "give the file of measured points")


def test_other_json_is_named_and_an_ini_preamble_is_not_json(tmp_path):
    p = tmp_path / "points.json"
    p.write_text(json.dumps([[1.0, 2.0], [3.0, 4.0], [5.0, 1.0]]))
    one_line(*cli("fit", "circle.kasa", p)[::2], "points.json is a JSON file, not a text table")
    ini = tmp_path / "ini.csv"
    pts = np.array([[np.cos(t), np.sin(t)] for t in np.linspace(0, 6, 20)])
    ini.write_text("[General]\nMachine=VMC\n\nx,y\n" + "\n".join(f"{x:.6f},{y:.6f}" for x, y in pts) + "\n")
    assert not_text(ini) is None
    one_line(*cli("fit", "circle.kasa", ini)[::2], "--skip-rows 3")


def test_positioning_parser_error_names_the_files_line(tmp_path):
    p = tmp_path / "laser.rtl"
    p.write_text("Machine: VMC-1\nAxis: X\nDate: 2026-11-20\n\nTarget,Run 1,Run 2\n0,0.001,0.002\n100,0.003,0.004\n"
                 "200,0.002,0.001\n")
    code, _, err = cli("positioning", p)
    one_line(code, err, "laser.rtl line 5: 3 fields where the header (line 1) has 2", "--skip-rows 4")
    assert "Expected" not in err and "line 4" not in err
