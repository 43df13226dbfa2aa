"""The machine's reference point outside the measured travel (ISO 230-2 leaves the travel ends out, and the
reference point of a machine is usually at one): the table is anchored there, holds 0 from it to the nearer target
and says so. Before: ``--reference 0`` on a test measured from 60 to 960 mm was refused, and the FANUC tape could
only be anchored at a target, so on the machine (whose sections start at its reference position) every section was
shifted by the gap."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import methods
from cli_calls import cli
from compensation_controllers import READERS, read_fanuc, remeasure
from datasets.positioning import axis_test, to_frame

TRAVEL = (60.0, 960.0)      # the laser could not get within 60 mm of the travel ends; the reference point is at 0


def axis(seed=3):
    return axis_test(rng=np.random.default_rng(seed), travel=TRAVEL, targets=10, pitch=(0.0, 0.040, -0.060, 0.030),
                     reversal=0.0, repeatability=0.0003)


@pytest.mark.parametrize("fmt", ["fanuc-pitch", "siemens-eec", "csv"])
def test_a_reference_point_outside_the_travel_anchors_the_table(tmp_path, fmt):
    data, truth = axis()
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X1", "--reference", "0mm",
              "--compensation", fmt, tmp_path / "t.txt", "--compensation", "csv", tmp_path / "t.csv")
    assert out.returncode == 0, out.stderr
    said = "the reference point lies 60 mm before the first target, outside the measured travel"
    assert said in out.stdout and "held at the model's value at the 60 mm target (not extrapolated)" in out.stdout
    text = (tmp_path / "t.txt").read_text()
    assert said.upper() in text.upper()
    table = pd.read_csv(tmp_path / "t.csv", comment="#")
    assert table.position_mm.iloc[0] == 0.0 and table.compensation_mm.iloc[0] == 0.0
    np.testing.assert_array_equal(table.compensation_mm[table.position_mm <= TRAVEL[0]], 0.0)   # held from R
    # the controller anchors the FANUC sections at the machine's reference position, 0 mm, whatever the tape says
    reader = (lambda t: read_fanuc(t, machine_reference_mm=0.0)) if fmt == "fanuc-pitch" else READERS[fmt]
    encoder, _ = reader(text)
    before = methods.fit("positioning.iso230_2", data).figures
    after = methods.fit("positioning.iso230_2", remeasure(data, truth, encoder, np.random.default_rng(9))).figures
    assert after["M"] <= 0.5 * before["M"] and after["E"] <= 0.5 * before["E"], (before, after)


def test_without_a_reference_a_fanuc_table_says_where_it_is_anchored(tmp_path):
    data, _ = axis()
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X1",
              "--compensation", "fanuc-pitch", tmp_path / "t.tap")
    assert out.returncode == 0, out.stderr
    assert "the reference point is taken at the nearer end target, 60 mm" in out.stdout
    assert "give --reference where it is" in out.stdout
