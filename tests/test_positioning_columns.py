"""A positioning long table with two columns named for one role (``Error (µm)`` beside ``Deviation (µm)``: a
straightness channel beside the linear one; twice ``Deviation (µm)`` under a two-row group header; two target or
two actual columns). Before: the first such column was read and the other dropped without a word (A from the
straightness channel, exit 0). Now refused naming both and ``--column ROLE=COLUMN``, which reads the one named and
says so in a note. The figures are checked against ISO 230-2's definitions computed here (k = 2)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from positioning_tables import LONG_TARGETS as TARGETS, iso_a_um


def channels(seed=8, runs=5):
    """(linear deviations, straightness) in µm to 4 decimals, each {direction: (targets, runs)}."""
    rng = np.random.default_rng(seed)
    err = 8 * TARGETS / 1000 - 12 * (TARGETS / 1000) ** 2
    lin = {d: (err + b)[:, None] + rng.normal(0, 0.6, (len(TARGETS), runs)) for d, b in (("+", -1.8), ("-", 1.8))}
    straight = {d: rng.normal(0, 3.0, (len(TARGETS), runs)) for d in "+-"}
    return ({d: np.round(v, 4) for d, v in lin.items()},            # as written to the files
            {d: np.round(v, 4) for d, v in straight.items()})


def long_table(path, header, columns):
    """A long table: ``header`` names, ``columns`` a function (direction, target index, run) -> the row's cells."""
    rows = [",".join(columns(d, i, r)) for d in "+-" for r in range(5) for i in range(len(TARGETS))]
    path.write_text(",".join(header) + "\n" + "\n".join(rows) + "\n")
    return path


@pytest.fixture
def two_deviations(tmp_path):
    lin, straight = channels()
    cells = lambda d, i, r: [f"{TARGETS[i]:.1f}", str(r + 1), d, f"{straight[d][i, r]:.4f}", f"{lin[d][i, r]:.4f}"]
    named = long_table(tmp_path / "err_dev.csv", ["Target (mm)", "Run", "Direction", "Error (µm)", "Deviation (µm)"],
                       cells)
    same = long_table(tmp_path / "dev_dev.csv", ["Target (mm)", "Run", "Direction", "Deviation (µm)",
                                                 "Deviation (µm)"], cells)
    return named, same, lin, straight


def test_two_deviation_columns_are_refused_naming_both(two_deviations):
    named, same, lin, straight = two_deviations
    assert abs(iso_a_um(lin) - iso_a_um(straight)) > 2.0          # reading the wrong one would show
    one_error_line(cli("positioning", named), "'Error (µm)'", "'Deviation (µm)'", '--column "deviation=Error (µm)"',
                   '--column "deviation=Deviation (µm)"')
    one_error_line(cli("positioning", same), "columns 3 and 4", "'Deviation (µm)'", "--column deviation=3",
                   "--column deviation=4")


def test_the_column_chosen_is_read_and_said(two_deviations):
    named, same, lin, straight = two_deviations
    for path, choice, want, other in ((named, "deviation=Deviation (µm)", lin, "column 3 'Error (µm)'"),
                                      (named, "deviation=error", straight, "column 4 'Deviation (µm)'"),
                                      (same, "deviation=4", lin, "column 3 'Deviation (µm)'"),
                                      (same, "deviation=3", straight, "column 4 'Deviation (µm)'")):
        out = cli("positioning", path, "--column", choice, "--json")
        assert out.returncode == 0, out.stderr
        got = json.loads(out.stdout)
        assert got["A"] * 1e3 == pytest.approx(iso_a_um(want), abs=1e-9), (path.name, choice)
        note = next(n for n in got["notes"] if n.startswith("the positioning deviations read from column"))
        assert f"as --column {choice} says" in note and f"not read: {other}" in note
    text = cli("positioning", same, "--column", "deviation=4")
    assert "note: the positioning deviations read from column 4 'Deviation (µm)'" in text.stdout


@pytest.mark.parametrize("header", [["Target (mm)", "Position (mm)", "Run", "Direction", "Deviation (µm)"],
                                    ["Target (mm)", "Run", "Direction", "Actual (mm)", "Measured position (mm)"]])
def test_two_target_or_two_actual_columns_are_refused(tmp_path, header):
    lin, _ = channels()
    if "Position (mm)" in header:
        cells = lambda d, i, r: [f"{TARGETS[i]:.1f}", f"{TARGETS[i]:.1f}", str(r + 1), d, f"{lin[d][i, r]:.4f}"]
    else:
        cells = lambda d, i, r: [f"{TARGETS[i]:.1f}", str(r + 1), d, f"{TARGETS[i] + lin[d][i, r] * 1e-3:.7f}",
                                 f"{TARGETS[i] + 0.01:.7f}"]
    path = long_table(tmp_path / "t.csv", header, cells)
    role = "target" if "Position (mm)" in header else "actual"
    one_error_line(cli("positioning", path), repr(header[1] if role == "target" else header[3]),
                   repr(header[0] if role == "target" else header[4]), f"--column \"{role}=")
    chosen = cli("positioning", path, "--column", f"{role}={header[0] if role == 'target' else header[3]}", "--json")
    assert chosen.returncode == 0, chosen.stderr
    assert json.loads(chosen.stdout)["A"] * 1e3 == pytest.approx(iso_a_um(lin), abs=2e-3)


def test_column_option_misuse_is_one_line(two_deviations, tmp_path):
    named, *_ = two_deviations
    one_error_line(cli("positioning", named, "--column", "speed=3"), "unknown role 'speed'", "deviation")
    one_error_line(cli("positioning", named, "--column", "deviation=9"), "no column 9", "5 columns")
    one_error_line(cli("positioning", named, "--column", "deviation"), "ROLE=COLUMN")
    one_error_line(cli("positioning", named, "--column", "deviation=Straightness"), "no column 'Straightness'")
    wide = tmp_path / "wide.csv"
    wide.write_text("Target (mm),Run 1 + (µm),Run 1 - (µm),Run 2 + (µm),Run 2 - (µm)\n0,1,2,1.5,2.5\n100,2,3,2.2,3.1\n")
    one_error_line(cli("positioning", wide, "--column", "deviation=1"), "this file has run columns", "drop the option")


def test_actual_beside_deviation_reads_the_deviations_and_says_so(tmp_path):
    lin, _ = channels()
    cells = lambda d, i, r: [f"{TARGETS[i]:.1f}", str(r + 1), d, f"{TARGETS[i] + 0.5:.4f}", f"{lin[d][i, r]:.4f}"]
    path = long_table(tmp_path / "ad.csv", ["Target (mm)", "Run", "Direction", "Actual (mm)", "Deviation (µm)"], cells)
    out = cli("positioning", path, "--json")
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert got["A"] * 1e3 == pytest.approx(iso_a_um(lin), abs=1e-9)
    assert any("deviations read from column 'Deviation (µm)'" in n and "'Actual (mm)'" in n for n in got["notes"])
    # the note does not hide the refusal of an option for wide exports
    one_error_line(cli("positioning", path, "--run-directions", "up"), "a long table with a direction column")


def test_other_channels_are_refused_or_named(tmp_path):
    """A second channel whose name is not exactly a role's ('Deviation Z (µm)') was read past without a word
    (review16 V1): a length column with a position or deviation word is refused unless --column chose; other
    numeric columns (straightness, pitch) are named in a note; --column naming another role's column is refused."""
    lin, straight = channels()
    cells = lambda d, i, r: [f"{TARGETS[i]:.1f}", str(r + 1), d, f"{straight[d][i, r]:.4f}", f"{lin[d][i, r]:.4f}"]
    z = long_table(tmp_path / "z.csv", ["Target (mm)", "Run", "Direction", "Deviation Z (µm)", "Deviation (µm)"], cells)
    one_error_line(cli("positioning", z), "besides 'Deviation (µm)'", "'Deviation Z (µm)'", '--column "deviation=NAME"')
    out = cli("positioning", z, "--column", "deviation=4", "--json")
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert got["A"] * 1e3 == pytest.approx(iso_a_um(lin), abs=1e-9)
    assert any("not read: column 3 'Deviation Z (µm)'" in n for n in got["notes"])
    cells3 = lambda d, i, r: cells(d, i, r) + ["12.5"]
    three = long_table(tmp_path / "three.csv", ["Target (mm)", "Run", "Direction", "Straightness Y (µm)",
                                                "Deviation (µm)", "Pitch (µrad)"], cells3)
    out = cli("positioning", three, "--json")
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert got["A"] * 1e3 == pytest.approx(iso_a_um(lin), abs=1e-9)
    assert "not read: column 3 'Straightness Y (µm)', column 5 'Pitch (µrad)'" in got["notes"]
    one_error_line(cli("positioning", z, "--column", "deviation=1"), "--column deviation=1 names 'Run', the run column")
