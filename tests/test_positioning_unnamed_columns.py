"""A positioning table's header cell left empty: messages name that column by its place in the user's file (its
0-based number, as --column takes it, and its spreadsheet letter), never by pandas' name for it ('Unnamed: 10',
which the file does not hold)."""
from __future__ import annotations

import pytest

from cli_calls import cli, one_error_line

NAMES = ["Target (mm)"] + [f"Run {r} {d} (µm)" for r in (1, 2, 3) for d in "+-"]


def rows():
    """A wide export's data rows (5 targets, 3 runs each way) as lists of cells."""
    return [[f"{t:.4f}"] + [f"{(-1.8 if d == '+' else 1.8) + 0.1 * r + t / 500:.3f}" for r in range(3) for d in "+-"]
            for t in (0.0, 97.3, 201.6, 298.1, 402.7)]


def write(path, header, cells):
    path.write_text("\n".join([header] + [";".join(c) for c in cells]) + "\n", encoding="utf-8")
    return path


def test_a_wide_run_column_without_name_is_named_by_its_place(tmp_path):
    header = ";".join(NAMES[:-1]) + ";"          # the last run column's name left out: column 6, G
    out = cli("positioning", write(tmp_path / "w.csv", header, rows()))
    one_error_line(out, "column 6 (G in a spreadsheet; no name in the header) holds values", "name it in the header")
    assert "Unnamed" not in out.stderr


def test_a_wide_table_whose_target_column_has_no_name(tmp_path):
    header = ";" + ";".join(NAMES[1:])
    out = cli("positioning", write(tmp_path / "t.csv", header, rows()))
    one_error_line(out, "column 0 (A in a spreadsheet; no name in the header)", "--column target=0")
    assert "Unnamed" not in out.stderr


def _long(path, header, extra):
    """A long table (target, direction, run, deviation) with ``extra(i)`` as a 5th field of row i."""
    lines = [header]
    i = 0
    for t in (0.0, 100.0, 200.0):
        for d in "+-":
            for run in (1, 2, 3):
                lines.append(f"{t};{d};{run};{0.5 * run - 1 + (d == '-')};{extra(i)}")
                i += 1
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_a_long_table_note_names_an_unnamed_numeric_column_by_its_place(tmp_path):
    path = _long(tmp_path / "l.csv", "Target [mm];Direction;Run;Deviation [µm];", lambda i: i)
    out = cli("positioning", path)
    assert out.returncode == 0, out.stderr
    assert "note: not read: column 4 (E in a spreadsheet; no name in the header)" in out.stdout
    assert "Unnamed" not in out.stdout + out.stderr


def test_an_empty_cell_of_an_unnamed_column_is_named_by_its_place(tmp_path):
    path = _long(tmp_path / "g.csv", "Target [mm];Direction;Run;Deviation [µm];", lambda i: "" if i == 3 else i)
    out = cli("positioning", path)
    one_error_line(out, "line 5: missing field(s): column 4 (E in a spreadsheet; no name in the header) is empty")
    assert "Unnamed" not in out.stderr


@pytest.mark.parametrize("k, letters", [(0, "A"), (25, "Z"), (26, "AA"), (51, "AZ"), (52, "BA"), (701, "ZZ"),
                                        (702, "AAA")])
def test_spreadsheet_letters(k, letters):
    from datasets.io.positioning import _spreadsheet_letters
    assert _spreadsheet_letters(k) == letters


def test_the_place_is_the_file_s_when_a_column_before_it_is_not_read(tmp_path):
    """Two target columns, --column choosing the second: the first is not read, and the unnamed run column is still
    named by its place in the file (column 7, H), not in what is left of the table."""
    cells = [[c[0]] + c for c in rows()]
    header = "Nominal (mm);" + ";".join(NAMES[:-1]) + ";"
    out = cli("positioning", write(tmp_path / "n.csv", header, cells), "--column", "target=1")
    one_error_line(out, "column 7 (H in a spreadsheet; no name in the header) holds values")
    assert "Unnamed" not in out.stderr
