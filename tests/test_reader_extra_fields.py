"""The x, y reader (fit, roundness, circular-test, magnify) and what a table's rows hold beyond its header.

* Rows with more fields than the header names were read from their first fields, silently: a point number before
  x, y (``x,y`` over ``1,170.001533,80.000000``) gave a circle of R 99.487 mm about (120.82, 182.84) for one of
  R 50 about (120, 80), exit 0; a decimal-comma file written with ',' between the fields (``170,80,000``) lost its
  third field. Such rows are refused in one line saying how many columns the header names and how many fields
  the rows have, and what to do; the way out it gives reads the circle.
* A units row with a placeholder for a column without a unit (``Nr;X;Y`` over ``[-];[µm];[µm]``, ``-``, ``[1]``)
  was not taken for a units row ('[µm]' is not a number); it is, and the values are read in its units (also in a
  positioning long table: ``[mm],[-],[-],[µm]``).
* An empty cell, a totals line, a summary after a blank line: the refusal says what to do; two blocks of points
  are still named as blocks.

The expected figures are the circle the points were made from (centre (120, 80) mm, R 50 mm) and ISO 230-2's A
computed here from the deviations by the standard's definitions, never fitbench's own output."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from datasets.io import read_points
from datasets.io.columns import SMALL_FILE_BYTES
from datasets.io.numbers import DataFileError

REPO = __import__("pathlib").Path(__file__).resolve().parents[1]
CENTRE, RADIUS = (120.0, 80.0), 50.0


def _circle(n):
    """``n`` points of the circle about CENTRE of RADIUS (mm), exact to the 6 decimals written."""
    t = 2 * np.pi * np.arange(n) / n
    return np.c_[CENTRE[0] + RADIUS * np.cos(t), CENTRE[1] + RADIUS * np.sin(t)]


def _write(path, header, rows):
    path.write_text(header + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    return path


def _fit(*args):
    """centre x, centre y, radius (mm) of ``fitbench fit circle.gauss_newton ARGS --json``."""
    code, out, err = cli("fit", "circle.gauss_newton", *args, "--json")
    assert code == 0, err
    got = json.loads(out)
    return (*got["center"], got["radius"])


# ------------------------------------------------------------------ rows longer than the header
LONGER = {   # header, one row of the circle's point (i, x, y) as a file with an unnamed column writes it
    "point number first": ("x,y", lambda i, x, y: f"{i + 1},{x:.6f},{y:.6f}"),
    "unnamed z last": ("x [mm],y [mm]", lambda i, x, y: f"{x:.6f},{y:.6f},0.0"),
    "3-D export, z between": ("x [mm],y [mm]", lambda i, x, y: f"{x:.6f},250.000,{y:.6f}"),
    "decimal commas, ',' between the fields": ("x,y", lambda i, x, y: f"{x:.3f}".replace(".", ",") + ","
                                               + f"{y:.3f}".replace(".", ",")),
}


@pytest.mark.parametrize("n", [240, 20000], ids=["small file", "large file (pandas)"])
@pytest.mark.parametrize("case", list(LONGER))
def test_rows_with_more_fields_than_the_header_names_are_refused(tmp_path, case, n):
    header, row = LONGER[case]
    path = _write(tmp_path / "extra.csv", header, [row(i, x, y) for i, (x, y) in enumerate(_circle(n))])
    assert (path.stat().st_size > SMALL_FILE_BYTES) == (n == 20000)
    fields = len(row(0, 170.0, 80.0).split(","))
    with pytest.raises(DataFileError, match=f"names 2 columns .* but every data line has {fields} fields "
                                            r"\(line 2: .*name every column in the header, or give --skip-rows 1"):
        read_points(path)
    for command in (("fit", "circle.gauss_newton", path), ("roundness", path),
                    ("circular-test", path, path, "--nominal-radius", RADIUS),
                    ("magnify", path, path, "--eta", 100)):
        one_error_line(cli(*command), "extra.csv: the header (line 1) names 2 columns",
                       f"every data line has {fields} fields", "--columns I J")
    if "decimal commas" in case:
        one_error_line(cli("fit", "circle.gauss_newton", path), "export with ';' or tabs between the fields")


def test_the_way_out_the_refusal_gives_reads_the_circle(tmp_path):
    header, row = LONGER["point number first"]
    path = _write(tmp_path / "extra.csv", header, [row(i, x, y) for i, (x, y) in enumerate(_circle(240))])
    cx, cy, r = _fit(path, "--skip-rows", 1, "--columns", 1, 2)
    assert np.allclose([cx, cy, r], [*CENTRE, RADIUS], atol=1e-6)
    named = _write(tmp_path / "named.csv", "Nr,x,y", [row(i, x, y) for i, (x, y) in enumerate(_circle(240))])
    assert np.allclose(_fit(named), [*CENTRE, RADIUS], atol=1e-6)


def test_a_longer_row_below_the_first_lines_is_refused_naming_it(tmp_path):
    for n in (400, 20000):
        rows = [f"{x:.6f},{y:.6f}" for x, y in _circle(n)]
        rows[300] = "301," + rows[300]
        path = _write(tmp_path / f"late{n}.csv", "x,y", rows)
        one_error_line(cli("fit", "circle.gauss_newton", path), "line 302: 3 fields where the header (line 1) has 2",
                       "correct the line, or delete it")


@pytest.mark.parametrize("n", [240, 20000])
@pytest.mark.parametrize("ending", [",", ", ", ",  # probe 1"])
def test_separators_at_the_end_of_the_data_lines_and_inline_comments_are_still_read(tmp_path, n, ending):
    path = _write(tmp_path / "ends.csv", "x,y", [f"{x:.6f},{y:.6f}{ending}" for x, y in _circle(n)])
    assert np.allclose(read_points(path), _circle(n), atol=1e-6)


def test_the_shipped_examples_are_still_read():
    for name in ("trace.csv", "cw.csv", "ccw.csv", "roundness.csv"):
        assert len(read_points(REPO / "docs/examples" / name)) > 100


# ------------------------------------------------------------------ a units row with placeholders
@pytest.mark.parametrize("placeholder", ["[-]", "-", "[1]", "1", "(-)", "[]"])
def test_a_units_row_with_a_placeholder_for_a_unitless_column_is_read_in_its_units(tmp_path, placeholder):
    rows = [f"{i + 1};{1000 * x:.3f};{1000 * y:.3f}" for i, (x, y) in enumerate(_circle(240))]
    path = _write(tmp_path / "units.csv", f"Nr;X;Y\n{placeholder};[µm];[µm]", rows)
    assert np.allclose(read_points(path, ("X", "Y")), _circle(240), atol=1e-6)      # µm read as µm: mm out
    assert np.allclose(_fit(path, "--columns", "X", "Y"), [*CENTRE, RADIUS], atol=1e-6)


def _iso_230_2_accuracy(table):
    """ISO 230-2:2014 A (µm) of a long table's rows (target, direction, run, deviation in µm), from the
    standard's definitions: per target and direction the mean and the standard deviation s of the runs; A is the
    largest mean + 2s minus the smallest mean - 2s over both directions."""
    up, down = [], []
    for target in sorted({t for t, _, _, _ in table}):
        for direction, out in (("+", up), ("-", down)):
            d = np.array([v for t, s, _, v in table if t == target and s == direction])
            out.append((d.mean() + 2 * d.std(ddof=1), d.mean() - 2 * d.std(ddof=1)))
    return max(hi for hi, _ in up + down) - min(lo for _, lo in up + down)


@pytest.mark.parametrize("units", ["[mm],[-],[-],[µm]", "mm,-,-,µm", "[mm],[1],[1],[µm]", "[mm],[-],[-],[mm]"])
def test_a_positioning_long_table_s_units_row_with_placeholders_is_read(tmp_path, units):
    lines = (REPO / "docs/examples/positioning.csv").read_text(encoding="utf-8").splitlines()
    names = lines[0].split(";")[1:]
    table = []
    for line in lines[1:]:
        values = line.split(";")
        for name, v in zip(names, values[1:]):
            run, direction = re.search(r"Run (\d+) ([+-])", name).groups()
            table.append((float(values[0]), direction, int(run), float(v)))
    scale = 1e-3 if units.endswith("[mm]") else 1.0
    rows = [f"{t:.3f},{s},{run},{v * scale:.9f}" for t, s, run, v in table]
    path = _write(tmp_path / "long.csv", f"Target,Direction,Run,Deviation\n{units}", rows)
    code, out, err = cli("positioning", path, "--json")
    assert code == 0, err
    assert json.loads(out)["A"] == pytest.approx(_iso_230_2_accuracy(table) * 1e-3, abs=1e-9)   # --json: mm


# ------------------------------------------------------------------ empty cells, totals, summaries
def test_an_empty_cell_and_a_totals_line_say_what_to_do(tmp_path):
    rows = [f"{x:.6f},{y:.6f}" for x, y in _circle(240)]
    empty = _write(tmp_path / "empty.csv", "x [mm],y [mm]", rows[:4] + [rows[4].split(",")[0] + ","] + rows[5:])
    totals = _write(tmp_path / "totals.csv", "x,y", rows + ["Mean,120.0"])
    for command in ("fit", "roundness"):
        args = ("circle.gauss_newton",) if command == "fit" else ()
        one_error_line(cli(command, *args, empty), "empty.csv line 6: missing field: 'y [mm]' is empty: fill in the "
                                                   "value, or delete the line")
        one_error_line(cli(command, *args, totals), "totals.csv line 242: 'Mean' is not a number: correct the value, "
                                                    "or delete the line", "prefix it with #")


def test_a_summary_after_a_blank_line_is_named_as_lines_below_the_points(tmp_path):
    rows = [f"{x:.6f},{y:.6f}" for x, y in _circle(240)]
    summary = _write(tmp_path / "summary.csv", "x,y", rows + ["", "Max deviation,0.0034", "Count,240"])
    excel = _write(tmp_path / "excel.csv", "x,y", rows + [",", "Count,240"])
    for command in ("fit", "roundness"):
        args = ("circle.gauss_newton",) if command == "fit" else ()
        one_error_line(cli(command, *args, summary), "summary.csv line 243: 'Max deviation' is not a number: lines "
                                                     "243-244, below the points, are not points",
                       "delete them, or prefix them with #", absent=("blocks",))
        one_error_line(cli(command, *args, excel), "excel.csv line 242: holds only separators (','), no values: "
                                                   "lines 242-243, below the points, are not points")
    commented = _write(tmp_path / "commented.csv", "x,y", rows + ["", "# Max deviation,0.0034", "# Count,240"])
    assert np.allclose(_fit(commented), [*CENTRE, RADIUS], atol=1e-6)


def test_two_blocks_of_points_are_still_named_as_blocks(tmp_path):
    rows = [f"{x:.6f},{y:.6f}" for x, y in _circle(240)]
    path = _write(tmp_path / "two.csv", "x,y", rows[:120] + [""] + rows[120:])
    one_error_line(cli("roundness", path), "2 blocks of points separated by blank lines")
    second = _write(tmp_path / "second.csv", "x,y", rows[:120] + ["", "x,y"] + rows[120:])
    one_error_line(cli("magnify", second, second, "--eta", 10), "line 123: 'x' is not a number: rows of numbers "
                                                               "follow again from line 124", "second table")
