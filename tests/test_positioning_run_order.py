"""Wide laser exports name their runs 'Forward'/'Reverse' ('Hin'/'Rück'): the run order, not the axis direction.
ISO 230-2's ↑ is an approach in the + direction, so a forward run through decreasing targets (a Z axis tested
downward) is ↓. A table read the other way swaps ↑ and ↓: B̄ changes sign and the backlash entry doubles the
reversal error instead of removing it."""
from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from datasets.io import read_positioning
from methods.positioning.data import RunOrderNote

LOST_MOTION = 0.005   # mm: moving down the axis stops 2.5 µm above the target, moving up 2.5 µm below


def z_export(path, *, order="down", words=("Forward", "Reverse"), seed=3):
    """A Z axis tested from 0 to -500 mm as laser software exports it (targets in acquisition order, errors in
    µm); the forward runs move down the axis (−), the reverse runs up (+). Returns the true ↑ - ↓ (mm)."""
    rng = np.random.default_rng(seed)
    T = np.array([0.0, -48.7, -101.3, -152.2, -197.9, -251.6, -302.4, -348.8, -401.5, -449.3, -500.0])
    slope = -0.015 * T / 500
    down = slope[:, None] + LOST_MOTION / 2 + rng.normal(0, 2e-4, (T.size, 3))   # moving −: stops above
    up = slope[:, None] - LOST_MOTION / 2 + rng.normal(0, 2e-4, (T.size, 3))
    rows = np.column_stack([T, down * 1e3, up * 1e3])
    if order == "up":
        rows = rows[::-1]
    elif order == "shuffled":
        rows = rows[[3, 0, 7, 1, 10, 5, 2, 9, 4, 8, 6]]
    head = ["Target (mm)"] + [f"Run {r} {words[0]} (µm)" for r in (1, 2, 3)] + [f"Run {r} {words[1]} (µm)" for r in (1, 2, 3)]
    path.write_text("\t".join(head) + "\n" + "\n".join("\t".join(f"{v:.4f}" for v in row) for row in rows) + "\n",
                    encoding="utf-8")
    return float(np.mean(up.mean(axis=1) - down.mean(axis=1)))


@pytest.mark.parametrize("words", [("Forward", "Reverse"), ("Hin", "Rück"), ("fwd", "rev")])
def test_forward_runs_through_decreasing_targets_are_the_minus_direction(tmp_path, words):
    """The forward runs of a downward test are ↓: B̄ = x̄↑ − x̄↓ = −5 µm (it read +4.93 µm before) and the
    backlash to enter is +5 µm (before: −4.93 µm, 'negative backlash', which doubles the error)."""
    p = tmp_path / "z.txt"
    truth = z_export(p, words=words)
    assert truth == pytest.approx(-LOST_MOTION, abs=3e-4)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        data = read_positioning(p)
    note = [w.message for w in seen if issubclass(w.category, RunOrderNote)]
    assert len(note) == 1 and note[0].forward == "-" and "decreasing" in str(note[0])
    np.testing.assert_allclose(np.mean(data.up.mean(axis=1) - data.down.mean(axis=1)), truth, atol=1e-7)  # 4 decimals in µm
    out = cli("positioning", p, "--axis", "Z", "--compensation", "siemens-eec", tmp_path / "z.mpf")
    assert out.returncode == 0, out.stderr
    b_mean = float(re.search(r"B_mean\s+mean reversal value\s+(\S+)", out.stdout).group(1))
    assert b_mean == pytest.approx(truth * 1e3, abs=1e-3) and b_mean < 0
    assert re.search(r"note: .*run order, not the axis direction.*forward runs are read as approaches in the − \(↓\) "
                     r"direction", out.stdout)
    backlash = float(re.search(r"MD32450 \$MA_BACKLASH\[0\] of Z = (\S+) mm", (tmp_path / "z.mpf").read_text()).group(1))
    assert backlash == pytest.approx(-truth, abs=1e-6) and backlash > 0


def test_forward_runs_through_increasing_targets_stay_plus(tmp_path):
    """The same test listed from -500 up to 0 (the forward runs moving +): the forward runs are ↑, said so."""
    p = tmp_path / "z.txt"
    z_export(p, order="up")
    out = cli("positioning", p, "--json")
    got = json.loads(out.stdout)
    assert out.returncode == 0 and got["B_mean"] > 0           # the columns' own data: 'forward' here moved up
    assert any("read as approaches in the + (↑) direction" in n for n in got["notes"])


def test_an_unordered_file_is_refused_unless_the_direction_is_given(tmp_path):
    """Targets neither increasing nor decreasing: which way 'forward' moved is unknown: one line naming
    --forward-direction; with it the figures equal those of the ordered file."""
    p, q = tmp_path / "s.txt", tmp_path / "z.txt"
    z_export(p, order="shuffled")
    z_export(q)
    one_error_line(cli("positioning", p), "run order", "neither increasing nor decreasing", "--forward-direction + or -")
    shuffled = json.loads(cli("positioning", p, "--forward-direction", "-", "--json").stdout)
    ordered = json.loads(cli("positioning", q, "--json").stdout)
    for k in ("A", "B_mean", "E", "R", "M"):
        assert shuffled[k] == pytest.approx(ordered[k], abs=1e-12)
    assert any("as --forward-direction - says" in n for n in shuffled["notes"])


def test_forward_direction_overrides_and_is_refused_where_it_means_nothing(tmp_path):
    p = tmp_path / "z.txt"
    truth = z_export(p)
    flipped = json.loads(cli("positioning", p, "--forward-direction", "+", "--json").stdout)
    assert flipped["B_mean"] == pytest.approx(-truth, abs=1e-7)
    long = tmp_path / "long.csv"
    long.write_text("target,direction,run,deviation\n" + "".join(
        f"{t},{d},{r},{0.001 * r}\n" for t in (0, 100, 200) for d in "+-" for r in (1, 2)))
    one_error_line(cli("positioning", long, "--forward-direction", "+"), "--forward-direction applies to",
                   "Forward/Reverse")
