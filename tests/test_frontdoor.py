"""The metrologist's front door and the CLI/API input checks:
units, instrument-style files, operator checks, partial arcs, plots with scale and units, compensation
tables, the 21-error CSV, the ``fitbench`` command."""
from __future__ import annotations

import json
import re
import sys
import warnings

import numpy as np
import pandas as pd
import pytest

import methods
from cli_calls import cli, one_error_line  # in this process; the subprocess form: tests/test_cli.py, --version below
from conftest import run_python
from datasets.circular_test import MachineErrors, TestConditions, circular_test, lola_hbg130, trace
from datasets.io import read_points, read_runs
from datasets.positioning import axis_test, to_frame
from methods import InvalidInputError
from methods.circular_test import diagnose, evaluate
from methods.circular_test.runs import check_pair, direction, trim
from fitbench.cli.commands import main
from methods.units import UnitWarning, mm_per

COND = TestConditions(nominal_radius=150.0, nominal_center=(300.0, 200.0), feed_mm_min=2000.0, sampling_hz=100.0,
                      start_angle_deg=17.0)
ERR = MachineErrors(squareness=40e-6, scale_x=25e-6, scale_y=-5e-6, lag_x=0.002, lag_y=0.0012, backlash_x=0.005,
                    backlash_y=0.003, noise=0.0003)


def save_xy(path, pts, header="x,y", fmt="%.9f"):
    np.savetxt(path, pts, delimiter=",", header=header, comments="", fmt=fmt)
    return path


@pytest.fixture(scope="module")
def lola(tmp_path_factory):
    d = tmp_path_factory.mktemp("lola")
    cond, err = lola_hbg130()
    cw, ccw, _ = circular_test(cond, err, seed=2004)
    save_xy(d / "cw.csv", cw)
    save_xy(d / "ccw.csv", ccw)
    return d, cond, cw, ccw


# ------------------------------------------------------------------------------------------ units
def test_unit_factors_and_refusal():
    assert mm_per("um") == mm_per("µm") == mm_per("μm") == 1e-3
    assert mm_per("nm") == 1e-6 and mm_per("m") == 1e3 and mm_per("in") == 25.4
    with pytest.raises(InvalidInputError, match="unknown length unit"):
        mm_per("furlong")


def test_points_in_micrometres_are_converted(tmp_path, lola):
    _, _, cw, _ = lola
    p = save_xy(tmp_path / "cw_um.csv", cw * 1e3, fmt="%.6f")
    np.testing.assert_allclose(read_points(p, unit="um"), cw, atol=1e-9)


def test_positioning_in_micrometres_gives_the_same_figures_and_a_warning_when_declared_mm(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(2), mpe=0.002)
    df = to_frame(data, actual=False)
    df.to_csv(tmp_path / "mm.csv", index=False)
    df.assign(deviation=df.deviation * 1e3).to_csv(tmp_path / "um.csv", index=False)
    ref = json.loads(cli("positioning", tmp_path / "mm.csv", "--json").stdout)
    out = cli("positioning", tmp_path / "um.csv", "--deviation-unit", "um", "--json")
    assert out.returncode == 0 and out.stderr == ""
    got = json.loads(out.stdout)
    for key in ("A", "E", "M", "R", "B"):
        assert got[key] == pytest.approx(ref[key], rel=1e-9)
    assert got["units"]["length"] == "mm" and got["units"]["input_deviation_unit"] == "µm"
    wrong = cli("positioning", tmp_path / "um.csv")          # µm read as mm: warned, naming the likely unit
    # the hint names the option that rescales the deviations alone (--unit would rescale the travel too)
    assert wrong.returncode == 0 and "implausible" in wrong.stderr and "(--deviation-unit um)" in wrong.stderr
    followed = json.loads(cli("positioning", tmp_path / "um.csv", "--deviation-unit", "um", "--json").stdout)
    assert followed["A"] == pytest.approx(ref["A"], rel=1e-9)
    assert wrong.stdout.startswith("fitbench ") and "input unit mm" in wrong.stdout.splitlines()[0]


def test_circular_test_json_one_unit_per_family(lola):
    d, cond, _, _ = lola
    out = cli("circular-test", d / "cw.csv", d / "ccw.csv", "--nominal-radius", cond.nominal_radius,
              "--nominal-center", *cond.nominal_center, "--feed", cond.feed_mm_min, "--json")
    assert out.returncode == 0, out.stderr
    j = json.loads(out.stdout)
    assert j["units"]["length"] == "mm" and j["units"]["angle"] == "rad"
    dg = j["diagnostics"]
    assert dg["squareness"]["unit"] == "rad" and dg["backlash_x"]["unit"] == "mm"
    assert dg["servo_mismatch"]["unit"] == "s" and dg["scale_mismatch"]["unit"] == "1 (m/m)"
    direct = diagnose(np.loadtxt(d / "cw.csv", delimiter=",", skiprows=1), np.loadtxt(d / "ccw.csv", delimiter=",",
                      skiprows=1), cond.nominal_radius, cond.nominal_center, feed_mm_min=cond.feed_mm_min)
    assert dg["squareness"]["value"] == pytest.approx(direct["squareness"]["value"] * 1e-6, rel=1e-9)
    human = cli("circular-test", d / "cw.csv", d / "ccw.csv", "--nominal-radius", cond.nominal_radius,
                "--nominal-center", *cond.nominal_center)
    assert "µrad" in human.stdout and "µm" in human.stdout and " um" not in human.stdout


# ------------------------------------------------------------------------------------------ readers
def test_reader_columns_and_plane_for_a_t_x_z_file(tmp_path):
    """A header t,x,z (a vertical-plane ballbar/encoder log): never silently t and x."""
    t = np.arange(50) * 0.01
    xz = np.column_stack([np.cos(t), np.sin(t)]) * 100
    p = tmp_path / "txz.csv"
    pd.DataFrame({"t": t, "x": xz[:, 0], "z": xz[:, 1]}).to_csv(p, index=False, float_format="%.9f")
    with pytest.raises(InvalidInputError, match="which two columns.*t, x, z"):
        read_points(p)
    np.testing.assert_allclose(read_points(p, plane="zx"), xz[:, ::-1], atol=1e-9)
    np.testing.assert_allclose(read_points(p, ("x", "z")), xz, atol=1e-9)
    np.testing.assert_allclose(read_points(p, (1, 2)), xz, atol=1e-9)
    with pytest.raises(InvalidInputError, match="no column 'y'"):
        read_points(p, plane="xy")


def test_reader_skip_rows_for_a_preamble(tmp_path):
    p = tmp_path / "pre.txt"
    p.write_text("Machine: HBG 130\nOperator: A. B.\nFeed 1000 mm/min\nx;y\n1,5;2\n3;4,25\n5;7\n")
    with pytest.raises(InvalidInputError):
        read_points(p)
    np.testing.assert_array_equal(read_points(p, skip_rows=3), [[1.5, 2], [3, 4.25], [5, 7]])


def ballbar_polar_file(path, runs, R, center, angle_unit="deg", dev_unit_factor=1e3):
    """A radial-deviation-against-angle export as ballbar software lists its data: a preamble of test
    conditions, then one row per sample with the run, the angle and the deviation in µm."""
    rows = []
    for label, pts in runs:
        ang = np.arctan2(pts[:, 1] - center[1], pts[:, 0] - center[0])
        dev = (np.hypot(pts[:, 0] - center[0], pts[:, 1] - center[1]) - R) * dev_unit_factor
        a = np.degrees(ang) if angle_unit == "deg" else ang
        rows += [f"{label},{x:.10f},{y:.4f}" for x, y in zip(a, dev)]
    head = ["Ballbar test export (synthetic)", f"Radius: {R} mm", "Feed: 1000 mm/min", "Plane: XY",
            f"direction,angle [{angle_unit}],deviation [um]"]
    path.write_text("\n".join(head + rows) + "\n")
    return path


@pytest.mark.parametrize("angle_unit", ["deg", "rad"])
def test_angle_and_radial_deviation_file_with_both_runs(tmp_path, lola, angle_unit):
    _, cond, cw, ccw = lola
    R, c = cond.nominal_radius, cond.nominal_center
    p = ballbar_polar_file(tmp_path / f"bb_{angle_unit}.txt", [("CW", cw), ("CCW", ccw)], R, c, angle_unit)
    runs = read_runs(p, skip_rows=4, unit="um", nominal_radius=R, nominal_center=c)
    assert runs.kind == "polar" and [t for t, _ in runs.runs] == ["cw", "ccw"]
    np.testing.assert_allclose(runs.runs[0][1], cw, atol=2e-6)       # 4 decimals of µm + angle rounding
    ref = evaluate(cw, ccw, R, c)
    out = cli("circular-test", p, "--skip-rows", 4, "--unit", "um", "--nominal-radius", R, "--nominal-center", *c,
              "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["G_b"] == pytest.approx(ref.figures["G_b"], abs=1e-5)


def test_polar_file_needs_the_angle_unit(tmp_path, lola):
    _, cond, cw, _ = lola
    p = tmp_path / "a.csv"
    ang = np.arctan2(cw[:, 1] - 650.0, cw[:, 0] - 1200.0)
    pd.DataFrame({"angle": ang, "deviation": 0.0}).to_csv(p, index=False)
    with pytest.raises(InvalidInputError, match="degrees or radians"):
        read_runs(p, nominal_radius=cond.nominal_radius)
    assert read_runs(p, nominal_radius=cond.nominal_radius, angle_unit="rad").kind == "polar"


def test_one_xy_file_with_a_run_column_directions_from_point_order(tmp_path, lola):
    """Runs numbered 1 and 2 (no direction words): CW and CCW are read from the point order, whichever comes first."""
    _, cond, cw, ccw = lola
    df = pd.concat([pd.DataFrame({"run": 1, "x": ccw[:, 0], "y": ccw[:, 1]}),
                    pd.DataFrame({"run": 2, "x": cw[:, 0], "y": cw[:, 1]})])
    p = tmp_path / "both.csv"
    df.to_csv(p, index=False, float_format="%.9f")
    out = cli("circular-test", p, "--nominal-radius", cond.nominal_radius, "--json")
    assert out.returncode == 0, out.stderr
    ref = evaluate(cw, ccw, cond.nominal_radius)
    got = json.loads(out.stdout)
    assert got["G_cw"] == pytest.approx(ref.figures["G_cw"], abs=1e-9) and got["G_ccw"] == pytest.approx(ref.figures["G_ccw"], abs=1e-9)


def wide_laser_export(path, data, *, sep=";", decimal=",", dev_factor=1e3, preamble=True, direction_column=False):
    """One column per run as laser software exports it: a preamble, the target in mm, errors in µm."""
    if direction_column:
        rows = []
        for d, arr in (("+", data.up), ("-", data.down)):
            for i, t in enumerate(data.targets):
                rows.append({"Target (mm)": t, "Direction": d,
                             **{f"Run {j + 1}": arr[i, j] * dev_factor for j in range(arr.shape[1])}})
        w = pd.DataFrame(rows)
    else:
        w = pd.DataFrame({"Target [mm]": data.targets})
        for j in range(data.runs):
            w[f"Run {j + 1} Forward"] = data.up[:, j] * dev_factor
            w[f"Run {j + 1} Reverse"] = data.down[:, j] * dev_factor
    head = "Laser calibration export (synthetic)\nAxis: X\nDate: 2026-11-22\n" if preamble else ""
    path.write_text(head + w.to_csv(sep=sep, index=False, decimal=decimal, float_format="%.4f"), encoding="utf-8")
    return path


@pytest.mark.parametrize("direction_column", [False, True])
def test_wide_laser_exports_match_the_long_format(tmp_path, direction_column):
    data, _ = axis_test(rng=np.random.default_rng(5), mpe=0.002)
    from datasets.io import read_positioning as read_csv
    p = wide_laser_export(tmp_path / "wide.csv", data, direction_column=direction_column)
    got = read_csv(p, skip_rows=3, deviation_unit="um")
    np.testing.assert_allclose(got.targets, data.targets)
    np.testing.assert_allclose(got.up, data.up, atol=1e-7)
    np.testing.assert_allclose(got.down, data.down, atol=1e-7)


def test_unidirectional_wide_export_gives_the_unidirectional_figures(tmp_path):
    """A wide export without directions is a unidirectional test (direction not given): A, E, R by their
    definitions (k = 2), no M or B; VDI 3441 refused; the model and the plot work on the one direction."""
    from datasets.io import read_positioning as read_csv
    p = tmp_path / "uni.csv"
    p.write_text("target,run 1,run 2,run 3\n0,1,2,1.5\n100,2,3,2.2\n200,1,1,1.4\n300,0,1,0.5\n")
    data = read_csv(p, deviation_unit="um")
    assert data.directions == ("up",) and data.down is None
    x = np.array([[1, 2, 1.5], [2, 3, 2.2], [1, 1, 1.4], [0, 1, 0.5]]) * 1e-3
    m, s = x.mean(axis=1), x.std(axis=1, ddof=1)
    res = methods.fit("positioning.gls_polynomial", data, degree=2)
    f = res.figures
    assert f["A"] == pytest.approx(np.max(m + 2 * s) - np.min(m - 2 * s), abs=1e-15)
    assert f["E_up"] == pytest.approx(np.ptp(m)) and f["R"] == pytest.approx(4 * s.max())
    assert "M" not in f and "B" not in f and f["directions"] == "unidirectional (direction not given)"
    assert set(res.polynomial) == {"up"}
    with pytest.raises(InvalidInputError, match="both approach directions"):
        methods.fit("positioning.iso230_2", data, standard="vdi3441")
    out = cli("positioning", p, "--deviation-unit", "um", "--degree", 2, "--plot", tmp_path / "u.png")
    assert out.returncode == 0 and "unidirectional (direction not given)" in out.stdout and (tmp_path / "u.png").stat().st_size > 5000


def test_decimal_commas_in_positioning_and_multilateration_readers(tmp_path):
    """Decimal commas (semicolon-separated files) are read by the positioning and multilateration readers."""
    from datasets.io import read_multilateration as read_ml
    from datasets.io import read_positioning as read_pos
    data, _ = axis_test(rng=np.random.default_rng(3))
    df = to_frame(data, actual=False)
    df.to_csv(tmp_path / "p.csv", index=False, float_format="%.6f")
    df.to_csv(tmp_path / "p_comma.csv", index=False, sep=";", decimal=",", float_format="%.6f")
    a, b = read_pos(tmp_path / "p.csv"), read_pos(tmp_path / "p_comma.csv")
    np.testing.assert_array_equal(a.up, b.up)
    from datasets.multilateration import write_example
    meas, _ = write_example(tmp_path, stations=4, noise=0.0)
    m = pd.read_csv(meas)
    m.to_csv(tmp_path / "m_comma.csv", index=False, sep=";", decimal=",", float_format="%.9f")
    np.testing.assert_allclose(read_ml(tmp_path / "m_comma.csv").lengths, read_ml(meas).lengths, atol=1e-9)


# ------------------------------------------------------------------------------------------ operator checks
def test_swapped_pair_is_swapped_back_with_a_warning(lola):
    d, cond, _, _ = lola
    base = ("--nominal-radius", cond.nominal_radius, "--nominal-center", *cond.nominal_center, "--json")
    right = cli("circular-test", d / "cw.csv", d / "ccw.csv", *base)
    swapped = cli("circular-test", d / "ccw.csv", d / "cw.csv", *base)
    assert right.returncode == swapped.returncode == 0 and right.stderr == ""
    assert "wrong order" in swapped.stderr and "swapped back" in swapped.stderr
    a, b = json.loads(right.stdout), json.loads(swapped.stdout)
    for k in ("backlash_x", "backlash_y", "servo_mismatch"):
        assert a["diagnostics"][k]["value"] == pytest.approx(b["diagnostics"][k]["value"], abs=1e-12)
    forced = cli("circular-test", d / "ccw.csv", d / "cw.csv", *base, "--as-given")
    assert forced.returncode == 0 and "evaluated as labelled (--as-given)" in forced.stderr
    f = json.loads(forced.stdout)["diagnostics"]
    assert f["reversal_spike_y"]["value"] != pytest.approx(a["diagnostics"]["reversal_spike_y"]["value"], rel=0.5)


def test_same_file_twice_and_two_runs_in_one_direction_are_refused(lola, tmp_path):
    d, cond, cw, _ = lola
    one_error_line(cli("circular-test", d / "cw.csv", d / "cw.csv", "--nominal-radius", cond.nominal_radius),
                   "same data")
    save_xy(tmp_path / "cw2.csv", cw[::-1][::-1] + 1e-6)
    one_error_line(cli("circular-test", d / "cw.csv", tmp_path / "cw2.csv", "--nominal-radius", cond.nominal_radius),
                   "both runs go CW")


def test_direction_from_point_order():
    cw, ccw, _ = circular_test(COND, ERR, seed=1)
    assert direction(cw, COND.nominal_center)[0] == "cw" and direction(ccw, COND.nominal_center)[0] == "ccw"
    runs, warns = check_pair({"cw": ccw, "ccw": cw}, COND.nominal_center)
    assert runs["cw"] is cw and warns


def test_nominal_centre_or_radius_off_is_warned_with_the_fitted_values(lola):
    d, cond, _, _ = lola
    out = cli("circular-test", d / "cw.csv", d / "ccw.csv", "--nominal-radius", cond.nominal_radius + 0.5,
              "--nominal-center", 1200.5, 650)
    assert out.returncode == 0
    assert "nominal centre (1200.5000, 650.0000) mm is 51" in out.stderr and "fitted centre (1199.98" in out.stderr
    assert "fitted radius 299.01" in out.stderr


def test_overrun_is_trimmed_and_G_unchanged(tmp_path):
    """20 deg recorded beyond 360 deg inflate G (with a slow thermal drift the overrun does not close the
    circle); trimmed to the nominal arc, G is the clean run's within 0.1 µm."""
    cond = TestConditions(nominal_radius=150.0, nominal_center=(300.0, 200.0), feed_mm_min=2000.0, sampling_hz=100.0,
                          start_angle_deg=17.0)
    err = MachineErrors(squareness=40e-6, scale_x=25e-6, backlash_x=0.005, spike_y=0.004, spike_tau=0.1,
                        drift_x=0.1e-3, noise=0.0003)
    rng = np.random.default_rng(7)
    over = TestConditions(**{**cond.__dict__, "arc_deg": 380.0})
    cw_full, _ = trace("cw", over, err, rng)
    ccw_full, _ = trace("ccw", over, err, np.random.default_rng(8))
    n360 = int(np.sum(np.degrees(np.abs(np.unwrap(np.arctan2(cw_full[:, 1] - 200, cw_full[:, 0] - 300)) -
                                        np.arctan2(cw_full[0, 1] - 200, cw_full[0, 0] - 300))) < 360 - 1e-9))
    clean = evaluate(cw_full[:n360], ccw_full[:n360], 150.0, (300.0, 200.0))
    untrimmed = evaluate(cw_full, ccw_full, 150.0, (300.0, 200.0))
    assert untrimmed.figures["G_cw"] - clean.figures["G_cw"] > 1e-3                        # the overrun mattered (> 1 µm)
    cw_t, rep = trim(cw_full, (300.0, 200.0))
    ccw_t, _ = trim(ccw_full, (300.0, 200.0))
    assert rep["overrun_trimmed_points"] > 0 and abs(rep["evaluated_arc_deg"] - 360) < 1.0
    trimmed = evaluate(cw_t, ccw_t, 150.0, (300.0, 200.0))
    assert abs(trimmed.figures["G_cw"] - clean.figures["G_cw"]) < 1e-4 and abs(trimmed.figures["G_ccw"] - clean.figures["G_ccw"]) < 1e-4
    save_xy(tmp_path / "cw.csv", cw_full)
    save_xy(tmp_path / "ccw.csv", ccw_full)
    out = cli("circular-test", tmp_path / "cw.csv", tmp_path / "ccw.csv", "--nominal-radius", 150, "--json")
    j = json.loads(out.stdout)
    assert abs(j["G_cw"] - clean.figures["G_cw"]) < 1e-4 and any("overrun" in n for n in j["notes"])


def test_lead_in_and_lead_out_removed_by_option(tmp_path):
    cond = TestConditions(nominal_radius=150.0, nominal_center=(300.0, 200.0), sampling_hz=100.0, run_in_deg=30.0,
                          run_out_deg=30.0)
    cw, ccw, truth = circular_test(cond, ERR, seed=4)
    with_leads = {n: np.vstack([truth["info"][n]["run_in"], pts, truth["info"][n]["run_out"]])
                  for n, pts in (("cw", cw), ("ccw", ccw))}
    assert len(with_leads["cw"]) > len(cw)
    got, rep = trim(with_leads["cw"], (300.0, 200.0), lead_in_deg=30.0, lead_out_deg=30.0)
    assert abs(len(got) - len(cw)) <= 2 and rep["lead_removed_points"] > 0
    ref = evaluate(cw, ccw, 150.0, (300.0, 200.0))
    save_xy(tmp_path / "cw.csv", with_leads["cw"])
    save_xy(tmp_path / "ccw.csv", with_leads["ccw"])
    out = cli("circular-test", tmp_path / "cw.csv", tmp_path / "ccw.csv", "--nominal-radius", 150,
              "--lead-in", 30, "--lead-out", 30, "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["G_cw"] == pytest.approx(ref.figures["G_cw"], abs=0.2e-3)


@pytest.mark.parametrize("leads", [("--lead-in", 400), ("--lead-in", 200, "--lead-out", 200)])
def test_leads_as_long_as_the_run_are_refused_not_called_the_same_file(lola, leads):
    """A lead-in longer than the arc trimmed both runs to nothing, then reported 'the same file twice'."""
    d, cond, _, _ = lola
    out = cli("circular-test", d / "cw.csv", d / "ccw.csv", "--nominal-radius", cond.nominal_radius, *leads)
    one_error_line(out, "trimming would leave nothing")
    assert "same" not in out.stderr


# ------------------------------------------------------------------------------------------ partial arcs
def arc_runs(arc_deg, start_deg, err, R=150.0, center=(0.0, 0.0), seed=1):
    c1 = TestConditions(nominal_radius=R, nominal_center=center, feed_mm_min=1000.0, sampling_hz=50.0,
                        arc_deg=arc_deg, start_angle_deg=start_deg)
    c2 = TestConditions(**{**c1.__dict__, "start_angle_deg": start_deg + arc_deg})
    ccw, _ = trace("ccw", c1, err, np.random.default_rng(seed))
    cw, _ = trace("cw", c2, err, np.random.default_rng(seed + 1))
    return cw, ccw


def test_220_degree_vertical_plane_arc_recovers_squareness_and_scale():
    """ISO 230-4 partial arc of 220 deg (from -20 to 200 deg, as in a vertical plane)."""
    err = MachineErrors(scale_x=20e-6, scale_y=-15e-6, squareness=30e-6, lag_x=0.002, lag_y=0.0012, backlash_x=0.004,
                        noise=0.0003)
    cw, ccw = arc_runs(220.0, -20.0, err)
    ev = evaluate(cw, ccw, 150.0, (0.0, 0.0))
    assert ev.partial_arc and 219 < ev.arc_deg["cw"] < 221
    dg = diagnose(cw, ccw, 150.0, (0.0, 0.0), feed_mm_min=1000.0)
    assert dg["squareness"]["value"] == pytest.approx(30.0, rel=0.05)
    assert dg["scale_mismatch"]["value"] == pytest.approx(35.0, rel=0.05)
    assert dg["servo_mismatch"]["value"] == pytest.approx(0.8, rel=0.05)
    assert dg["_model"]["partial_arc"] and dg["_model"]["not_identifiable"] == []


def test_arc_without_an_x_reversal_reports_backlash_x_not_identifiable():
    err = MachineErrors(scale_x=20e-6, squareness=30e-6, noise=0.0003)
    cw, ccw = arc_runs(120.0, 30.0, err)                # 30..150 deg: Y reverses at 90, X never
    dg = diagnose(cw, ccw, 150.0, (0.0, 0.0))
    for k in ("backlash_x", "reversal_spike_x"):
        assert dg[k]["value"] is None and "no reversal of the X axis" in dg[k]["note"]
    assert dg["backlash_y"]["value"] is not None
    out_text = __import__("fitbench.plots.circular_test", fromlist=["text"]).text(evaluate(cw, ccw, 150.0, (0, 0)), dg)
    assert "not identifiable" in out_text and "partial arc" in out_text


# ------------------------------------------------------------------------------------------ plots
def test_polar_plot_carries_scale_units_markers_and_panel(lola):
    from fitbench.plots.circular_test import polar_plot
    _, cond, cw, ccw = lola
    ev = evaluate(cw, ccw, cond.nominal_radius, cond.nominal_center,
                  conditions={"machine": "HBG 130", "date": "2026-11-22", "feed_mm_min": 1000.0, "plane": "xy"})
    dg = diagnose(cw, ccw, cond.nominal_radius, cond.nominal_center, feed_mm_min=1000.0)
    figs = []
    polar_plot(cw, ccw, ev, "unused.png", diagnostics=dg, save=lambda fig, path: figs.append(fig))
    fig = figs[0]
    ax = fig.axes[0]
    assert re.search(r"scale \d+(\.\d+)? µm/div", ax.get_title())
    ticks = [t.get_text() for t in ax.get_yticklabels()]
    assert ticks and all(t.endswith("µm") for t in ticks)
    assert [t.get_text() for t in ax.get_xticklabels()][:2] == ["0°", "45°"]
    panel = "\n".join(t.get_text() for t in fig.texts)
    for needed in ("HBG 130", "2026-11-22", "298.997 mm", "1000 mm/min", "µm/div", "µrad", "G(b)"):
        assert needed in panel
    # diagnostics ranked by contribution: squareness (about 20 µm) before scale mismatch (about 10 µm)
    assert panel.index("squareness") < panel.index("scale mismatch") < panel.index("backlash X")
    labels = [h.get_label() for h in fig.legends[0].legend_handles]
    assert any("G band" in l for l in labels) and any("CW start" in l for l in labels) and any("nominal" in l for l in labels)


def test_positioning_plot_carries_units_runs_and_figures(tmp_path):
    from fitbench.plots.positioning import plot
    data, _ = axis_test(rng=np.random.default_rng(2), mpe=0.002)
    res = methods.fit("positioning.gls_polynomial", data, mpe=0.002)
    figs = []
    labels = plot(res, "unused.png", data=data, save=lambda fig, path: figs.append(fig))
    assert labels["x"] == "target position P [mm]" and labels["y"] == "positional deviation [µm]"
    ax = figs[0].axes[0]
    assert len(ax.lines) >= 2 * data.runs + 3                # every run, both means, the bidirectional mean
    annot = "\n".join(t.get_text() for t in ax.texts)
    for k in ("A", "E", "B", "M", "R"):
        assert re.search(rf"^{k} = -?\d+\.\d\d µm$", annot, re.M)


# ------------------------------------------------------------------------------------------ outputs
def test_positioning_text_has_per_target_table_readable_coefficients_and_vdi_heading(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(2), mpe=0.002)
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    out = cli("positioning", tmp_path / "a.csv").stdout
    assert "per target" in out and "1000.000" in out and "µm/m^3" in out and "e-1" not in out
    vdi = cli("positioning", tmp_path / "a.csv", "--standard", "vdi3441").stdout
    assert "VDI/DGQ 3441" in vdi and "ISO 230-2" not in vdi


def test_multilateration_21_errors_csv(tmp_path):
    from datasets.multilateration import write_example
    meas, st = write_example(tmp_path, stations=6, noise=0.0)
    assert main(["multilaterate", str(meas), "--stations", str(st), "--identify", "--errors-csv",
                 str(tmp_path / "e.csv")]) == 0
    e = pd.read_csv(tmp_path / "e.csv", comment="#")
    names = set(e.iso230_1_name) - {"rigid"}
    assert len(names) == 21 and {"EXX", "EYX", "ECZ", "C0Y", "B0Z", "A0Z"} <= names
    assert set(e.unit) == {"mm", "rad"}
    assert e.loc[e.parameter == "C0Y", "unit"].item() == "rad"


# ----------------------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def small(tmp_path_factory):
    d = tmp_path_factory.mktemp("small")
    cw, ccw, _ = circular_test(COND, ERR, seed=2)
    save_xy(d / "cw.csv", cw)
    save_xy(d / "ccw.csv", ccw)
    data, _ = axis_test(rng=np.random.default_rng(2))
    to_frame(data, actual=False).to_csv(d / "axis.csv", index=False)
    t = np.linspace(0, 1, 50)
    save_xy(d / "ref.csv", np.column_stack([t * 10, 0 * t]))
    save_xy(d / "meas.csv", np.column_stack([t * 10, 0.001 * np.sin(7 * t)]))
    huge = to_frame(data, actual=False)
    huge.loc[3, "deviation"] = 1e300
    huge.to_csv(d / "huge.csv", index=False)
    from datasets.multilateration import write_example
    write_example(d, stations=4, noise=0.0)
    return d


CT = ("circular-test", "{d}/cw.csv", "{d}/ccw.csv", "--nominal-radius", "150")
CTC = CT + ("--nominal-center", "300", "200")


@pytest.mark.parametrize("args, match", [
    (CT + ("--plot", "{d}/no_such_folder/p.png"), "does not exist"),
    (CT + ("--plot", "{d}/p.xyz"), "unknown image format"),
    (("positioning", "{d}/axis.csv", "--plot", "{d}/missing/p.png"), "does not exist"),
    (("positioning", "{d}/axis.csv", "--plot", "{d}/p.doc"), "unknown image format"),
    (("magnify", "{d}/ref.csv", "{d}/meas.csv", "--eta", "100", "--plot", "{d}/nope/m.png"), "does not exist"),
    (("magnify", "{d}/ref.csv", "{d}/meas.csv", "--eta", "100", "--plot", "{d}/m.bmpx"), "unknown image format"),
    (CTC + ("--cyclic-pitch", "nan"), "--cyclic-pitch must be a positive"),
    (CT + ("--nominal-center", "nan", "650"), "--nominal-center must be a finite"),
    (("multilaterate", "{d}/measurements.csv", "--identify", "--degree", "-1"), "--degree must be a positive"),
    (("positioning", "{d}/huge.csv"), "not a measurement"),
    (("magnify", "{d}/ref.csv", "{d}/meas.csv", "--eta", "nan"), "--eta must be a positive"),
    (("magnify", "{d}/ref.csv", "{d}/meas.csv", "--eta", "inf"), "--eta must be a positive"),
    (("magnify", "{d}/ref.csv", "{d}/meas.csv", "--eta", "0"), "--eta must be a positive"),
    (("magnify", "{d}/ref.csv", "{d}/meas.csv", "--eta=-5"), "--eta must be a positive"),
    (("multilaterate", "{d}/measurements.csv", "--max-iter=-3"), "--max-iter must be a positive"),
    (CTC + ("--feed=-1000",), "--feed must be a positive"),
    (CTC + ("--cyclic-pitch=-5",), "--cyclic-pitch must be a positive"),
    (CT + ("--arc", "45"), "--arc must be between 90 and 360"),
    (CT + ("--unit", "furlong"), "invalid choice"),
])
def test_bad_values_one_line_no_traceback(small, args, match):
    one_error_line(cli(*[a.format(d=small) for a in args]), match)


@pytest.mark.parametrize("eta", [float("nan"), float("inf"), 0.0, -5.0, "abc"])
def test_magnify_api_refuses_bad_eta(eta):
    ref = np.column_stack([np.linspace(0, 10, 20), np.zeros(20)])
    with pytest.raises(InvalidInputError, match="eta"):
        methods.fit("magnify.offset", (ref, ref + [0, 0.001]), eta=eta)
    with pytest.raises(InvalidInputError, match="eta"):
        methods.fit("magnify.nearest", (ref, ref + [0, 0.001]), eta=eta)


def test_plot_is_written_atomically_and_no_temporary_files_left(small, tmp_path):
    out = cli(*[a.format(d=small) for a in CT], "--plot", tmp_path / "p.svg")
    assert out.returncode == 0, out.stderr
    assert [p.name for p in tmp_path.iterdir()] == ["p.svg"]


@pytest.mark.slow
# -----------------------------------------------------------------------------------------------------------
def test_reader_peak_memory_within_3x_the_array(tmp_path):
    """2e6 points (a 32 MB array): the reader's peak resident memory grows by less than 3x the array
    (measured in a fresh process after a warm-up read)."""
    n = 2_000_000
    p = tmp_path / "big.csv"
    rng = np.random.default_rng(0)
    np.savetxt(p, rng.normal(size=(n, 2)) * 100, delimiter=",", header="x,y", comments="", fmt="%.9f")
    small = tmp_path / "warm.csv"
    save_xy(small, rng.normal(size=(100, 2)))
    code = f"""
import resource, sys
from datasets.io import read_points
read_points({str(small)!r})
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
pts = read_points({str(p)!r})
after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print((after - before) * 1024 / pts.nbytes, pts.shape[0])
"""
    out = run_python("-c", code)
    assert out.returncode == 0, out.stderr
    ratio, rows = out.stdout.split()
    assert int(rows) == n and float(ratio) < 3.0, ratio


# ------------------------------------------------------------------------------------------ the fitbench command
def test_version_on_every_entry_point():
    from fitbench import __version__
    for args in (["-m", "methods", "--version"], ["-m", "fitbench", "--version"], ["-m", "fitbench", "run", "--version"],
                 ["-m", "methods", "circular-test", "--version"]):
        out = run_python(*args)
        assert out.returncode == 0 and out.stdout.strip() == f"fitbench {__version__}", (args, out)


def test_fitbench_delegates_and_names_a_missing_module(monkeypatch, capsys):
    import fitbench.cli as fc
    monkeypatch.setitem(fc.DELEGATED, "verify", ("experiments.no_such_module", "x"))
    assert fc.main(["verify"]) == 2
    assert "experiments.no_such_module is missing" in capsys.readouterr().err
    assert fc.main(["list", "--family", "circle"]) == 0


def test_fit_reads_any_plane_and_unit_and_says_so(tmp_path):
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    p = tmp_path / "yz_um.csv"
    pd.DataFrame({"t": t, "y": 5000 + 2000 * np.cos(t), "z": -1000 + 2000 * np.sin(t)}).to_csv(p, index=False)
    out = cli("fit", "circle.gauss_newton", p, "--plane", "yz", "--unit", "um", "--json")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    assert d["radius"] == pytest.approx(2.0, abs=1e-12) and d["center"] == pytest.approx([5.0, -1.0], abs=1e-12)
    assert d["units"]["length"] == "mm" and d["units"]["input_unit"] == "µm"
    human = cli("fit", "circle.gauss_newton", p, "--plane", "yz", "--unit", "um")
    assert human.stdout.startswith("input unit µm (converted to mm)")
    # the centre's lines name the file's coordinates, in the order read
    assert re.search(r"^center y +5 mm$", human.stdout, re.M) and re.search(r"^center z +-1 mm$", human.stdout, re.M)
    swapped = cli("fit", "circle.gauss_newton", p, "--columns", "z", "y", "--unit", "um").stdout
    assert swapped.index("center z") < swapped.index("center y") and "center x" not in swapped
    rnd = cli("roundness", p, "--plane", "yz", "--unit", "um")
    assert rnd.returncode == 0 and "centre y [mm]" in rnd.stdout and "centre z [mm]" in rnd.stdout, rnd.stderr
    one_error_line(cli("fit", "circle.gauss_newton", p), "which two columns")


def test_circular_test_file_in_micrometres(lola, tmp_path):
    d, cond, cw, ccw = lola
    save_xy(tmp_path / "cw.csv", cw * 1e3, fmt="%.6f")
    save_xy(tmp_path / "ccw.csv", ccw * 1e3, fmt="%.6f")
    base = ("--nominal-radius", cond.nominal_radius, "--json")
    ref = json.loads(cli("circular-test", d / "cw.csv", d / "ccw.csv", *base).stdout)
    got = json.loads(cli("circular-test", tmp_path / "cw.csv", tmp_path / "ccw.csv", *base, "--unit", "um").stdout)
    assert got["G_b"] == pytest.approx(ref["G_b"], abs=1e-6) and got["units"]["input_unit"] == "µm"
    one_error_line(cli("circular-test", tmp_path / "cw.csv", tmp_path / "ccw.csv", *base[:2]), "is the file in µm?")


def test_fitbench_run_and_report_default_folders_are_relative_to_the_cwd(monkeypatch):
    import types
    import fitbench.cli as fc
    seen = {}
    fake = types.ModuleType("fake_experiments")
    fake.main = lambda argv, prog: seen.setdefault("argv", argv) and 0
    monkeypatch.setitem(sys.modules, "fake_experiments", fake)
    monkeypatch.setitem(fc.DELEGATED, "run", ("fake_experiments", "x"))
    monkeypatch.setitem(fc.DELEGATED, "report", ("fake_experiments", "x"))
    # run's own default is relative to the cwd and depends on --quick and on the study (results/quick/, results/user/)
    assert fc.main(["run", "published"]) == 0 and seen.pop("argv") == ["published"]
    assert fc.main(["run", "--quick"]) == 0 and seen.pop("argv") == ["--quick"]
    assert fc.main(["run", "published", "--out=X"]) == 0 and seen.pop("argv") == ["published", "--out=X"]
    assert fc.main(["report"]) == 0 and seen.pop("argv") == ["--results", "results"]
    # report's --out follows its --results (experiments.report.default_out): a fixed `--out paper` sent the report
    # of `--results mine` into paper/, which experiments.report refuses
    assert fc.main(["report", "--results", "mine"]) == 0 and seen.pop("argv") == ["--results", "mine"]


def test_fit_help_docs_and_output_agree_on_the_printed_unit(lola, capsys, tmp_path):
    """fit --help said 'results are printed in µm' while fit prints mm (whatever the input unit)."""
    d, cond, cw, _ = lola
    with pytest.raises(SystemExit):
        main(["fit", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "printed in mm" in text and "printed in µm" not in text
    p = save_xy(tmp_path / "um.csv", cw * 1e3, fmt="%.6f")
    out = cli("fit", "circle.gauss_newton", p, "--unit", "um")
    assert out.returncode == 0 and "lengths below in mm" in out.stdout
    radius = next(ln for ln in out.stdout.splitlines() if ln.startswith("radius"))
    assert radius.endswith(" mm") and float(radius.split()[1]) == pytest.approx(cond.nominal_radius, abs=0.1)


def test_wide_laser_export_without_units_is_told_the_deviation_unit(tmp_path):
    """A laser export with no units in its header (targets mm, errors µm): the warning recommended --unit um,
    which made the travel 0-1 mm (and a compensation table over 0..1 mm). It names --deviation-unit um, and
    following it gives the figures of the file read with the right units, over the whole travel."""
    data, _ = axis_test(rng=np.random.default_rng(5), mpe=0.002)
    p = wide_laser_export(tmp_path / "wide.csv", data)
    p.write_text(p.read_text(encoding="utf-8").replace("Target [mm]", "Target"), encoding="utf-8")
    wrong = cli("positioning", p, "--skip-rows", 3)
    assert "implausible" in wrong.stderr and "(--deviation-unit um)" in wrong.stderr and "(--unit um)" not in wrong.stderr
    ok = cli("positioning", p, "--skip-rows", 3, "--deviation-unit", "um", "--compensation", "csv",
             tmp_path / "comp.csv", "--json")
    assert ok.returncode == 0 and "warning" not in ok.stderr, ok.stderr
    ref = methods.fit("positioning.iso230_2", data).figures
    assert json.loads(ok.stdout)["E"] == pytest.approx(ref["E"], abs=2e-7)
    table = pd.read_csv(tmp_path / "comp.csv", comment="#")
    position = table.iloc[:, 0].to_numpy(dtype=float)
    assert position.min() == pytest.approx(data.targets.min()) and position.max() == pytest.approx(data.targets.max())
