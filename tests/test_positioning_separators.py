"""Separators at the ends of a positioning table's lines, and an empty cell. Excel writes a ';' after the last field
of every line, header included, when the sheet has an empty column to the right: that was refused as 'line 2:
missing field(s)' (the profile reader reads it); it is read now, the empty last column dropped. An empty cell was
'line 4: missing field(s)'; its column is named now. Rows that all have one field more than the header (pandas took their
first field for the row index, shifting every column) are refused saying so. '; ' (a separator and a space) after
the last field of every line: the blank-named last column of spaces is dropped as the unnamed empty one is (it was
'line 2: missing field(s): ' ' is empty'). Figures checked against ISO 230-2's definitions computed here (k = 2)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from positioning_tables import TARGETS, iso_a_um, runs

NAMES = ["Target (mm)"] + [f"Run {r} {d} (µm)" for r in (1, 2, 3) for d in "+-"]


def rows(dev):
    """The wide export's data rows as lists of cells, decimal commas."""
    return [[f"{t:.4f}".replace(".", ",")] + [f"{dev[d][i, r]:.3f}".replace(".", ",") for r in range(3) for d in "+-"]
            for i, t in enumerate(TARGETS)]


def write(path, header, cells, end=""):
    """BOM, CRLF, ';' separators, ``end`` after every data line (and after the header when it ends ``header``)."""
    path.write_bytes(("\r\n".join([header] + [";".join(c) + end for c in cells]) + "\r\n").encode("utf-8-sig"))
    return path


@pytest.mark.parametrize("end", ["", ";", "; ", ";  ", ";\t"])   # none, a separator, a separator and spaces
def test_a_separator_after_every_line_header_included_is_read(tmp_path, end):
    dev = runs(seed=4)
    path = write(tmp_path / "t.csv", ";".join(NAMES) + end, rows(dev), end=end)
    out = cli("positioning", path, "--json")
    assert out.returncode == 0 and not out.stderr, (end, out.stderr)
    assert json.loads(out.stdout)["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)


def test_an_empty_cell_is_named_with_its_column_and_line(tmp_path):
    cells = rows(runs(seed=4))
    cells[2][3] = ""                                   # line 4: 'Run 2 + (µm)'
    one_error_line(cli("positioning", write(tmp_path / "e.csv", ";".join(NAMES), cells)),
                   "line 4: missing field(s): 'Run 2 + (µm)' is empty", "fill in the value")


def test_rows_with_one_field_more_than_the_header_are_refused(tmp_path):
    dev = runs(seed=4)
    only_rows = write(tmp_path / "rows.csv", ";".join(NAMES), rows(dev), end=";")
    one_error_line(cli("positioning", only_rows), "the header has 7 names but every data line has 8 fields",
                   "each data line ends with a separator and the header does not")
    extra = write(tmp_path / "extra.csv", ";".join(NAMES[:-1]), rows(dev))     # the header lacks a name
    one_error_line(cli("positioning", extra), "the header has 6 names but every data line has 7 fields",
                   "name every column in the header")


def test_a_run_column_named_twice_is_named_as_written(tmp_path):
    """Before: "column 'Run 1 + (µm).1' is neither the target, a direction nor a run" (pandas' renaming, not in
    the file)."""
    names = NAMES[:3] + ["Run 1 + (µm)"] + NAMES[4:]
    out = cli("positioning", write(tmp_path / "dup.csv", ";".join(names), rows(runs(seed=4))))
    one_error_line(out, "the column 'Run 1 + (µm)' appears twice (columns 1 and 3, numbered from 0)")
    assert ".1'" not in out.stderr
