"""A long positioning table without a run column counts its runs by rows: a point missing at one target (or written
twice) is refused in those terms, naming the target's lines. It said 'target 97.3 misses run(s) [5] in the up
direction' when the target's 3rd point was missing: the file has no run 5 (nor runs at all)."""
from __future__ import annotations

import numpy as np

from cli_calls import cli, one_error_line
from positioning_tables import LONG_TARGETS as TARGETS, capture_order

DEV = {d: np.round((6 * TARGETS / 500 + b)[:, None] + np.random.default_rng(3).normal(0, 0.6, (len(TARGETS), 5)), 3)
       for d, b in (("+", -1.8), ("-", 1.8))}


def _lines(tmp_path, header, cells):
    path = capture_order(tmp_path / "t.txt", DEV, header, cells)
    return path, path.read_text().splitlines()


def _lines_of(lines, target, direction):
    return [k + 1 for k, ln in enumerate(lines) if ln.split("\t")[:2] == [f"{target:.4f}", direction]]


def test_a_missing_point_is_named_by_its_target_and_lines_not_by_a_run_number(tmp_path):
    path, lines = _lines(tmp_path, "Target position [mm]\tDirection\tError [µm]",
                         lambda t, d, r, e: f"{t:.4f}\t{d}\t{e:.3f}")
    gone = _lines_of(lines, 97.3, "+")[2]                    # the target's 3rd point up
    del lines[gone - 1]
    path.write_text("\n".join(lines) + "\n")
    left = _lines_of(lines, 97.3, "+")
    out = cli("positioning", path)
    one_error_line(out, f"target 97.3 has 4 rows with direction '+' (lines {', '.join(map(str, left))}) and the "
                        "other targets 5", "no run column", "a point is missing there")
    assert "run(s) [5]" not in out.stderr


def test_a_point_written_twice_is_named_so(tmp_path):
    path, lines = _lines(tmp_path, "Target position [mm]\tDirection\tError [µm]",
                         lambda t, d, r, e: f"{t:.4f}\t{d}\t{e:.3f}")
    k = _lines_of(lines, 201.6, "-")[1]
    lines.insert(k, lines[k - 1])
    path.write_text("\n".join(lines) + "\n")
    one_error_line(cli("positioning", path), "target 201.6 has 6 rows with direction '-'", "the other targets 5",
                   "written more than once", "delete the extra row")


def test_without_run_and_direction_columns_the_rows_of_a_target_are_counted(tmp_path):
    path, lines = _lines(tmp_path, "Target position [mm]\tError [µm]", lambda t, d, r, e: f"{t:.4f}\t{e:.3f}")
    k = next(i for i, ln in enumerate(lines) if ln.startswith("0.0000\t"))
    del lines[k]
    path.write_text("\n".join(lines) + "\n")
    out = cli("positioning", path, "--run-directions", "up,down")
    one_error_line(out, "target 0 has 9 rows (lines", "and the other targets 10", "a point is missing there")
    assert "direction '" not in out.stderr
