"""A closed trace whose first point is written again at the end (as many instruments export it) is read as the profile
it is: the repeat is dropped with a note, and the figures are those of the file without it. It was refused with 'two
points lie at the same polar angle (point 0)'. A last point at the first one's angle with another value is still
refused: that is two measurements at one angle, not a repeat."""
from __future__ import annotations

import json

import pytest

from cli_calls import cli
from conftest import REPO

EXAMPLES = REPO / "docs" / "examples"


def closed_copy(src, dst, last_line):
    text = src.read_text()
    dst.write_text(text + ("" if text.endswith("\n") else "\n") + last_line + "\n")
    return dst


def figures(*args):
    code, out, err = cli("roundness", *args, "--json")
    assert code == 0, err
    d = json.loads(out)
    return d["references"], d["notes"]


@pytest.mark.parametrize("name, closing", [
    ("roundness.csv", lambda lines: lines[1]),                                    # x, y: the first point again
    ("profile.csv", lambda lines: "360.0," + lines[1].split(",")[1]),             # angle + deviation: 360° at 0°'s
    ("profile.csv", lambda lines: lines[1]),                                      # ... or 0° written again
])
def test_repeated_closing_point_is_dropped_with_a_note(tmp_path, name, closing):
    src = EXAMPLES / name
    closed = closed_copy(src, tmp_path / name, closing(src.read_text().splitlines()))
    ref, ref_notes = figures(src)
    got, notes = figures(closed)
    assert got == ref                                     # every figure of every reference circle, to the last bit
    extra = [n for n in notes if n not in ref_notes]
    assert len(extra) == 1 and "repeats the first" in extra[0] and "dropped" in extra[0], notes
    code, out, err = cli("roundness", closed)
    assert code == 0 and "note: the last point repeats the first" in out and "Traceback" not in err, err


def test_fit_reads_the_closed_trace_without_its_repeat(tmp_path):
    src = EXAMPLES / "trace.csv"
    closed = closed_copy(src, tmp_path / "trace.csv", src.read_text().splitlines()[1])
    ref = json.loads(cli("fit", "circle.gauss_newton", src, "--json", "--no-residuals")[1])
    got = json.loads(cli("fit", "circle.gauss_newton", closed, "--json", "--no-residuals")[1])
    assert (got["center"], got["radius"], got["n_points"]) == (ref["center"], ref["radius"], ref["n_points"])
    assert any("repeats the first" in n for n in got["notes"])


def test_a_different_value_at_the_first_angle_is_still_refused(tmp_path):
    src = EXAMPLES / "profile.csv"
    first = src.read_text().splitlines()[1].split(",")
    closed = closed_copy(src, tmp_path / "profile.csv", f"360.0,{float(first[1]) + 0.05:.4f}")
    code, _, err = cli("roundness", closed)
    assert code == 2 and "same polar angle" in err and len(err.strip().splitlines()) == 1, err
