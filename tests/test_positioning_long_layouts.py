"""Long positioning tables without a run column, or without a direction column. Before: a capture-order export
(target, direction, error per point, the runs one after the other, no run number) was refused as "column
'deviation' is neither the target, a direction nor a run (wide layout: ...)", naming a column the file does not
have; a table without directions was refused ("missing column 'direction'") although positioning.md says it is a
unidirectional test. Now the k-th row of each target (and direction) is run k, said in a note; without directions
the runs are one direction, not given, or as --run-directions says, and alternating runs are refused as in the
wide layout. The figures are checked against ISO 230-2's definitions computed here (k = 2)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from positioning_tables import LONG_TARGETS as TARGETS, capture_order, iso_a_um


@pytest.fixture(scope="module")
def dev():
    rng = np.random.default_rng(11)
    return {d: np.round((6 * TARGETS / 500 + b)[:, None] + rng.normal(0, 0.6, (len(TARGETS), 5)), 3)
            for d, b in (("+", -1.8), ("-", 1.8))}


def test_a_table_without_a_run_column_numbers_the_runs_in_file_order(tmp_path, dev):
    path = capture_order(tmp_path / "norun.txt", dev, "Target position [mm]\tDirection\tError [µm]",
                         lambda t, d, r, e: f"{t:.4f}\t{d}\t{e:.3f}")
    out = cli("positioning", path, "--json")
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert got["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)
    assert any("no run column: the k-th row of each target and direction is read as run k" in n for n in got["notes"])


def test_a_table_without_run_or_direction_column_is_refused_as_alternating_or_read_as_told(tmp_path, dev):
    path = capture_order(tmp_path / "nodirrun.txt", dev, "Target position [mm]\tError [µm]",
                         lambda t, d, r, e: f"{t:.4f}\t{e:.3f}")
    out = cli("positioning", path)
    one_error_line(out, "no direction column", "odd runs differ from the even runs", "--run-directions up,down")
    assert "neither the target" not in out.stderr
    told = cli("positioning", path, "--run-directions", "up,down", "--json")
    assert told.returncode == 0, told.stderr
    assert json.loads(told.stdout)["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)


def test_a_table_without_a_direction_column_is_one_direction_not_given(tmp_path, dev):
    path = tmp_path / "uni.csv"
    path.write_text("Target (mm),Run,Deviation (µm)\n" + "".join(
        f"{t:.1f},{r + 1},{dev['+'][i, r]:.3f}\n" for r in range(5) for i, t in enumerate(TARGETS)))
    out = cli("positioning", path, "--json")
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert got["A"] * 1e3 == pytest.approx(iso_a_um(dev, "+"), abs=1e-9)
    assert got["directions"] == "unidirectional (direction not given)"
    up = json.loads(cli("positioning", path, "--run-directions", "up", "--json").stdout)
    assert up["directions"] != got["directions"] and up["A"] == got["A"]


def test_alternating_runs_without_a_direction_column(tmp_path, dev):
    path = tmp_path / "alt.csv"
    path.write_text("Target (mm),Run,Deviation (µm)\n" + "".join(
        f"{t:.1f},{2 * r + k + 1},{dev[d][i, r]:.3f}\n" for r in range(5) for k, d in enumerate("+-")
        for i, t in enumerate(TARGETS)))
    one_error_line(cli("positioning", path), "no direction column", "--run-directions up,down")
    told = cli("positioning", path, "--run-directions", "up,down", "--json")
    assert told.returncode == 0, told.stderr
    assert json.loads(told.stdout)["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)
    with_dirs = tmp_path / "dirs.csv"
    with_dirs.write_text("Target (mm),Direction,Run,Deviation (µm)\n0,+,1,1\n0,+,2,1.2\n100,+,1,2\n100,+,2,2.1\n")
    one_error_line(cli("positioning", with_dirs, "--run-directions", "up"), "a long table with a direction column",
                   "drop the option")


def test_both_directions_without_a_direction_column_are_refused_naming_it(tmp_path, dev):
    path = tmp_path / "way.csv"
    path.write_text("Target (mm),Way,Run,Deviation (µm)\n" + "".join(
        f"{t:.1f},{d},{r + 1},{dev[d][i, r]:.3f}\n" for d in "+-" for r in range(5) for i, t in enumerate(TARGETS)))
    one_error_line(cli("positioning", path), "missing column 'direction'", "target 0 has run 1 twice (lines 2 and 32)",
                   "name the direction column 'Direction'")
