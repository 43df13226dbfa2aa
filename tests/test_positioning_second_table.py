"""A second table (the header repeated, with or without a blank line before it: two axes or two tests in one file)
and a row of statistics below the table (``Mean;0.1;...``, ``Max``, ``Std dev``) are refused in one line naming
them as such and saying what to do (one table per file; delete the line or prefix it with #). Before: both were
only 'line 14: target 'Target (mm)' is not a finite number' / 'line 13: target 'Mean' is not a finite number'.
The same lines prefixed with # are skipped, and the file gives the figures of the table alone (A by ISO 230-2's
definition, computed here)."""
from __future__ import annotations

import json

import pytest

from cli_calls import cli, one_error_line
from positioning_tables import TARGETS, iso_a_um, runs

HEAD = ";".join(["Target (mm)"] + [f"Run {r} {d} (µm)" for r in (1, 2, 3) for d in "+-"])


def table(dev, sep=";"):
    return [HEAD.replace(";", sep)] + [sep.join([f"{t:.3f}"] + [f"{dev[d][i, r]:.3f}" for r in range(3) for d in "+-"])
                                       for i, t in enumerate(TARGETS)]


@pytest.mark.parametrize("gap", [[""], []])
def test_a_second_table_is_named_as_one(tmp_path, gap):
    dev, other = runs(seed=3), runs(seed=4)
    path = tmp_path / "two.csv"
    path.write_text("\n".join(table(dev) + gap + table(other)) + "\n")
    line = 1 + len(TARGETS) + len(gap) + 1
    one_error_line(cli("positioning", path), f"line {line}: 'Target (mm);Run 1 + (µm);", "repeats the header",
                   "a second table" + (" after a blank line" if gap else " ("),
                   f"lines {line}-{line + len(TARGETS)}", "one table per file", "put each table in a file of its own",
                   f"delete the lines from {line} on", "prefix them with #", absent=["not a finite number"])


@pytest.mark.parametrize("row", ["Mean;0.1;0.1;0.1;0.1;0.1;0.1", "Max;3.1;3.1;3.1;3.1;3.1;3.1",
                                 "Std dev;0.5;0.5;0.5;0.5;0.5;0.5", "Mittelwert;0.1;0.1;0.1;0.1;0.1;0.1",
                                 "TOTAL:;1;1;1;1;1;1"])
def test_a_row_of_statistics_is_named_as_one(tmp_path, row):
    dev = runs(seed=3)
    path = tmp_path / "totals.csv"
    path.write_text("\n".join(table(dev) + [row]) + "\n")
    word = row.split(";")[0]
    one_error_line(cli("positioning", path), f"line {len(TARGETS) + 2}: {row!r} is a row of statistics ({word!r})",
                   "delete the line", "prefix it with #", absent=["not a finite number"])
    path.write_text("\n".join(table(dev) + ["# " + row]) + "\n")
    out = cli("positioning", path, "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)


def test_a_long_table_with_a_totals_row_and_a_repeated_header(tmp_path):
    dev = runs(seed=3)
    rows = ["Target (mm),Direction,Run,Deviation (µm)"] + [
        f"{t:.3f},{d},{r + 1},{dev[d][i, r]:.3f}" for d in "+-" for r in range(3) for i, t in enumerate(TARGETS)]
    path = tmp_path / "long.csv"
    path.write_text("\n".join(rows + ["Average,,,0.2"]) + "\n")
    # fields missing: refused as a trailer line, as before (it says what to do)
    one_error_line(cli("positioning", path), "'Average,,,0.2' is not a data row", "prefix them with #")
    path.write_text("\n".join(rows + [""] + rows) + "\n")
    one_error_line(cli("positioning", path), f"line {len(rows) + 2}: 'Target (mm),Direction,Run,Deviation (µm)' "
                   "repeats the header: a second table after a blank line")
