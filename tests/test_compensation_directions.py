"""Tables per direction (``--compensation-directions both``): where the reversal B_i varies along the travel, the mean
table with one backlash leaves (B_i - B mean)/2 in each direction; a controller that takes a table per direction
(FANUC bidirectional pitch-error compensation; any controller fed the csv's compensation_up_mm / compensation_down_mm)
removes it. Each tape or file is read back by the simulated controller (tests/compensation_controllers.py: a strict
parser and the manual's rule, each direction's table applied when the axis approaches in that direction) and the
compensated axis is evaluated against the true error curves it was simulated from."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import methods
from cli_calls import cli, one_error_line
from compensation_controllers import read_csv, read_fanuc
from fitbench.compensation import REPRESENT_SHARE, CompensationError, compensation_table, write_tables
from methods.positioning.data import PositioningData

READ = {"csv": read_csv, "fanuc-pitch": read_fanuc}


def reversal_axis(b_start_um, b_end_um, seed=3, travel=(0.0, 1000.0), targets=11, runs=5):
    """An ISO 230-2 test of an axis whose reversal x_up - x_down runs linearly from ``b_start_um`` to ``b_end_um``
    along the travel, on a 30 µm-scale pitch error with curvature, 0.5 µm repeatability: (data, truth)."""
    rng = np.random.default_rng(seed)
    lo, hi = travel
    P = np.linspace(lo, hi, targets)

    def base(x):
        u = (np.asarray(x, float) - lo) / (hi - lo)
        return 0.030 * u - 0.020 * u ** 2 + 0.010 * u ** 3

    def B(x):
        return 1e-3 * (b_start_um + (b_end_um - b_start_um) * (np.asarray(x, float) - lo) / (hi - lo))
    truth = {"up": lambda x: base(x) + B(x) / 2, "down": lambda x: base(x) - B(x) / 2, "delta": 0.0}
    runs_of = {d: truth[d](P)[:, None] + rng.normal(0.0, 0.0005, (targets, runs)) for d in ("up", "down")}
    return PositioningData(targets=P, up=runs_of["up"], down=runs_of["down"], unit="mm"), truth


def tables(data, fmt, per_direction, **kw):
    """The text written for ``fmt`` (all checks of write_tables, as the command makes them)."""
    res = methods.fit("positioning.gls_polynomial", data)
    out = {}
    write_tables(res, data, [(fmt, "t")], axis="X", write=out.__setitem__, per_direction=per_direction,
                 unit_confirmed=True, model_confirmed=True, **kw)
    return out["t"]


def left(text, fmt, per_direction, data, truth, **reader):
    """What the compensated axis deviates at the targets, per direction (mm, noise-free): the true error where the
    controller puts it plus the controller's correction."""
    encoder, _ = (read_csv(text, per_direction) if fmt == "csv" else read_fanuc(text, **reader))
    P = data.targets
    return {d: truth[d](encoder(P, d)) + (encoder(P, d) - P) for d in ("up", "down")}


def figures(lf):
    """(E_up, E_down, the reversal left: the span of x_up - x_down), µm."""
    return (1e3 * np.ptp(lf["up"]), 1e3 * np.ptp(lf["down"]), 1e3 * np.ptp(lf["up"] - lf["down"]))


@pytest.mark.parametrize("source", ["model", "mean"])
@pytest.mark.parametrize("fmt", ["csv", "fanuc-pitch"])
@pytest.mark.parametrize("seed", [3, 4, 5])
def test_tables_per_direction_remove_a_reversal_that_varies_along_the_travel(fmt, source, seed):
    """Reversal from -2 to -10 µm over 1000 mm: the mean table and -B mean leave (B_i - B mean)/2 in each direction
    (E per direction 3-6 µm, x_up - x_down still spanning 8 µm); the tables per direction leave the model's or the
    means' scatter and the FANUC's 1 µm detection unit (at most 1.5 µm, about a fifth of it)."""
    data, truth = reversal_axis(-2.0, -10.0, seed)
    mean_up, mean_down, mean_rev = figures(left(tables(data, fmt, False, source=source), fmt, False, data, truth))
    up, down, rev = figures(left(tables(data, fmt, True, source=source), fmt, True, data, truth))
    assert min(mean_up, mean_down) > 2.5 and mean_rev > 7.5, (mean_up, mean_down, mean_rev)
    assert max(up, down, rev) <= 1.5 + (1.0 if fmt == "fanuc-pitch" else 0.0), (up, down, rev)
    assert up <= 0.4 * mean_up and down <= 0.4 * mean_down and rev <= 0.25 * mean_rev


@pytest.mark.parametrize("source", ["model", "mean"])
@pytest.mark.parametrize("fmt", ["csv", "fanuc-pitch"])
def test_with_a_constant_reversal_both_compensate_alike(fmt, source):
    """Reversal -4 µm everywhere: the tables per direction are the mean table -/+ B mean / 2 up to the measured
    reversal's scatter ((B_i - B mean)/2 at the targets), and the axes compensated either way differ by no more than
    that (and the FANUC's rounding to its detection unit, one unit per table)."""
    from methods.positioning.iso230_2 import reversal_variation
    data, truth = reversal_axis(-4.0, -4.0, seed=6)
    assert not reversal_variation(data)["significant"]
    res = methods.fit("positioning.gls_polynomial", data)
    t = compensation_table(res, data, source=source, per_direction=True)
    B = data.up.mean(axis=1) - data.down.mean(axis=1)
    scatter = np.max(np.abs(B - B.mean())) / 2
    if source == "mean":              # at the targets exactly -(B_i - B mean)/2 off the mean table -/+ B mean / 2
        at = np.isin(t.position_mm, data.targets)
        np.testing.assert_allclose((t.compensation_up_mm - t.compensation_mm + B.mean() / 2)[at], -(B - B.mean()) / 2,
                                   atol=1e-12)
    assert np.max(np.abs(t.compensation_up_mm - t.compensation_mm + B.mean() / 2)) <= scatter + 1e-6
    assert np.max(np.abs(t.compensation_down_mm - t.compensation_mm - B.mean() / 2)) <= scatter + 1e-6
    mean = left(tables(data, fmt, False, source=source), fmt, False, data, truth)
    both = left(tables(data, fmt, True, source=source), fmt, True, data, truth)
    rounding = 0.002 if fmt == "fanuc-pitch" else 1e-6
    for d in ("up", "down"):
        assert np.ptp(both[d] - mean[d]) <= 2 * scatter + rounding, d


def test_the_csv_columns_per_direction_relative_to_the_reference():
    """compensation_up_mm / _down_mm = -(x_up / x_down - x mean at R): their mean is compensation_mm, and at R they
    are -/+ B(R)/2; the default columns are unchanged."""
    data, _ = reversal_axis(-2.0, -10.0)
    res = methods.fit("positioning.gls_polynomial", data)
    t = compensation_table(res, data, per_direction=True)
    k0 = t.attrs["reference_index"]
    np.testing.assert_allclose((t.compensation_up_mm + t.compensation_down_mm) / 2, t.compensation_mm, atol=1e-15)
    np.testing.assert_allclose(t.compensation_up_mm, -(t.deviation_up_mm - t.deviation_mm[k0]), atol=1e-15)
    assert t.compensation_up_mm[k0] - t.compensation_down_mm[k0] == pytest.approx(
        -(t.deviation_up_mm[k0] - t.deviation_down_mm[k0]), abs=1e-15)
    text = tables(data, "csv", True)
    frame = pd.read_csv(pd.io.common.StringIO(text), comment="#")
    assert list(frame.columns)[-2:] == ["compensation_up_mm", "compensation_down_mm"]
    np.testing.assert_allclose(frame.compensation_up_mm, t.compensation_up_mm, atol=5e-7)
    assert "enter the backlash as -B" in text and "(a table per direction) enter none" in text
    assert list(compensation_table(res, data).columns) == ["position_mm", "deviation_mm", "deviation_up_mm",
                                                           "deviation_down_mm", "compensation_mm"]


def test_the_fanuc_bidirectional_tape():
    """Positive direction at 3621 ... 3622 as the unidirectional tape, the negative direction's block right after it
    (3626 = 3622 + 1), 3627 the negative direction's value at R (reference return in the positive direction), no
    backlash; with the reference return in the negative direction the roles swap and the axis is compensated alike."""
    data, truth = reversal_axis(-2.0, -10.0)
    text = tables(data, "fanuc-pitch", True, interval=100.0)
    _, info = read_fanuc(text)
    assert info["p3626"] == 11 and list(info["numbers"]) == list(range(22))
    res = methods.fit("positioning.gls_polynomial", data)
    t = compensation_table(res, data, interval=100.0, per_direction=True)
    k0 = t.attrs["reference_index"]
    assert info["p3627"] == round(1e3 * -(t.deviation_down_mm[k0] - t.deviation_up_mm[k0]))
    up_only = tables(data, "fanuc-pitch", False, interval=100.0)
    assert "SET 1851 = 0" in text and "NOT CONFIRMED FROM A MANUAL PAGE" in text and "SET 1851 = 0" not in up_only
    down_first = tables(data, "fanuc-pitch", True, interval=100.0, fanuc_reference_return="down")
    assert "REFERENCE RETURN IN THE NEGATIVE DIRECTION" in down_first
    a = figures(left(text, "fanuc-pitch", True, data, truth))
    b = figures(left(down_first, "fanuc-pitch", True, data, truth))
    assert max(a) <= 2.0 and max(b) <= 2.0, (a, b)


def test_a_reference_point_outside_the_travel_anchors_both_tables():
    """Measured from 60 to 960 mm, the machine's reference position at 0: both FANUC blocks are anchored there (the
    simulated controller anchors them at the machine's reference, whatever the tape says) and remove the varying
    reversal; the csv's columns hold 0 -/+ B(first target)/2 from R to the first target."""
    data, truth = reversal_axis(-2.0, -10.0, travel=(60.0, 960.0), targets=11)
    mean = figures(left(tables(data, "fanuc-pitch", False, reference_mm=0.0, interval=30.0), "fanuc-pitch", False,
                        data, truth, machine_reference_mm=0.0))
    both = figures(left(tables(data, "fanuc-pitch", True, reference_mm=0.0, interval=30.0), "fanuc-pitch", True,
                        data, truth, machine_reference_mm=0.0))
    assert max(both) <= 2.0 and both[2] <= 0.25 * mean[2], (mean, both)
    frame = pd.read_csv(pd.io.common.StringIO(tables(data, "csv", True, reference_mm=0.0, interval=30.0)), comment="#")
    before = frame[frame.position_mm <= 60.0]
    assert before.compensation_mm.abs().max() == 0.0
    assert np.ptp(before.compensation_up_mm) == 0.0 and np.ptp(before.compensation_down_mm) == 0.0


@pytest.mark.parametrize("interval", [500.0, 250.0, 200.0, 100.0, 50.0])
def test_every_bidirectional_tape_written_follows_each_direction(interval):
    """The coarse-interval guard checks each direction's table as the FANUC applies it (stepwise): a tape is written
    only if each direction's compensated curve stays within the guard's bound of that direction's model at the
    targets (one detection unit of rounding aside), else one line names a step that does."""
    data, truth = reversal_axis(-2.0, -10.0)
    res = methods.fit("positioning.gls_polynomial", data)
    try:
        text = tables(data, "fanuc-pitch", True, interval=interval)
    except CompensationError as exc:
        assert "applied stepwise as the FANUC does" in str(exc) and "give --interval" in str(exc)
        return
    from methods.positioning.model import evaluate_band
    encoder, _ = read_fanuc(text)
    P = data.targets
    at_r = evaluate_band(res.polynomial["up"], P[:1])[0][0]     # both tables relative to x_up at R = 0 mm
    for d in ("up", "down"):
        curve = evaluate_band(res.polynomial[d], P)[0]
        miss = np.max(np.abs(curve + (encoder(P, d) - P) - at_r))
        assert miss <= REPRESENT_SHARE * np.ptp(curve) + 0.001, (interval, d, miss)


# ------------------------------------------------------------------------------------------------- the command
def axis_file(tmp_path, b_end_um=-10.0):
    data, _ = reversal_axis(-2.0, b_end_um)
    rows = [(t, s, r + 1, 1e3 * getattr(data, d)[i, r]) for d, s in (("up", "+"), ("down", "-"))
            for i, t in enumerate(data.targets) for r in range(data.runs)]
    path = tmp_path / "bidir.csv"
    pd.DataFrame(rows, columns=["Target (mm)", "Direction", "Run", "Deviation (um)"]).to_csv(path, index=False)
    return path


def test_the_command_writes_tables_per_direction(tmp_path):
    f = axis_file(tmp_path)
    out = cli("positioning", f, "--axis", "X", "--compensation-directions", "both", "--compensation", "csv",
              tmp_path / "t.csv", "--compensation", "fanuc-pitch", tmp_path / "t.tap", "--json")
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)["compensation"]
    assert got["directions"] == "both" and got["tables"][1]["fanuc_points"]["p3626"] == got["tables"][1][
        "fanuc_points"]["p3622"] + 1
    assert "reversal B_i varies" not in out.stderr                     # the tables hold it: a note, not a warning
    assert any("the tables of the two directions hold it" in n for n in json.loads(out.stdout)["notes"])
    assert "compensation_up_mm" in (tmp_path / "t.csv").read_text()
    assert "SET 3605 BIT 0 = 1" in (tmp_path / "t.tap").read_text()


def test_the_default_is_the_mean_table_byte_for_byte(tmp_path):
    f = axis_file(tmp_path)
    base = ("positioning", f, "--axis", "X")
    for name, extra in (("a", ()), ("b", ("--compensation-directions", "mean"))):
        out = cli(*base, *extra, "--compensation", "csv", tmp_path / f"{name}.csv", "--compensation", "fanuc-pitch",
                  tmp_path / f"{name}.tap", "--compensation", "siemens-eec", tmp_path / f"{name}.mpf")
        assert out.returncode == 0, out.stderr
        assert "write a table per direction with --compensation-directions both" in out.stderr
    for ext in ("csv", "tap", "mpf"):
        assert (tmp_path / f"a.{ext}").read_bytes() == (tmp_path / f"b.{ext}").read_bytes()
    assert "compensation_up_mm" not in (tmp_path / "a.csv").read_text()


def test_what_cannot_have_tables_per_direction_is_refused_in_one_line(tmp_path):
    f = axis_file(tmp_path)
    out = cli("positioning", f, "--axis", "X1", "--compensation-directions", "both", "--compensation", "csv",
              tmp_path / "t.csv", "--compensation", "siemens-eec", tmp_path / "t.mpf")
    one_error_line(out, "siemens-eec: a SINUMERIK LEC table ($AA_ENC_COMP) holds one curve",
                   "write siemens-eec without --compensation-directions both")
    assert not (tmp_path / "t.csv").exists() and not (tmp_path / "t.mpf").exists()
    out = cli("positioning", f, "--compensation-directions", "both")
    one_error_line(out, "--compensation-directions applies to a compensation table")
    out = cli("positioning", f, "--fanuc-reference-return", "down", "--compensation", "fanuc-pitch", tmp_path / "t.tap")
    one_error_line(out, "--fanuc-reference-return applies to a FANUC tape per direction")
    assert not (tmp_path / "t.tap").exists()
    one = tmp_path / "up.csv"
    frame = pd.read_csv(f)
    frame[frame.Direction == "+"].to_csv(one, index=False)
    out = cli("positioning", one, "--axis", "X", "--compensation-directions", "both", "--compensation", "csv",
              tmp_path / "u.csv")
    one_error_line(out, "--compensation-directions both needs a bidirectional test and this one has only the up "
                        "direction: drop --compensation-directions")
    assert not (tmp_path / "u.csv").exists()
