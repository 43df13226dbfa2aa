"""Controller compensation tables (fitbench.compensation) and the ``fitbench positioning --compensation`` door.

Every format is read back by a strict parser of its grammar and applied by the manual's rule in a
simulated controller (tests/compensation_controllers.py); the compensated axis is measured again."""
from __future__ import annotations

import re
from decimal import Decimal

import numpy as np
import pandas as pd
import pytest

import methods
from cli_calls import cli
from compensation_controllers import READERS, read_csv, read_fanuc, read_siemens, remeasure
from datasets.positioning import axis_test, to_frame
from fitbench.compensation import WRITERS, CompensationError, compensation_table, write_fanuc_pitch, write_siemens_eec
from methods import InvalidInputError
from methods.positioning.model import evaluate_band

FORMATS = list(WRITERS)
PITCH = (0.0, 0.030, -0.020, 0.010)     # mm over the relative position: a 30 um/m-ish scale error with curvature


def axis(seed=2, **kw):
    kw = {"pitch": PITCH, "reversal": -0.004, "repeatability": 0.0005, **kw}
    data, truth = axis_test(rng=np.random.default_rng(seed), **kw)
    return data, truth, methods.fit("positioning.gls_polynomial", data)


def test_compensation_tables(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(2), mpe=0.002)
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--mpe", 0.002, "--interval", 25, "--axis", "X1", "--compensation", "csv",
              tmp_path / "c.csv", "--compensation", "siemens-eec", tmp_path / "eec.mpf", "--compensation", "fanuc-pitch",
              tmp_path / "f.txt")
    assert out.returncode == 0, out.stderr
    res = methods.fit("positioning.gls_polynomial", data, mpe=0.002)
    pos = np.arange(0, 1000.0 + 1e-9, 25.0)
    mean = 0.5 * (evaluate_band(res.polynomial["up"], pos)[0] + evaluate_band(res.polynomial["down"], pos)[0])
    rel = mean - mean[0]                                   # the reference point is position 0, the first target
    csv = pd.read_csv(tmp_path / "c.csv", comment="#")
    np.testing.assert_allclose(csv.position_mm, pos)
    np.testing.assert_allclose(csv.deviation_mm, mean, atol=1e-6)
    np.testing.assert_allclose(csv.compensation_mm, -rel, atol=1e-6)
    eec = (tmp_path / "eec.mpf").read_text().splitlines()
    assert eec[0] == "%_N_AX_EEC_INI" and eec[-1] == "M17" and "CHANDATA(1)" in eec
    vals = [float(l.split("=")[1]) for l in eec if l.startswith("$AA_ENC_COMP[0,")]
    np.testing.assert_allclose(vals, rel, atol=1e-6)       # SINUMERIK holds +deviation
    assert "$AA_ENC_COMP_STEP[0,X1]=25.000000" in eec and "$AA_ENC_COMP_MAX[0,X1]=1000.000000" in eec
    _, info = read_fanuc((tmp_path / "f.txt").read_text())
    absolute = np.cumsum(info["values"][1:])               # point 0 is the reference's, then one per section
    np.testing.assert_allclose(absolute, -rel[1:], atol=0.5e-3 + 1e-12)   # 1 um detection unit
    mean_table = compensation_table(res, data, interval=100.0, source="mean")
    xm = res.per_target["mean_bidirectional"]
    np.testing.assert_allclose(mean_table.compensation_mm, -(xm - xm[0]), atol=1e-12)


def test_methods_does_not_import_the_controller_export():
    """Layers run one way: the algorithms never import the fitbench layer's controller export."""
    import pathlib
    root = pathlib.Path(methods.__file__).parent
    offenders = [str(p.relative_to(root)) for p in root.rglob("*.py")
                 if re.search(r"fitbench\.compensation|import compensation|positioning\.compensation", p.read_text())]
    assert offenders == []
    assert not (root / "positioning" / "compensation.py").exists()


# ----------------------------------------------------------------------------------------- coverage
@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("interval", [None, 30.0])
def test_table_covers_the_measured_travel_and_says_so(seed, interval):
    """Irregular targets (ISO 230-2 practice): the first point is at or before the first target, the last
    at or after the last target, extended by less than one step (by at most 0.001 mm per step when the
    step is chosen), and every file's header names the range."""
    data, _, res = axis(seed, travel=(0.0, 2000.0), targets=13, irregular=0.4)
    t = compensation_table(res, data, interval=interval)
    first, last = data.targets[0], data.targets[-1]
    lo, hi, step = t.position_mm.iloc[0], t.position_mm.iloc[-1], t.attrs["interval_mm"]
    assert lo <= first + 1e-12 and hi >= last - 1e-12
    assert hi - last < (0.001 * (len(t) - 1) + 1e-9 if interval is None else step)
    if interval is None:
        assert step <= np.min(np.diff(data.targets)) + 1e-12
    for fmt, w in WRITERS.items():
        text = w(t, axis="X1")
        assert re.search(rf"covers {lo:.6f} to {hi:.6f} mm", text, re.I), fmt
        assert re.search(r"measured travel 0 to 2000 mm", text, re.I), fmt


def test_step_gives_max_exactly_as_printed():
    """MIN + STEP (n - 1) = MAX in the printed decimals (the SINUMERIK computes the end from them)."""
    for seed in range(6):
        data, _, res = axis(seed, travel=(-12.345, 987.655), targets=9, irregular=0.45)
        for interval in (None, 7.3, 0.123457):
            t = compensation_table(res, data, interval=interval)
            if len(t) > 200:
                continue
            text = write_siemens_eec(t, axis="X1")
            get = {k: Decimal(re.search(rf"\$AA_ENC_COMP_{k}\[0,X1\]=(\S+)", text).group(1)) for k in ("STEP", "MIN", "MAX")}
            n = len(re.findall(r"^\$AA_ENC_COMP\[0,", text, re.M))
            assert get["MIN"] + get["STEP"] * (n - 1) == get["MAX"]
            assert get["MIN"] <= Decimal(float(data.targets[0])) and get["MAX"] >= Decimal(float(data.targets[-1]))


# --------------------------------------------------------------------------------- simulated controllers
@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("layout", ["regular", "irregular", "around-reference", "negative-travel"])
@pytest.mark.parametrize("interval", [None, 20.0])
def test_simulated_controller_at_least_halves_the_error(fmt, layout, interval):
    """The file, read by a strict parser and applied by the manual's rule (with the backlash the header
    asks for), at least halves E (ISO 230-2 systematic positioning error) and M (range of the mean
    bidirectional deviation) of the re-measured axis."""
    kw = {"regular": {}, "irregular": {"irregular": 0.4}, "around-reference": {"travel": (-400.0, 800.0), "irregular": 0.4},
          "negative-travel": {"travel": (-800.0, 0.0), "irregular": 0.3}}[layout]
    data, truth, res = axis(3, **kw)
    before = methods.fit("positioning.iso230_2", data).figures
    encoder, _ = READERS[fmt](WRITERS[fmt](compensation_table(res, data, interval=interval), axis="X1"))
    after = methods.fit("positioning.iso230_2", remeasure(data, truth, encoder, np.random.default_rng(9))).figures
    assert after["E"] <= 0.5 * before["E"], (before["E"], after["E"])
    assert after["M"] <= 0.5 * before["M"], (before["M"], after["M"])


def test_siemens_sign_follows_the_manual():
    """808D / 840D K3: a positive value moves the axis in the negative direction, so an axis that goes
    too far (deviation > 0) gets positive values."""
    data, _, res = axis(1, pitch=(0.0, 0.020), reversal=0.0)           # deviation grows to +20 um
    _, info = read_siemens(write_siemens_eec(compensation_table(res, data), axis="X1"))
    assert info["values"][0] == 0.0 and info["values"][-1] > 0.015
    _, fan = read_fanuc(write_fanuc_pitch(compensation_table(res, data), axis="X"))
    assert fan["values"].sum() < -0.015                                 # Fanuc: added to the command


def test_reference_point_holds_zero_in_every_format():
    data, _, res = axis(4, travel=(-400.0, 800.0), irregular=0.4)
    t = compensation_table(res, data)
    assert t.attrs["reference_q"] == 0 and t.position_mm.iloc[t.attrs["reference_index"]] == 0.0
    _, sie = read_siemens(write_siemens_eec(t, axis="X1"))
    assert sie["values"][t.attrs["reference_index"]] == 0.0
    _, csv = read_csv(WRITERS["csv"](t))
    assert csv["values"][t.attrs["reference_index"]] == 0.0
    enc, fan = read_fanuc(write_fanuc_pitch(t, axis="X"))
    assert enc(np.array([0.0]), "up")[0] - enc(np.array([0.0]), "down")[0] == pytest.approx(-t.attrs["backlash_mm"], abs=0.5e-6)
    outside = compensation_table(res, data, reference_mm=900.0)       # beyond the last target: held, 0 from R on
    assert outside.position_mm.iloc[outside.attrs["reference_index"]] == 900.0
    np.testing.assert_array_equal(outside.compensation_mm[outside.position_mm >= data.targets[-1]], 0.0)
    with pytest.raises(InvalidInputError, match="reference point"):
        compensation_table(res, data, reference_mm=float("nan"))


# ------------------------------------------------------------------------------------------ limits
def test_siemens_point_count_is_the_808d_limit():
    data, _, res = axis(2)
    t = compensation_table(res, data, interval=4.0)                      # 251 points
    with pytest.raises(CompensationError, match=r"251 points do not fit the controller's 200 .*at least 5.025126 mm"):
        write_siemens_eec(t, axis="X1")
    assert "$AA_ENC_COMP[0,250,X1]" in write_siemens_eec(t, axis="X1", max_points=1000)   # an 840D with MD38000 >= 251
    assert len(read_siemens(write_siemens_eec(compensation_table(res, data, interval=5.025126), axis="X1"))[1]["values"]) == 200


def test_fanuc_refuses_what_does_not_fit_the_pitch_block(tmp_path):
    """--interval 0.0105 on a 1000 mm axis: one line, exit 2, no file (it wrote 95,239 lines into N10000 ...
    N105238, overwriting unrelated parameters)."""
    data, _ = axis_test(rng=np.random.default_rng(2))
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    for interval, match in (("0.0105", r"do not fit the pitch block 0 \.\.\. 1023"),
                            ("10.0005", r"not a whole number .*parameter 3624")):
        out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--interval", interval, "--compensation", "csv", tmp_path / "c.csv",
                  "--compensation", "fanuc-pitch", tmp_path / "f.txt")
        assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1 and re.search(match, out.stderr), out.stderr
        assert "Traceback" not in out.stderr and not (tmp_path / "f.txt").exists() and not (tmp_path / "c.csv").exists()
    _, info = read_fanuc(write_fanuc_pitch(compensation_table(methods.fit("positioning.gls_polynomial", data), data,
                                                              interval=10.5), axis="X"))
    assert info["p3624"] == 10500 and info["numbers"][-1] <= 1023


def test_fanuc_magnification_and_integer_fields():
    data, _, res = axis(5, pitch=(0.0, 0.9), reversal=0.0)              # 0.9 mm over 1000 mm: 90 um per 100 mm
    t = compensation_table(res, data, interval=200.0)                    # 180 um per interval > 127 units
    text = write_fanuc_pitch(t, axis="X")
    _, info = read_fanuc(text)
    assert info["magnification"] == 2 and "3623 = 2," in text
    with pytest.raises(CompensationError, match="exceeds 127"):
        write_fanuc_pitch(t, axis="X", magnification=1)
    for bad in (0, 101, 1.5):
        with pytest.raises(CompensationError, match="3623"):
            write_fanuc_pitch(t, axis="X", magnification=bad)
    with pytest.raises(CompensationError, match="pitch block"):
        write_fanuc_pitch(t, axis="X", first_number=1020)


# ------------------------------------------------------------------------------------- axis grammar
@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("bad", ["X1\nM30", "X)\nG91 G00 X-100.", "", "X 1", "1X", "X1;", "X1]", "Ä1", "X" * 33])
def test_axis_is_checked_against_the_grammar(fmt, bad):
    data, _, res = axis(2)
    with pytest.raises(InvalidInputError, match="not a valid axis name"):
        WRITERS[fmt](compensation_table(res, data), axis=bad)


def test_bad_axis_on_the_command_line_writes_nothing(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(2))
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X1\nM30", "--compensation", "siemens-eec", tmp_path / "e.mpf")
    assert out.returncode == 2 and "not a valid axis name" in out.stderr and not (tmp_path / "e.mpf").exists()
    good = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "Z1", "--compensation", "fanuc-pitch", tmp_path / "f.txt")
    assert good.returncode == 0, good.stderr
    read_fanuc((tmp_path / "f.txt").read_text())


def test_no_negative_zero():
    """Values that round to zero print as 0.000000 (they printed -0.000000)."""
    data, _ = axis_test(rng=np.random.default_rng(2), pitch=(0.0,), reversal=0.0, repeatability=1e-9)
    res = methods.fit("positioning.gls_polynomial", data)
    t = compensation_table(res, data, interval=50.0)
    assert np.any(np.signbit(t.compensation_mm)) and np.all(np.abs(t.compensation_mm) < 5e-7)
    for fmt in ("csv", "siemens-eec"):
        text = WRITERS[fmt](t, axis="X1")
        assert "-0.000000" not in text
        READERS[fmt](text)


# ---------------------------------------------------------------------------------------- backlash
def test_header_backlash_is_the_iso_mean_reversal_value(tmp_path):
    """The header's B is the ISO 230-2 table's mean reversal value (it was the mean of the polynomials'
    difference over the table grid: -3.13 against -2.979 um) and says to enter -B."""
    for seed, reversal in ((0, -0.003), (1, -0.003), (2, 0.002)):
        data, _, res = axis(seed, reversal=reversal, irregular=0.3)
        to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
        out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--compensation", "siemens-eec", tmp_path / "e.mpf", "--axis", "X1")
        iso = re.search(r"mean reversal value\D*?(-?\d+\.\d{3})", out.stdout).group(1)
        text = (tmp_path / "e.mpf").read_text()
        assert re.search(rf"mean reversal value B = {iso} um", text), (iso, text[:800])
        b = float(iso)
        assert re.search(rf"enter the backlash as -B = {-b:.3f} um, {'normal' if b < 0 else 'negative'} backlash", text)


def test_unidirectional_test_gives_the_table_of_its_direction():
    data, _ = axis_test(rng=np.random.default_rng(2), pitch=PITCH, reversal=0.0)
    from methods.positioning.data import PositioningData
    one = PositioningData(targets=data.targets, up=data.up, down=None, unit="mm")
    res = methods.fit("positioning.gls_polynomial", one)
    t = compensation_table(res, one)
    for fmt, w in WRITERS.items():
        text = w(t, axis="X1")
        low = text.lower()
        assert "mean reversal value b unknown, unidirectional test" in low and "one direction measured, up," in low
        encoder, _ = READERS[fmt](text)
        np.testing.assert_allclose(encoder(one.targets, "up") - encoder(one.targets, "down"), 0.0)   # no backlash
    np.testing.assert_allclose(t.deviation_mm, t.deviation_up_mm)
    assert np.all(np.isnan(t.deviation_down_mm))


def test_reference_option_moves_the_zero_and_the_fanuc_reference_point(tmp_path):
    """--reference R: the table holds 0 at R in every format, FANUC's 3620 is R's point, and a reference
    outside the measured travel is taken, and said (tests/test_compensation_reference.py)."""
    data, truth, _ = axis(7, irregular=0.3)    # seed 6: its ↓ cubic is one of the 5 % a 5 % lack-of-fit test rejects
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--reference", 1000, "--axis", "X1", "--compensation", "siemens-eec", tmp_path / "e.mpf",
              "--compensation", "fanuc-pitch", tmp_path / "f.txt")
    assert out.returncode == 0, out.stderr
    _, sie = read_siemens((tmp_path / "e.mpf").read_text())
    assert sie["values"][-1] == 0.0 and sie["grid"][-1] == 1000.0 and sie["values"][0] != 0.0
    ftext = (tmp_path / "f.txt").read_text()
    enc, fan = read_fanuc(ftext)
    assert "REFERENCE POSITION AT 1000.000000 MM" in ftext and fan["numbers"][-1] == fan["reference_number"] + 1
    after = methods.fit("positioning.iso230_2", remeasure(data, truth, enc, np.random.default_rng(1))).figures
    assert after["E"] <= 0.5 * methods.fit("positioning.iso230_2", data).figures["E"]
    beyond = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--reference", 1200, "--compensation", "csv", tmp_path / "c.csv")
    assert beyond.returncode == 0 and "the reference point lies 200 mm after the last target" in beyond.stdout


def test_targets_must_increase():
    from methods.positioning.data import PositioningData
    data, _, res = axis(2)
    swapped = PositioningData(targets=data.targets[::-1].copy(), up=data.up, down=data.down, unit="mm")
    with pytest.raises(InvalidInputError, match="increasing order"):
        compensation_table(res, swapped, source="mean")


def test_files_name_the_backlash_parameter_value():
    """-B in the controller's unit: SINUMERIK MD32450 in mm, FANUC 1851 in detection units."""
    data, _, res = axis(7, reversal=-0.004)
    t = compensation_table(res, data)
    b = t.attrs["backlash_mm"]
    sie = write_siemens_eec(t, axis="X1")
    assert re.search(r"MD32450 \$MA_BACKLASH\[0\] of X1 = (\S+) mm", sie).group(1) == f"{-b:.6f}"
    fan = write_fanuc_pitch(t, axis="X", detection_unit_mm=0.0001)
    assert re.search(r"SET 1851 = (-?\d+) DETECTION UNITS OF 0.0001 MM", fan).group(1) == str(int(np.rint(-b / 1e-4)))
    read_siemens(sie), read_fanuc(fan, detection_unit_mm=0.0001)
