"""FANUC pitch-error points of several axes: the point numbers are one block that every axis' parameters 3620-3622
point into (0i-PB parameter manual B-63980EN/01 p. 99-100), so two axes' tapes must fill different numbers.
Before: every tape started at point 0 and the command line could not move it; the Z tape loaded after the X tape
overwrote X's points, and X was compensated with Z's increments."""
from __future__ import annotations

import json
import re

import numpy as np

import methods
from cli_calls import cli, one_error_line
from compensation_controllers import read_fanuc, remeasure
from datasets.positioning import axis_test, to_frame

PITCH = (0.0, 0.030, -0.020, 0.010)


def load_into_one_block(*tapes: str) -> list[str]:
    """The controller's one block of pitch-error points, loaded tape after tape (a later point number overwrites an
    earlier one), then each axis' tape as the controller sees it: its own comments and SET parameters, and the
    points 3621 ... 3622 as they are in the block after all tapes were loaded."""
    block = {}
    for tape in tapes:
        block.update({int(n): int(v) for n, v in re.findall(r"^N1(\d{4}) P(-?\d+)$", tape, re.M)})
    seen = []
    for tape in tapes:
        p21, p22 = (int(v) for v in re.search(r"3621 = (\d+), 3622 = (\d+)", tape).groups())
        comments = [line for line in tape.splitlines() if line.startswith("(")]
        points = [f"N{10000 + n} P{block[n]}" for n in range(p21, p22 + 1)]
        seen.append("\n".join(["%", *comments, *points, "%"]) + "\n")
    return seen


def test_two_axes_tapes_fill_separate_points_and_both_compensate(tmp_path):
    tests = {"X": axis_test(rng=np.random.default_rng(5), travel=(0.0, 1000.0), pitch=PITCH, reversal=0.0),
             "Z": axis_test(rng=np.random.default_rng(7), travel=(-800.0, 0.0), targets=9,   # seed 6: its ↑ cubic fails the 5 % lack-of-fit test (p = 1.3 %)
                            pitch=(0.0, -0.025, 0.015, 0.0), reversal=0.0)}
    for name, (data, _) in tests.items():
        to_frame(data, actual=False).to_csv(tmp_path / f"{name}.csv", index=False)
    out = cli("positioning", tmp_path / "X.csv", "--deviation-unit", "mm", "--axis", "X",
              "--compensation", "fanuc-pitch", tmp_path / "x.tap")
    assert out.returncode == 0, out.stderr
    last_x = int(re.search(r"fills pitch-error points 0 \.\.\. (\d+)", out.stdout).group(1))
    assert f"--fanuc-first-point {last_x + 1} or higher" in out.stdout
    out = cli("positioning", tmp_path / "Z.csv", "--deviation-unit", "mm", "--axis", "Z",
              "--fanuc-first-point", last_x + 1, "--compensation", "fanuc-pitch", tmp_path / "z.tap")
    assert out.returncode == 0, out.stderr
    tapes = {n: (tmp_path / f"{n.lower()}.tap").read_text() for n in tests}
    js = cli("positioning", tmp_path / "Z.csv", "--deviation-unit", "mm", "--axis", "Z", "--json",
             "--fanuc-first-point", last_x + 1, "--compensation", "fanuc-pitch", tmp_path / "z.tap")
    points = json.loads(js.stdout)["compensation"]["tables"][0]["fanuc_points"]
    assert points["p3621"] == last_x + 1 and points["p3621"] <= points["p3620"] < points["p3622"]
    assert re.search(rf"3621 = {last_x + 1}, ", tapes["Z"])
    assert re.search(rf"THIS TAPE FILLS PITCH-ERROR POINTS {last_x + 1} \.\.\. \d+", tapes["Z"])
    # loaded one after the other into the controller's one block, each axis keeps its own increments
    for (name, (data, truth)), tape in zip(tests.items(), load_into_one_block(tapes["X"], tapes["Z"])):
        encoder, _ = read_fanuc(tape)
        before = methods.fit("positioning.iso230_2", data).figures
        after = methods.fit("positioning.iso230_2", remeasure(data, truth, encoder, np.random.default_rng(9))).figures
        assert after["M"] <= 0.5 * before["M"], (name, before["M"], after["M"])


def test_a_first_point_that_does_not_fit_is_refused(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(5), pitch=PITCH)
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    for first, words in (("1020", ("do not fit the pitch block", "at most 1013 (--fanuc-first-point)")),
                         ("-1", ("first point number -1", "0 ... 1023")),
                         ("2000", ("first point number 2000", "0 ... 1023"))):
        out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X", "--fanuc-first-point",
                  first, "--compensation", "fanuc-pitch", tmp_path / "t.tap")
        one_error_line(out, *words)
        assert not (tmp_path / "t.tap").exists()


def test_the_advice_for_a_first_point_without_room_can_be_followed(tmp_path):
    """A first point that leaves too few points: following the advice writes the tape. Before, the coarser --interval
    advised was the one that fits from point 0 (0.979 mm for 1000 mm, whatever the first point: still refused), and
    it was advised also where no interval fits the room or the one that fits is refused as too coarse for the curve."""
    data, _ = axis_test(rng=np.random.default_rng(5), pitch=PITCH)
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    args = ("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X", "--compensation-from", "mean",
            "--compensation", "fanuc-pitch", tmp_path / "t.tap")
    seen = set()
    for first, interval in ((990, ("--interval", "10")), (1013, ("--interval", "10")), (1014, ()), (1023, ())):
        out = cli(*args, "--fanuc-first-point", first, *interval)
        one_error_line(out, f"points from number {first} do not fit the pitch block")
        lower = re.search(r"first point number of at most (\d+) \(--fanuc-first-point\)", out.stderr).group(1)
        assert int(lower) < first
        ok = cli(*args, "--fanuc-first-point", lower, *interval)
        assert ok.returncode == 0 and "3622 = 1023;" in ok.stdout, ok.stderr
        assert f"tape must end below {lower}" in ok.stdout and "--fanuc-first-point 1024" not in ok.stdout
        coarser = re.search(r"coarser --interval \(at least ([\d.]+) mm", out.stderr)
        refused = re.search(r"no coarser --interval helps: ([\d.]+) mm", out.stderr)
        if coarser:                                   # the finest interval whose points fit from this first point
            seen.add("interval")
            step = float(coarser.group(1))
            ok = cli(*args, "--fanuc-first-point", first, "--interval", coarser.group(1))
            assert ok.returncode == 0 and "3622 = 1023;" in ok.stdout, ok.stderr
            one_error_line(cli(*args, "--fanuc-first-point", first, "--interval", f"{step - 0.001:.3f}"),
                           "do not fit the pitch block")
        elif refused:                                 # it fits but misses the curve: said, not advised
            seen.add("refused")
            one_error_line(cli(*args, "--fanuc-first-point", first, "--interval", refused.group(1)), "too coarse")
        else:                                         # one point left: no table fits
            seen.add("none")
            assert "1 point is left" in out.stderr and "--interval" not in out.stderr
    assert seen == {"interval", "refused", "none"}


def test_fanuc_options_without_a_fanuc_tape_are_refused(tmp_path):
    """--fanuc-first-point / --fanuc-increment with no --compensation fanuc-pitch (forgotten, or another format) were
    read and ignored, exit 0, nothing said; now refused in one line, nothing written."""
    data, _ = axis_test(rng=np.random.default_rng(5), pitch=PITCH)
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    base = ("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X", "--compensation-from", "mean")
    table = ("--compensation", "csv", tmp_path / "d.csv")
    for extra, named in ((("--fanuc-first-point", "50"), "--fanuc-first-point applies"),
                         (("--fanuc-first-point", "0"), "--fanuc-first-point applies"),
                         (("--fanuc-increment", "0.0001mm"), "--fanuc-increment applies"),
                         (("--fanuc-first-point", "50", "--fanuc-increment", "0.0001in"),
                          "--fanuc-first-point and --fanuc-increment apply")):
        for tables in ((), table):
            one_error_line(cli(*base, *tables, *extra), named, "add --compensation fanuc-pitch FILE or drop")
            assert not (tmp_path / "d.csv").exists()
    ok = cli(*base, *table, "--compensation", "fanuc-pitch", tmp_path / "t.tap", "--fanuc-first-point", "50",
             "--fanuc-increment", "0.0001mm")
    assert ok.returncode == 0 and "3621 = 50," in ok.stdout, ok.stderr
