"""The coarse-interval guard checks each format as its controller applies the table: linearly between the points
(SINUMERIK) or stepwise (FANUC pitch-error compensation: the value of the point on the reference position's side held
over each interval). Before, it interpolated every format linearly, and ``--interval 500`` on a 1000 mm axis with 11
targets was written for FANUC: three points for a 20 µm curve, missing it by 10.5 µm at the targets in the simulated
controller (the SINUMERIK table of the same step missed by 1 µm)."""
from __future__ import annotations

import re

import numpy as np
import pytest

import methods
from cli_calls import cli, one_error_line
from compensation_controllers import READERS
from datasets.positioning import axis_test, to_frame
from fitbench.compensation import REPRESENT_SHARE, CompensationError, write_tables
from methods.positioning.model import evaluate_band


def axis():
    data, truth = axis_test(rng=np.random.default_rng(2), pitch=(0.0, 0.030, -0.010, 0.0), reversal=0.0,
                            repeatability=0.0005)
    return data, truth, methods.fit("positioning.gls_polynomial", data)


def residual_at_targets(text: str, fmt: str, res, data) -> float:
    """Largest |model + the controller's compensation| at the targets, relative to its value at the reference point:
    what the controller (tests/compensation_controllers.py, written from the manuals) leaves of the curve."""
    encoder, _ = READERS[fmt](text)
    P = data.targets
    curve = np.mean([evaluate_band(res.polynomial[d], P)[0] for d in ("up", "down")], axis=0)
    correction = np.mean([encoder(P, d) for d in ("up", "down")], axis=0) - P        # the backlash halves cancel
    left = curve + correction
    return float(np.max(np.abs(left - left[0]))), float(np.ptp(curve))


@pytest.mark.parametrize("interval", [500.0, 333.333, 250.0, 200.0, 125.0, 100.0, 50.0])
def test_every_fanuc_table_written_reproduces_the_curve_in_the_simulated_controller(interval):
    """Whatever --interval asks, a FANUC tape is written only if the simulated FANUC controller, applying it
    stepwise, follows the model at the targets within the guard's bound (one detection unit of rounding aside)."""
    data, _, res = axis()
    out = {}
    try:
        write_tables(res, data, [("fanuc-pitch", "f")], axis="X1", interval=interval, unit_confirmed=True,
                     write=out.__setitem__)
    except CompensationError as exc:
        assert "applied stepwise as the FANUC does" in str(exc) and "give --interval" in str(exc)
        return
    left, span = residual_at_targets(out["f"], "fanuc-pitch", res, data)
    assert left <= REPRESENT_SHARE * span + 0.001, (interval, left, span)


def test_a_coarse_fanuc_interval_is_refused_naming_one_the_fanuc_follows(tmp_path):
    data, _, res = axis()
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    args = ("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X1")
    # the SINUMERIK interpolates the 500 mm table and follows the curve: written
    assert cli(*args, "--interval", "500mm", "--compensation", "siemens-eec", tmp_path / "t.mpf").returncode == 0
    out = cli(*args, "--interval", "500mm", "--compensation", "fanuc-pitch", tmp_path / "t.tap")
    one_error_line(out, "--interval 500 mm is too coarse: the table for fanuc-pitch, applied stepwise")
    assert not (tmp_path / "t.tap").exists()
    miss, span = (float(v) for v in re.search(r"misses the model at the targets by up to (\S+) µm of the (\S+) µm",
                                              out.stderr).groups())
    named = float(re.search(r"give --interval (\S+) or finer", out.stderr).group(1))
    assert cli(*args, "--interval", named, "--compensation", "fanuc-pitch", tmp_path / "t.tap").returncode == 0
    left, span_ = residual_at_targets((tmp_path / "t.tap").read_text(), "fanuc-pitch", res, data)
    assert left <= REPRESENT_SHARE * span_ + 0.001 < miss * 1e-3, (left, miss)
