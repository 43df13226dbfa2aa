"""A positioning test with fewer targets or runs than ISO 230-2 asks for (5.3.2-5.3.4: at least five targets per
metre and five overall, five runs each direction, for axes up to 2000 mm) is still evaluated by the standard's
formulas, but the output says it is not an ISO 230-2 test and what it lacks (text and JSON). Before: 'ISO
230-2:2014 (k = 2): 2 targets x 2 runs' with A, E, R, B and no note."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli
from datasets.positioning import axis_test, to_frame
from methods.positioning.iso230_2 import conformity


def axis_file(path, **kw):
    data, _ = axis_test(rng=np.random.default_rng(1), **kw)
    to_frame(data, actual=False).rename(columns={"deviation": "deviation [mm]"}).to_csv(path, index=False)
    return path


@pytest.mark.parametrize("kw, lacks", [
    ({"targets": 2, "runs": 2, "travel": (0.0, 500.0)}, ["2 targets on a 500 mm travel (5 needed", "2 runs per direction (5 needed)"]),
    ({"targets": 11, "runs": 3}, ["3 runs per direction (5 needed)"]),
    ({"targets": 11, "runs": 5}, []),
])
def test_text_and_json_say_what_the_test_lacks(tmp_path, kw, lacks):
    p = axis_file(tmp_path / "a.csv", **kw)
    out = cli("positioning", p, "--degree", 1)
    assert out.returncode == 0, out.stderr
    note = [l for l in out.stdout.splitlines() if l.startswith("note: not an ISO 230-2 test")]
    got = json.loads(cli("positioning", p, "--degree", 1, "--json").stdout)
    assert got["iso230_2_conformity"]["meets_minimum"] == (not lacks)
    assert len(got["iso230_2_conformity"]["lacks"]) == len(lacks)
    if lacks:
        assert len(note) == 1 and all(w in note[0] for w in lacks) and "not for acceptance" in note[0]
        assert out.stdout.index(note[0]) < out.stdout.index("ISO 230-2:2014 (k = 2)")   # before the figures
        assert any(n.startswith("not an ISO 230-2 test") for n in got["notes"])
    else:
        assert note == [] and not any(n.startswith("not an ISO 230-2 test") for n in got["notes"])


def test_the_other_standards_carry_no_iso_note(tmp_path):
    p = axis_file(tmp_path / "a.csv", targets=4, runs=2)
    got = json.loads(cli("positioning", p, "--degree", 1, "--standard", "vdi3441", "--json").stdout)
    assert "iso230_2_conformity" not in got
    old = cli("positioning", p, "--degree", 1, "--standard", "iso230-2:1988")
    assert "note: not an ISO 230-2 test: 4 targets" in old.stdout


@pytest.mark.parametrize("travel, targets, runs, lacking", [
    (1500.0, 7, 5, "7 targets on a 1500 mm travel (8 needed"),       # 5 per metre
    (1500.0, 8, 5, None),
    (400.0, 4, 5, "4 targets on a 400 mm travel (5 needed"),          # 5 overall
    (3000.0, 11, 2, "11 targets on a 3000 mm travel (13 needed"),     # long axis: 250 mm apart on average
    (3000.0, 13, 2, None),
])
def test_target_counts_per_metre_overall_and_long_axes(travel, targets, runs, lacking):
    data, _ = axis_test(rng=np.random.default_rng(0), travel=(0.0, travel), targets=targets, runs=runs)
    got = conformity(data)
    assert (got == []) if lacking is None else (len(got) == 1 and got[0].startswith(lacking))
