"""An inch test written as a FANUC tape for an inch machine: the values, the interval 3624 and the backlash 1851 are
counts of the machine's 0.0001 in, the absolute curve rounded once (not each increment). Before: the tape was in
0.001 mm (3624 = 101600 for a 4 in interval, i.e. 10.16 in on an inch machine, the table stretched 2.54 times) with a
note to divide the point values by 2.54, which rounds each increment and accumulates a count of error."""
from __future__ import annotations

import re

import numpy as np

import methods
from cli_calls import cli
from compensation_controllers import read_fanuc, remeasure
from datasets.positioning import axis_test, to_frame
from methods.positioning.model import evaluate_band

INCH = 25.4
COUNT = 0.0001 * INCH          # the inch machine's detection unit and least input increment (IS-B), mm


def test_an_inch_machine_tape_counts_its_own_units_and_rounds_the_whole_curve(tmp_path):
    data, truth = axis_test(rng=np.random.default_rng(7), travel=(0.0, 40 * INCH), pitch=(0.0, -0.016, 0.030, -0.004),
                            reversal=-0.004, repeatability=0.0004)
    df = to_frame(data, actual=False)
    df["target"] /= INCH
    df.columns = ["Target (in)", "Direction", "Run", "Deviation (mm)"]
    df.to_csv(tmp_path / "inch.csv", index=False)
    out = cli("positioning", tmp_path / "inch.csv", "--axis", "X", "--fanuc-increment", "0.0001in",
              "--compensation", "fanuc-pitch", tmp_path / "t.tap")
    assert out.returncode == 0, out.stderr
    text = (tmp_path / "t.tap").read_text()
    # 3624: the 4 in interval in counts of 0.0001 in; 1851: -B in counts of 0.0001 in
    assert re.search(r"3624 = 40000 I\.E\. 101\.600000 MM", text), text
    iso = methods.fit("positioning.iso230_2", data).figures
    assert f"SET 1851 = {int(np.rint(-iso['B_mean'] / COUNT))} DETECTION UNITS OF 0.0001 IN" in text
    # the increments sum to the model's curve rounded once in counts of 0.0001 in, at every point
    res = methods.fit("positioning.gls_polynomial", data)
    grid = np.arange(11) * 4 * INCH
    curve = np.mean([evaluate_band(res.polynomial[d], grid)[0] for d in ("up", "down")], axis=0)
    wanted = np.rint(-(curve - curve[0]) / COUNT)
    increments = [int(v) for v in re.findall(r"^N1\d{4} P(-?\d+)$", text, re.M)]
    np.testing.assert_array_equal(np.cumsum(increments), wanted)
    # an inch machine (3624 and the values in its own counts) applying the tape halves the error
    encoder, _ = read_fanuc(text, detection_unit_mm=COUNT, increment_mm=COUNT)
    after = methods.fit("positioning.iso230_2", remeasure(data, truth, encoder, np.random.default_rng(9))).figures
    assert after["M"] <= 0.5 * iso["M"] and after["E"] <= 0.5 * iso["E"], (iso, after)


def test_an_inch_test_asks_which_machine_the_tape_is_for(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(7), travel=(0.0, 40 * INCH))
    df = to_frame(data, actual=False)
    df["target"] /= INCH
    df.columns = ["Target (in)", "Direction", "Run", "Deviation (mm)"]
    df.to_csv(tmp_path / "inch.csv", index=False)
    out = cli("positioning", tmp_path / "inch.csv", "--axis", "X", "--compensation", "fanuc-pitch", tmp_path / "t.tap")
    assert out.returncode == 2 and "--fanuc-increment 0.0001in for an inch machine" in out.stderr
    assert not (tmp_path / "t.tap").exists()
    # a metric machine tested in inches: the tape in 0.001 mm, as said
    out = cli("positioning", tmp_path / "inch.csv", "--axis", "X", "--fanuc-increment", "0.001mm",
              "--compensation", "fanuc-pitch", tmp_path / "t.tap")
    assert out.returncode == 0 and "3624 = 101600 I.E. 101.600000 MM IN UNITS OF 0.001 MM" in (tmp_path / "t.tap").read_text()
    assert "the fanuc-pitch tape is for a metric machine" in out.stdout
