"""A controller table is written only from deviations whose unit is stated (``fitbench positioning --compensation``):
a laser export with no unit anywhere, µm deviations of a well-compensated or a long axis, passes every plausibility
bound read as mm (±0.8 µm on a 1 m axis is below 0.1 % of the travel), and the SINUMERIK / FANUC tables came out
1000x too large, exit 0. Without the header's unit or --deviation-unit: one line, exit 2, no file."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from compensation_controllers import READERS
from fitbench.compensation import WRITERS

RUNS = 5


def unitless_export(path, targets, amplitude_um, period_mm, seed, header_unit=""):
    """A wide laser export ``Target;Run 1 +;Run 1 -;...`` of a good axis, deviations in µm (amplitude_um sin +
    a 0.2 µm reversal), no unit in the header unless ``header_unit`` (e.g. ' (µm)') is appended to the runs.
    Returns the values (targets x runs x 2) in µm as written."""
    rng = np.random.default_rng(seed)
    e = amplitude_um * np.sin(2 * np.pi * targets / period_mm)
    values = e[:, None, None] + np.array([0.1, -0.1])[None, None, :] + rng.normal(0, 0.05, (len(targets), RUNS, 2))
    values = np.round(values, 3)
    head = "Target;" + ";".join(f"Run {r} {d}{header_unit}" for r in range(1, RUNS + 1) for d in "+-")
    rows = [f"{t:.1f};" + ";".join(f"{v:.3f}" for v in values[i].ravel()) for i, t in enumerate(targets)]
    path.write_text("\n".join([head, *rows]) + "\n", encoding="utf-8")
    return values


PRECISE = dict(targets=np.array([0, 97.5, 203.1, 299.4, 402.8, 501.2, 598.7, 702.3, 797.9, 901.6, 1000.0]),
               amplitude_um=0.8, period_mm=1000.0, seed=6)      # a 1 m linear-scale axis, ±0.8 µm
LONG = dict(targets=np.linspace(0.0, 3000.0, 16), amplitude_um=2.0, period_mm=6000.0, seed=5)   # 3 m, 0-2 µm


@pytest.mark.parametrize("axis", [PRECISE, LONG], ids=["precise-1m", "long-3m"])
@pytest.mark.parametrize("fmt", list(WRITERS))
def test_unitless_deviations_write_no_controller_table(tmp_path, axis, fmt):
    unitless_export(tmp_path / "a.csv", **axis)
    out = cli("positioning", tmp_path / "a.csv", "--axis", "X1", "--compensation-from", "mean", "--compensation", fmt,
              tmp_path / "t.txt")
    one_error_line(out, "not writing", "t.txt", "unit is not stated", "a.csv", "--deviation-unit um")
    assert not (tmp_path / "t.txt").exists() and out.stdout == ""


def test_the_figures_are_still_printed_with_a_note(tmp_path):
    """Without --compensation the evaluation runs as before (read as mm) and says the unit was not stated."""
    unitless_export(tmp_path / "a.csv", **PRECISE)
    out = cli("positioning", tmp_path / "a.csv")
    assert out.returncode == 0 and "deviation columns name no unit: read as mm" in out.stdout
    js = json.loads(cli("positioning", tmp_path / "a.csv", "--json").stdout)
    assert any("name no unit" in n for n in js["notes"]) and js["units"]["input_deviation_unit"] == "mm"


@pytest.mark.parametrize("how", ["option", "header"])
@pytest.mark.parametrize("fmt", list(WRITERS))
def test_a_stated_unit_writes_the_micrometre_table(tmp_path, how, fmt):
    """--deviation-unit um, or the unit in the header, writes the table; its values at the targets are the
    means minus the mean at the reference point (0 mm), and its backlash entry -B, computed here from the file
    with NumPy: µm-level, not mm."""
    values = unitless_export(tmp_path / "a.csv", **LONG, header_unit=" (µm)" if how == "header" else "")
    extra = ["--deviation-unit", "um"] if how == "option" else []
    out = cli("positioning", tmp_path / "a.csv", *extra, "--axis", "X1", "--compensation-from", "mean", "--compensation", fmt,
              tmp_path / "t.txt")
    assert out.returncode == 0 and "Traceback" not in out.stderr, out.stderr
    encoder, info = READERS[fmt]((tmp_path / "t.txt").read_text())
    means_mm = values.mean(axis=(1, 2)) * 1e-3
    expected = -(means_mm - means_mm[0])                        # the table compensates the mean deviation
    B_mm = float(np.mean(values[:, :, 0].mean(axis=1) - values[:, :, 1].mean(axis=1))) * 1e-3
    # what the simulated controller does at each target: moves the encoder by the table's value (+ half of -B)
    applied = np.array([encoder(t, "up") - t for t in LONG["targets"]]) + 0.5 * B_mm
    resolution = 1e-3 if fmt == "fanuc-pitch" else 1e-6                       # FANUC: 1 µm detection units
    np.testing.assert_allclose(applied, expected, atol=resolution * 1.01)
    assert np.max(np.abs(applied)) < 0.005                                    # mm: a few µm, not a few mm
