"""Two small positioning messages: a long table whose direction column says Forward/Reverse (the laser software's
run order) is refused saying so and what to write (it said only "is not one of +, -, up, down"); an inch test that
writes compensation tables (in mm) gets a note that an inch machine needs them in inches."""
from __future__ import annotations

import json

import numpy as np

from cli_calls import cli, one_error_line
from datasets.positioning import axis_test, to_frame


def long_table(tmp_path, name, *, scale=1.0, unit="mm", directions=None):
    data, _ = axis_test(rng=np.random.default_rng(1), pitch=(0.0, 0.01), reversal=-0.002)
    df = to_frame(data, actual=False)
    if directions:
        df["direction"] = df["direction"].map(directions)
    df["target"] *= scale
    df["deviation"] *= scale
    df.columns = [f"Target ({unit})", "Direction", "Run", f"Deviation ({unit})"]
    p = tmp_path / name
    df.to_csv(p, index=False)
    return p


def test_forward_in_a_long_table_names_the_run_order(tmp_path):
    p = long_table(tmp_path, "fr.csv", directions={"+": "Forward", "-": "Reverse"})
    one_error_line(cli("positioning", p), "line 2", "'Forward' names the run order", "write + or -")


def test_an_inch_test_writing_tables_in_mm_says_so(tmp_path):
    inch = long_table(tmp_path, "in.csv", scale=1 / 25.4, unit="in")
    mm = long_table(tmp_path, "mm.csv")
    for p in (inch, mm):
        out = cli("positioning", p, "--json", "--compensation-from", "mean", "--compensation", "csv", tmp_path / "t.csv")
        assert out.returncode == 0, out.stderr
        said = [n for n in json.loads(out.stdout)["notes"] if "inch machine" in n]
        assert bool(said) == (p == inch), said
    text = cli("positioning", inch, "--compensation-from", "mean", "--compensation", "csv", tmp_path / "t.csv")
    assert "the compensation tables are in mm, the input in inches" in text.stdout
    assert "the csv values are mm: divide them by 25.4 for inches" in text.stdout and "fanuc" not in text.stdout
    # a FANUC tape holds counts of the machine's own unit, which the file does not tell: asked for, then said
    # (tests/test_compensation_inch.py checks the inch tape itself)
    args = ("positioning", inch, "--compensation-from", "mean", "--compensation", "fanuc-pitch", tmp_path / "f.txt")
    one_error_line(cli(*args), "the test is in inches", "--fanuc-increment 0.0001in")
    fanuc = cli(*args, "--fanuc-increment", "0.0001in")
    assert ("the fanuc-pitch tape is for an inch machine, as --fanuc-increment 0.0001in says: its values, 3624 and "
            "1851 are counts of 0.0001 in" in fanuc.stdout), fanuc.stdout + fanuc.stderr
    plain = cli("positioning", inch)
    assert "inch machine" not in plain.stdout + plain.stderr   # no table written, no note
