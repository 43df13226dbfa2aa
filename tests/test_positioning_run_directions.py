"""Run columns that name no approach direction (``Run 1 ... Run 10``). Before: a bidirectional test exported so,
odd runs forward and even runs reverse, was evaluated as one unidirectional ↑ test (R 9.88 instead of 4.80 µm, no
B, exit 0), and any unlabelled test was called ↑ although nothing said the approach was in +. Now alternating runs
are refused naming --run-directions, which reads them as the labelled test; an unlabelled single direction is
'direction not given'."""
from __future__ import annotations

import json

import numpy as np
import pytest

from datasets.io import read_positioning
from datasets.io.positioning import ALTERNATING_P, alternating_runs
from datasets.positioning import axis_test
from cli_calls import cli, one_error_line


def exports(tmp_path, seed=2):
    """The same bidirectional test as a labelled wide export and as Run 1 ... Run 10 (odd = ↑, even = ↓), µm."""
    data, _ = axis_test(rng=np.random.default_rng(seed), reversal=-0.004)
    n = data.runs
    fmt = lambda row: ";".join(f"{v:.4f}" for v in row)    # noqa: E731
    labelled = ["Target (mm)"] + [f"Run {r} {d} (µm)" for r in range(1, n + 1) for d in "+-"]
    inter = np.empty((len(data.targets), 2 * n))
    inter[:, 0::2], inter[:, 1::2] = data.up * 1e3, data.down * 1e3
    (tmp_path / "lab.csv").write_text(";".join(labelled) + "\n" + "\n".join(
        fmt(np.r_[t, row]) for t, row in zip(data.targets, inter)) + "\n")
    plain = ["Target (mm)"] + [f"Run {r} (µm)" for r in range(1, 2 * n + 1)]
    (tmp_path / "ten.csv").write_text(";".join(plain) + "\n" + "\n".join(
        fmt(np.r_[t, row]) for t, row in zip(data.targets, inter)) + "\n")
    return tmp_path / "lab.csv", tmp_path / "ten.csv", data


def test_alternating_unlabelled_runs_are_refused_naming_the_option(tmp_path):
    lab, ten, data = exports(tmp_path)
    out = cli("positioning", ten)
    one_error_line(out, "name no approach direction", "--run-directions up,down", "odd runs differ from the even runs by")
    true_b = float(np.mean(data.up - data.down)) * 1e3
    got = float(out.stderr.split("even runs by ")[1].split(" µm")[0])
    assert got == pytest.approx(true_b, abs=0.01)


def test_run_directions_reads_them_as_the_labelled_test(tmp_path):
    lab, ten, _ = exports(tmp_path)
    ref = json.loads(cli("positioning", lab, "--json").stdout)
    got = json.loads(cli("positioning", ten, "--json", "--run-directions", "up,down").stdout)
    for key in ("A", "E", "M", "R", "B", "B_mean", "R_up", "R_down", "A_up", "A_down"):
        assert got[key] == pytest.approx(ref[key], abs=1e-12), key
    assert got["directions"] == "bidirectional" and any("--run-directions up,down" in n for n in got["notes"])
    swapped = json.loads(cli("positioning", ten, "--json", "--run-directions", "down,up").stdout)
    assert swapped["B_mean"] == pytest.approx(-ref["B_mean"], abs=1e-12)


def test_an_unlabelled_single_direction_is_not_called_up(tmp_path):
    """One direction, 5 runs drifting 1 µm per run (not two directions), no label: evaluated, direction not
    given; --run-directions down names it ↓."""
    rng = np.random.default_rng(3)
    T = np.linspace(0, 500, 6)
    runs = 2e-3 * T[:, None] / 500 + 1e-3 * np.arange(5)[None, :] + rng.normal(0, 2e-4, (6, 5))
    p = tmp_path / "uni.csv"
    p.write_text("target," + ",".join(f"run {r}" for r in range(1, 6)) + "\n"
                 + "\n".join(",".join(f"{v:.6f}" for v in np.r_[t, row]) for t, row in zip(T, runs)) + "\n")
    out = cli("positioning", p)
    assert out.returncode == 0, out.stderr
    assert "unidirectional (direction not given)" in out.stdout and "↑" not in out.stdout
    assert "name no approach direction" in out.stdout
    assert json.loads(cli("positioning", p, "--json").stdout)["directions"] == "unidirectional (direction not given)"
    down = cli("positioning", p, "--run-directions", "down")
    assert "unidirectional (down)" in down.stdout and "↓" in down.stdout
    assert read_positioning(p, run_directions="down").down is not None


def test_run_directions_on_a_labelled_file_is_refused(tmp_path):
    lab, _, _ = exports(tmp_path)
    one_error_line(cli("positioning", lab, "--run-directions", "up,down"), "this file names its directions",
                   "drop the option")


def test_unidirectional_runs_rarely_pass_for_two_directions():
    """300 unidirectional tests of 10 runs with a random offset per run (0.5 µm) and 1 µm repeatability: the
    Welch test of the odd against the even runs' means flags at most 1 (its level is 0.1 %)."""
    rng = np.random.default_rng(0)
    flagged = 0
    for _ in range(300):
        v = rng.normal(0, 1e-3, (11, 10)) + rng.normal(0, 5e-4, (1, 10))
        flagged += alternating_runs(v)[2] < ALTERNATING_P
    assert flagged <= 1
    assert alternating_runs(np.zeros((5, 3))) is None
