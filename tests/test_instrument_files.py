"""Instrument-style files through every subcommand, with injected truth: polar roundness exports (angle + radial
deviation, units in the header), the same profile as x, y, units in headers and their contradictions, --columns
naming any layout's columns, angle headers never read as x, y, plausibility warnings naming the likely unit."""
from __future__ import annotations

import io
import json

import numpy as np
import pytest

import methods
from cli_calls import cli
from datasets.circular_test import MachineErrors, TestConditions, circular_test
from datasets.io import DataFileError, read_points, read_profile

R = 20.0                                   # a Ø40 mm shaft
LOBES = [(2, 0.9e-3, 0.3), (3, 1.5e-3, 1.1), (7, 0.3e-3, 2.0), (40, 0.2e-3, 0.7), (160, 0.05e-3, 1.5)]  # mm


def shaft(n=1440, seed=4):
    """Angles (rad) and radial deviations (mm) of a turned shaft's trace: lobes plus noise."""
    t = 2 * np.pi * np.arange(n) / n
    d = sum(a * np.cos(k * t + ph) for k, a, ph in LOBES)
    return t, d + 2e-5 * np.random.default_rng(seed).standard_normal(n)


def write_polar(path, t, d_mm, header="Angle (deg);Radial deviation (µm)", sep=";", angle="deg", factor=1e3,
                decimal_comma=True, preamble=()):
    a = np.degrees(t) if angle == "deg" else t
    rows = [f"{x:.8f}{sep}{y * factor:.6f}" for x, y in zip(a, d_mm)]
    if decimal_comma:
        rows = [r.replace(".", ",") for r in rows]
    path.write_text("\n".join([*preamble, header, *rows]) + "\n", encoding="utf-8")
    return path


def write_xy(path, t, d_mm, radius=R, header="X [mm],Y [mm]", factor=1.0):
    r = radius + d_mm
    path.write_text(header + "\n" + "".join(f"{x * factor:.9f},{y * factor:.9f}\n"
                                            for x, y in zip(r * np.cos(t), r * np.sin(t))))
    return path


@pytest.mark.parametrize("cutoff", ["none", "15", "50", "150"])
def test_polar_export_and_xy_profile_give_the_same_ron_for_every_reference(tmp_path, cutoff):
    t, d = shaft()
    polar = write_polar(tmp_path / "talyrond.txt", t, d, preamble=("Roundness trace", "Part: shaft Ø40"))
    xy = write_xy(tmp_path / "xy.csv", t, d)
    a = cli("roundness", polar, "--skip-rows", 2, "--nominal-radius", R, "--cutoff", cutoff, "--json")
    b = cli("roundness", xy, "--cutoff", cutoff, "--json")
    assert a.returncode == 0 and b.returncode == 0, a.stderr + b.stderr
    ja, jb = json.loads(a.stdout), json.loads(b.stdout)
    assert set(ja["references"]) == {"lsci", "mzci", "mici", "mcci"}
    for kind in ja["references"]:
        for p in ("RONt", "RONp", "RONv", "RONq"):
            assert ja["references"][kind][p] == pytest.approx(jb["references"][kind][p], abs=2e-9), (kind, p)
    assert ja["input_unit"] == "µm" and jb["input_unit"] == "mm"
    # the deviations alone (no nominal radius): the limaçon evaluation, RONt within 1e-5 of the profile's
    c = cli("roundness", polar, "--skip-rows", 2, "--cutoff", cutoff, "--json")
    assert c.returncode == 0, c.stderr
    jc = json.loads(c.stdout)
    assert any("without a nominal radius" in n for n in jc["notes"])
    for kind in jc["references"]:
        assert jc["references"][kind]["RONt"] == pytest.approx(jb["references"][kind]["RONt"], rel=1e-5, abs=1e-9)


def test_unfiltered_ront_is_the_injected_profile_span(tmp_path):
    """Truth: with lobes of 2 UPR and more the LSCI centre is the origin, so RONt(LSCI) is the span of the
    injected deviations, to the centre's scatter from the noise (sigma sqrt(2 / N) ~ 1e-6 mm)."""
    t, d = shaft(seed=9)
    polar = write_polar(tmp_path / "p.csv", t, d, header="angle_rad,dr_um", sep=",", angle="rad", decimal_comma=False)
    out = cli("roundness", polar, "--nominal-radius", R, "--cutoff", "none", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["references"]["lsci"]["RONt"] == pytest.approx(np.ptp(d), abs=3e-6)


def test_fit_reads_a_polar_profile(tmp_path):
    t, d = shaft()
    polar = write_polar(tmp_path / "p.txt", t, d, header="Winkel/°\tAbw. [um]", sep="\t")
    out = cli("fit", "circle.gauss_newton", polar, "--nominal-radius", R, "--json", "--no-residuals")
    assert out.returncode == 0, out.stderr
    res = json.loads(out.stdout)
    direct = methods.fit("circle.gauss_newton", np.c_[(R + d) * np.cos(t), (R + d) * np.sin(t)])
    assert res["radius"] == pytest.approx(direct.radius, abs=1e-8)
    np.testing.assert_allclose(res["center"], direct.center, atol=1e-8)
    assert res["units"]["input_unit"] == "µm"


def test_a_two_column_file_whose_header_names_an_angle_is_never_xy(tmp_path):
    t, d = shaft(n=200)
    p = tmp_path / "a.csv"
    p.write_text("angle_deg,value\n" + "".join(f"{a:.4f},{v:.6f}\n" for a, v in zip(np.degrees(t), d * 1e3)))
    for cmd in (("roundness", p), ("fit", "circle.kasa", p)):
        out = cli(*cmd)
        assert out.returncode == 2 and out.stderr.count("\n") == 1 and "is an angle" in out.stderr, out.stderr
    with pytest.raises(DataFileError, match="is an angle"):
        read_points(p)
    # --columns naming the angle and the other column reads it as angle + deviation
    got = read_profile(p, columns=("Angle deg", "value"), unit="um", nominal_radius=R)
    assert got.kind == "polar"
    np.testing.assert_allclose(np.hypot(*got.runs[0][1].T), R + d, atol=2e-6)
    # magnify needs x, y: a polar file is refused in one line
    xy = write_xy(tmp_path / "ref.csv", t, 0 * d)
    poolar = write_polar(tmp_path / "m.csv", t, d, header="angle [deg],deviation [um]", sep=",", decimal_comma=False)
    out = cli("magnify", xy, poolar, "--eta", 100)
    assert out.returncode == 2 and "not x, y" in out.stderr


@pytest.mark.parametrize("header,unit,expect", [("x_um,y_um", None, 1e-3), ("X (µm), Y (µm)", "um", 1e-3),
                                                ("x [mm],y [mm]", None, 1.0), ("x/m,y/m", None, 1e3)])
def test_units_in_headers(tmp_path, header, unit, expect):
    t, d = shaft(n=120)
    p = write_xy(tmp_path / "u.csv", t, d, header=header, factor=1 / expect)
    pts = read_points(p, unit=unit)
    np.testing.assert_allclose(np.hypot(*pts.T), R + d, atol=1e-8)


@pytest.mark.parametrize("cmd", [("fit", "circle.kasa"), ("roundness",), ("magnify",)])
def test_a_header_unit_contradicting_unit_is_an_error(tmp_path, cmd):
    t, d = shaft(n=120)
    p = write_xy(tmp_path / "u.csv", t, d, header="x [um],y [um]", factor=1e3)
    args = [*cmd, p, "--unit", "mm"] if cmd[0] != "magnify" else ["magnify", p, p, "--eta", 10, "--unit", "mm"]
    out = cli(*args)
    assert out.returncode == 2 and out.stderr.count("\n") == 1
    assert "header says" in out.stderr and "µm" in out.stderr and "--unit says mm" in out.stderr


def test_a_header_unit_contradicting_the_circular_test_unit_or_angle_unit(tmp_path):
    cond = TestConditions(nominal_radius=100.0, nominal_center=(0.0, 0.0), sampling_hz=50.0)
    cw, ccw, _ = circular_test(cond, MachineErrors(), seed=1)
    rows = [f"{lab},{np.degrees(np.arctan2(y, x)):.6f},{(np.hypot(x, y) - 100.0) * 1e3:.5f}"
            for lab, pts in (("cw", cw), ("ccw", ccw)) for x, y in pts]
    p = tmp_path / "bb.csv"
    p.write_text("Direction, Angle (deg), Radial deviation (um)\n" + "\n".join(rows) + "\n")
    for extra, word in ((("--unit", "mm"), "--unit says mm"), (("--angle-unit", "rad"), "--angle-unit says rad")):
        out = cli("circular-test", p, "--nominal-radius", 100, *extra)
        assert out.returncode == 2 and word in out.stderr and out.stderr.count("\n") == 1, out.stderr


def test_radial_deviation_in_um_header_and_diagnostics_without_nominal_center(tmp_path):
    """A ballbar export 'Radial deviation (um)' is read as angle + deviation in µm (not x, y in mm), and the
    diagnostics come without --nominal-center 0 0: the reader placed the points about (0, 0) itself."""
    cond = TestConditions(nominal_radius=150.0, nominal_center=(0.0, 0.0), feed_mm_min=2000.0, sampling_hz=100.0,
                          start_angle_deg=17.0)
    err = MachineErrors(squareness=40e-6, scale_x=25e-6, noise=0.0001)
    cw, ccw, _ = circular_test(cond, err, seed=3)
    rows = [f"{lab};{np.degrees(np.arctan2(y, x)):.6f};{(np.hypot(x, y) - 150.0) * 1e3:.5f}".replace(".", ",")
            for lab, pts in (("CW", cw), ("CCW", ccw)) for x, y in pts]
    p = tmp_path / "ballbar.txt"
    p.write_text("Run;Angle [°];Radial deviation (um)\n" + "\n".join(rows) + "\n", encoding="utf-8")
    out = cli("circular-test", p, "--nominal-radius", 150, "--json")
    assert out.returncode == 0, out.stderr
    j = json.loads(out.stdout)
    assert isinstance(j["diagnostics"], dict)
    assert j["diagnostics"]["squareness"]["value"] == pytest.approx(40e-6, abs=3 * j["diagnostics"]["squareness"]["u"] + 2e-6)
    assert j["units"]["input_unit"] == "µm" and j["G_b"] < 0.05    # µm deviations, not mm


@pytest.mark.parametrize("cmd", [("fit", "circle.gauss_newton"), ("roundness",)])
def test_a_shaft_in_um_read_as_mm_warns_naming_um(tmp_path, cmd):
    t, d = shaft(n=720)
    p = write_xy(tmp_path / "um.csv", t, d, header="x,y", factor=1e3)       # written in µm, no unit in the header
    out = cli(*cmd, p)
    assert "fitbench: warning:" in out.stderr and "--unit um" in out.stderr, out.stderr
    ok = cli(*cmd, p, "--unit", "um")
    assert "warning" not in ok.stderr.replace("fewer than", ""), ok.stderr


def test_polar_deviations_in_mm_that_are_um_warn(tmp_path):
    t, d = shaft(n=720)
    p = write_polar(tmp_path / "p.csv", t, d, header="angle [deg],deviation", sep=",", decimal_comma=False)
    out = cli("roundness", p, "--nominal-radius", R, "--cutoff", "none")          # deviations in µm read as mm
    assert "radial deviations" in out.stderr and "--unit um" in out.stderr, out.stderr


def test_roundness_plot_into_a_missing_folder_is_one_line(tmp_path):
    t, d = shaft(n=400)
    p = write_xy(tmp_path / "xy.csv", t, d)
    out = cli("roundness", p, "--plot", tmp_path / "missing" / "x.png")
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and "does not exist" in out.stderr
    assert "Traceback" not in out.stderr


def test_temperature_correction_removes_a_pure_thermal_slope(tmp_path):
    """ISO 230-2 nominal differential expansion: an axis at 26 °C with alpha = 11.5 µm/(m·K) shows a pure
    thermal slope alpha dT P; E before is alpha dT x travel (69 µm over 1000 mm), after the correction 0."""
    from datasets.positioning import axis_test, to_frame
    data, _ = axis_test(rng=np.random.default_rng(1), pitch=(0.0,), reversal=0.0, mpe=1e-9)
    alpha, temp = 11.5, 26.0
    slope = alpha * 1e-6 * (temp - 20.0)
    import dataclasses
    noise = np.random.default_rng(2).normal(0.0, 1e-5, (2, *data.up.shape))      # 10 nm of laser noise
    hot = dataclasses.replace(data, up=noise[0] + slope * data.targets[:, None],
                              down=noise[1] + slope * data.targets[:, None])
    p = tmp_path / "laser.csv"
    to_frame(hot, actual=False).to_csv(p, index=False)
    travel = float(np.ptp(data.targets))
    before = json.loads(cli("positioning", p, "--mpe", 0.001, "--json").stdout)
    out = cli("positioning", p, "--mpe", 0.001, "--json", "--material-temperature", temp, "--expansion-coefficient", alpha)
    assert out.returncode == 0, out.stderr
    after = json.loads(out.stdout)
    assert before["E"] == pytest.approx(slope * travel, abs=1e-4)
    assert after["E"] < 1e-4 < 0.05 * before["E"]
    np.testing.assert_allclose(np.array(before["per_target"]["mean_bidirectional"]) - slope * data.targets,
                               after["per_target"]["mean_bidirectional"], atol=1e-12)
    assert after["temperature_correction"]["material_temperature_c"] == temp
    text = cli("positioning", p, "--mpe", 0.001, "--material-temperature", temp, "--expansion-coefficient", alpha)
    assert "26 °C" in text.stdout and "11.5 µm/(m·K)" in text.stdout
    one = cli("positioning", p, "--material-temperature", temp)
    assert one.returncode == 2 and "--expansion-coefficient" in one.stderr and one.stderr.count("\n") == 1


def test_tolerances_give_pass_fail_in_table_json_and_plot_with_exit_0(tmp_path):
    from datasets.positioning import axis_test, to_frame
    data, _ = axis_test(rng=np.random.default_rng(3), mpe=0.002)
    p = tmp_path / "axis.csv"
    to_frame(data, actual=False).to_csv(p, index=False)
    ref = json.loads(cli("positioning", p, "--mpe", 0.002, "--json").stdout)
    A_um, E_um = ref["A"] * 1e3, ref["E"] * 1e3
    out = cli("positioning", p, "--mpe", 0.002, "--json", "--tolerance", f"A={A_um * 1.1:.4f}",
              "--tolerance", f"e={E_um * 0.9:.4f}", "--plot", tmp_path / "pos.png")
    assert out.returncode == 0, out.stderr
    v = json.loads(out.stdout)["verdict"]
    assert v["overall"] == "FAIL" and [(c["figure"], c["result"]) for c in v["checks"]] == [("A", "PASS"), ("E", "FAIL")]
    assert (tmp_path / "pos.png").stat().st_size > 0
    text = cli("positioning", p, "--mpe", 0.002, "--tolerance", f"A={A_um * 1.1:.4f}")
    assert text.returncode == 0 and "verdict      PASS" in text.stdout
    t, d = shaft()
    xy = write_xy(tmp_path / "xy.csv", t, d)
    r = cli("roundness", xy, "--reference", "mzci", "--tolerance", "RONt=1", "--json")
    assert r.returncode == 0 and json.loads(r.stdout)["verdict"]["checks"][0]["result"] == "FAIL"
    cond = TestConditions(nominal_radius=100.0, nominal_center=(0.0, 0.0), sampling_hz=50.0)
    cw, ccw, _ = circular_test(cond, MachineErrors(squareness=30e-6), seed=2)
    for name, pts in (("cw", cw), ("ccw", ccw)):
        (tmp_path / f"{name}.csv").write_text("x,y\n" + "".join(f"{x:.7f},{y:.7f}\n" for x, y in pts))
    c = cli("circular-test", tmp_path / "cw.csv", tmp_path / "ccw.csv", "--nominal-radius", 100, "--tolerance",
            "G=50", "--json")
    assert c.returncode == 0, c.stderr
    assert json.loads(c.stdout)["verdict"]["overall"] == "PASS"
    bad = cli("roundness", xy, "--tolerance", "G=3")
    assert bad.returncode == 2 and "RONt" in bad.stderr and bad.stderr.count("\n") == 1


def test_fit_plot_quick_look(tmp_path):
    t, d = shaft(n=360)
    xy = write_xy(tmp_path / "xy.csv", t, d)
    for method in ("circle.gauss_newton", "ellipse.halir_flusser"):
        png = tmp_path / f"{method}.png"
        out = cli("fit", method, xy, "--plot", png)
        assert out.returncode == 0, out.stderr
        assert png.read_bytes().startswith(b"\x89PNG")
    out = cli("fit", "circle.kasa", xy, "--plot", tmp_path / "no" / "x.png")
    assert out.returncode == 2 and "does not exist" in out.stderr and out.stderr.count("\n") == 1


def test_multilateration_lengths_in_um_read_as_mm_warn(tmp_path):
    import pandas as pd
    from datasets.multilateration import write_example
    meas, _ = write_example(tmp_path, stations=4, noise=0.0)
    scaled = tmp_path / "um.csv"
    df = pd.read_csv(meas)
    for c in ("x", "y", "z", "length"):
        df[c] = df[c] * 1e3                                    # the file in µm
    df.to_csv(scaled, index=False)
    out = cli("multilaterate", scaled)
    assert "measured lengths" in out.stderr and "--unit um" in out.stderr, out.stderr
    ok = cli("multilaterate", scaled, "--unit", "um")
    assert "measured lengths" not in ok.stderr, ok.stderr


def test_one_page_reports(tmp_path):
    import re
    from datasets.positioning import axis_test, to_frame
    data, _ = axis_test(rng=np.random.default_rng(3), mpe=0.002)
    axis = tmp_path / "axis.csv"
    to_frame(data, actual=False).to_csv(axis, index=False)
    t, d = shaft(n=720)
    xy = write_xy(tmp_path / "xy.csv", t, d)
    cond = TestConditions(nominal_radius=100.0, nominal_center=(0.0, 0.0), sampling_hz=50.0)
    cw, ccw, _ = circular_test(cond, MachineErrors(squareness=30e-6), seed=2)
    bb = tmp_path / "bb.csv"
    bb.write_text("run,x,y\n" + "".join(f"{lab},{x:.7f},{y:.7f}\n" for lab, pts in (("cw", cw), ("ccw", ccw))
                                        for x, y in pts))
    for args in (("positioning", axis, "--mpe", 0.002, "--tolerance", "A=30"), ("roundness", xy, "--tolerance", "RONt=9"),
                 ("circular-test", bb, "--nominal-radius", 100, "--nominal-center", 0, 0, "--tolerance", "G=40")):
        pdf = tmp_path / f"{args[0]}.pdf"
        out = cli(*args, "--report", pdf)
        assert out.returncode == 0, out.stderr
        body = pdf.read_bytes()
        assert body.startswith(b"%PDF") and len(re.findall(rb"/Type\s*/Page[^s]", body)) == 1
        assert "verdict" in out.stdout                         # the page's text is the printed report
    out = cli("roundness", xy, "--report", tmp_path / "missing" / "r.pdf")
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and "does not exist" in out.stderr


def test_history_trends_the_injected_squareness_over_services(tmp_path):
    """Three services of one machine whose squareness grows 10 -> 20 -> 30 µrad (files named out of date
    order): the trend lists them by their test dates with the diagnosed squareness of each."""
    cond = TestConditions(nominal_radius=100.0, nominal_center=(0.0, 0.0), sampling_hz=50.0)
    folder = tmp_path / "machine"
    folder.mkdir()
    for k, (sq, date) in enumerate(((30e-6, "2026-09-01"), (10e-6, "2026-01-10"), (20e-6, "2026-05-03"))):
        cw, ccw, _ = circular_test(cond, MachineErrors(squareness=sq, noise=0.0002), seed=k)
        f = tmp_path / f"run{k}.csv"
        f.write_text("run,x,y\n" + "".join(f"{lab},{x:.7f},{y:.7f}\n" for lab, pts in (("cw", cw), ("ccw", ccw))
                                           for x, y in pts))
        out = cli("circular-test", f, "--nominal-radius", 100, "--nominal-center", 0, 0, "--date", date, "--json")
        assert out.returncode == 0, out.stderr
        (folder / f"{chr(ord('c') - k)}.json").write_text(out.stdout)
    (folder / "notes.json").write_text('{"operator": "A. N. Other"}')          # not a result: skipped
    out = cli("history", folder, "--json", "--plot", tmp_path / "trend.png")
    assert out.returncode == 0, out.stderr
    tests = json.loads(out.stdout)["circular-test"]["tests"]
    assert [t["date"][:10] for t in tests] == ["2026-01-10", "2026-05-03", "2026-09-01"]
    np.testing.assert_allclose([t["squareness"] for t in tests], [10.0, 20.0, 30.0], atol=1.0)   # µrad
    # the servo mismatch without a feed is a length: mm in the JSON results, µm in the trend (never "ms")
    trend = json.loads(out.stdout)["circular-test"]
    assert trend["units"]["servo mismatch"] == "µm"
    by_date = {json.loads(p.read_text())["details"]["conditions"]["date"]: json.loads(p.read_text())
               for p in folder.glob("[abc].json")}
    for t in tests:
        servo = by_date[t["date"][:10]]["diagnostics"]["servo_mismatch"]
        assert servo["unit"] == "mm" and t["servo mismatch"] == pytest.approx(servo["value"] * 1e3)
        assert t["servo mismatch (time)"] is None
    assert (tmp_path / "trend.png").read_bytes().startswith(b"\x89PNG")
    text = cli("history", folder)
    assert "squareness [µrad]" in text.stdout and text.stdout.index("2026-01-10") < text.stdout.index("2026-09-01")
    empty = tmp_path / "empty"
    empty.mkdir()
    bad = cli("history", empty)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "no JSON results" in bad.stderr


def test_magnify_plot_zooms_on_the_corner_of_the_largest_error(tmp_path):
    import methods as m
    from fitbench.plots import pyplot
    from fitbench.plots.magnify import zoom_on_largest_error
    from methods.magnify import MagnifyInput
    s = np.linspace(0, 50, 200)
    ref = np.r_[np.c_[s, 0 * s], np.c_[np.full(199, 50.0), s[1:]]]
    d = np.hypot(ref[:, 0] - 50, ref[:, 1])
    meas = ref + np.c_[0.008 * np.exp(-d ** 2 / 4) * (ref[:, 1] > 0), -0.01 * np.exp(-d ** 2 / 4) * (ref[:, 0] < 50)]
    data = MagnifyInput(ref, meas)
    res = m.fit("magnify.offset", data, eta=200.0)
    fig, ax = pyplot().subplots()
    try:
        inset = zoom_on_largest_error(ax, data, res, 200.0)
        (x0, x1), (y0, y1) = inset.get_xlim(), inset.get_ylim()
        assert x0 < 50 < x1 and y0 < 0 < y1 and x1 - x0 < 0.3 * 50     # the corner, not the whole contour
    finally:
        pyplot().close(fig)
    r = tmp_path / "ref.csv"
    r.write_text("x,y\n" + "".join(f"{x:.6f},{y:.6f}\n" for x, y in ref))
    q = tmp_path / "meas.csv"
    q.write_text("x,y\n" + "".join(f"{x:.6f},{y:.6f}\n" for x, y in meas))
    out = cli("magnify", r, q, "--eta", 200, "--plot", tmp_path / "m.png")
    assert out.returncode == 0 and (tmp_path / "m.png").read_bytes().startswith(b"\x89PNG"), out.stderr


@pytest.mark.parametrize("layout", ["wide", "long"])
def test_positioning_units_in_headers(tmp_path, layout):
    """A laser export 'Target (mm), Run 1 + (µm), ...' is read with its deviations in µm (not mm), and a
    header unit contradicting --deviation-unit is a one-line error."""
    from datasets.io import read_positioning
    from datasets.positioning import axis_test, to_frame
    data, _ = axis_test(rng=np.random.default_rng(4), mpe=0.002)
    long = to_frame(data, actual=False)
    p = tmp_path / f"{layout}.csv"
    if layout == "long":
        long = long.rename(columns={"target": "Target [mm]", "deviation": "Deviation (um)", "run": "Run",
                                    "direction": "Direction"})
        long["Deviation (um)"] *= 1e3
        long.to_csv(p, index=False)
    else:
        wide = {"Target (mm)": data.targets}
        for j in range(data.runs):
            wide[f"Run {j + 1} + (µm)"] = data.up[:, j] * 1e3
            wide[f"Run {j + 1} - (µm)"] = data.down[:, j] * 1e3
        import pandas as pd
        pd.DataFrame(wide).to_csv(p, index=False)
    got, unit, dev_unit = read_positioning(p, with_units=True)
    assert (unit, dev_unit) == ("mm", "µm")
    np.testing.assert_allclose(got.up, data.up, atol=1e-9)
    np.testing.assert_allclose(got.down, data.down, atol=1e-9)
    out = cli("positioning", p, "--mpe", 0.002, "--deviation-unit", "mm")
    assert out.returncode == 2 and "--deviation-unit says mm" in out.stderr and out.stderr.count("\n") == 1
    ok = cli("positioning", p, "--mpe", 0.002, "--json")
    assert ok.returncode == 0 and "warning" not in ok.stderr, ok.stderr
    assert json.loads(ok.stdout)["units"]["input_deviation_unit"] == "µm"


def test_roundness_plot_labels_rings_and_visible_lobes_without_overlap(tmp_path):
    from fitbench.plots import pyplot
    from fitbench.plots.roundness import plot
    t, d = shaft()
    res = methods.fit("roundness.iso12181", np.c_[(R + d) * np.cos(t), (R + d) * np.sin(t)], cutoff_upr=50.0)
    plt = pyplot()
    fig = plt.figure()
    try:
        plot(res, None, into=fig)
        polar, spectrum = fig.axes[0], fig.axes[1]
        labels = [tl.get_text() for tl in polar.get_yticklabels()]
        assert labels and all(lab.endswith("µm") for lab in labels)
        k_min = np.degrees(res.angles[np.argmin(res.deviations)]) % 360
        assert polar.get_rlabel_position() == pytest.approx(k_min)
        lobes = sorted(float(a.xy[0]) for a in spectrum.texts)
        assert lobes and all(b - a > 0.02 * 10 for a, b in zip(lobes, lobes[1:]))
        top = max(x["amplitude"] for x in res.dominant_lobes)
        shown = {int(x) for x in lobes}
        assert all(x["amplitude"] >= 0.05 * top for x in res.dominant_lobes if x["upr"] in shown)
    finally:
        plt.close(fig)


@pytest.mark.parametrize("cmd", [("roundness", "--cutoff", "none"), ("fit", "circle.gauss_newton")])
def test_a_nominal_radius_that_puts_points_at_negative_radius_is_one_line(tmp_path, cmd):
    """A nominal radius of 0.001 mm with deviations down to -4.6 µm placed points across the centre and
    reported a wrong RONt with exit 0; any nominal radius + deviation <= 0 is refused."""
    t, d = shaft(n=720)
    p = write_polar(tmp_path / "p.csv", t, d)
    assert d.min() < -1e-3                                            # some deviation below -1 µm
    out = cli(*cmd, p, "--nominal-radius", 0.001)
    assert out.returncode == 2 and "Traceback" not in out.stderr, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and "<= 0" in out.stderr and "--nominal-radius" in out.stderr
    assert cli(*cmd, p, "--nominal-radius", R).returncode == 0
    with pytest.raises(DataFileError, match="<= 0"):
        read_profile(p, nominal_radius=-abs(d.min()) / 2)


def test_roundness_table_columns_never_touch_without_a_nominal_radius(tmp_path):
    """Without a nominal radius the deviations sit on a circle of 1e6 x their span (a 12-digit radius): the
    radius ran into the centre column ('-0.000170 12592.599899'). Every entry is now at least two spaces from
    its neighbour and right-aligned under its header."""
    t, d = shaft(n=720)
    p = write_polar(tmp_path / "p.csv", t, d * 3)
    out = cli("roundness", p, "--cutoff", "none")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("reference"))
    head, rows = lines[k], lines[k + 2:k + 6]
    assert float(rows[0].split()[-2]) > 1e4                          # the wide radius is there
    ends = [m.end() for m in __import__("re").finditer(r"\S+(?: \S+)*", head)][1:-1]   # right edges of numeric headers
    for row in rows:
        fields = __import__("re").split(r"\s{2,}", row.strip())
        assert len(fields) == 9, row                                  # name, 7 numbers, status: all apart
        for e in ends:
            assert row[e - 1] != " " and row[e] == " ", (row, e)      # right-aligned under the header


def _history_axes(history):
    """The date axes of the history plot as drawn (limits as dates, visible tick labels per panel)."""
    import matplotlib.dates as mdates
    from fitbench.cli.history import plot
    seen = {}

    def save(fig, path):
        fig.canvas.draw()
        axes = [ax for ax in fig.axes if ax.get_title()]
        seen["limits"] = [tuple(mdates.num2date(v).replace(tzinfo=None) for v in ax.get_xlim()) for ax in axes]
        seen["labels"] = [[t.get_text() for t in ax.get_xticklabels() if t.get_visible() and t.get_text()]
                          for ax in axes]
    plot(history, None, save)
    return seen


def test_history_plot_shares_its_dates_and_labels_every_panel():
    """The panels were unshared and fig.autofmt_xdate() hid the upper panels' date labels; a panel with one
    test spanned +-2 years. Now one date axis for all panels, labelled on each, a single date shown over days."""
    import datetime as dt
    row = {"G(b)": 5.0, "squareness": 10.0}
    days = [dt.datetime(2026, 1, 10), dt.datetime(2026, 5, 3), dt.datetime(2026, 9, 1)]
    history = {"circular-test": [(d, f"{k}.json", {**dict.fromkeys(
                   n for _, n, _, _ in __import__("fitbench.cli.history", fromlist=["COLUMNS"]).COLUMNS["circular-test"]),
                   **row}) for k, d in enumerate(days)],
               "roundness": [(dt.datetime(2026, 5, 3), "r.json", {"RONt LSCI": 1.0, "RONt MZCI": 0.9,
                                                                   "RONt MICI": 1.2, "RONt MCCI": 1.1})]}
    seen = _history_axes(history)
    assert len(seen["limits"]) == 2 and seen["limits"][0] == seen["limits"][1]     # one date axis
    lo, hi = seen["limits"][0]
    assert lo < days[0] and hi > days[-1] and (hi - lo) < (days[-1] - days[0]) * 1.2
    assert all(len(labels) >= 2 for labels in seen["labels"]), seen["labels"]      # every panel labelled
    single = _history_axes({"roundness": history["roundness"]})
    lo, hi = single["limits"][0]
    assert lo < dt.datetime(2026, 5, 3) < hi and hi - lo <= dt.timedelta(days=7)
    assert len(single["labels"][0]) >= 2


def test_positioning_and_roundness_take_date_and_machine_for_history(tmp_path):
    """positioning and roundness had no --date: history dated them by the files' modification time. Both now
    record --date and --machine where circular-test does (details.conditions) and history uses the date."""
    import os
    from datasets.positioning import axis_test, to_frame
    data, _ = axis_test(rng=np.random.default_rng(2), mpe=0.002)
    pos = tmp_path / "pos.csv"
    to_frame(data, actual=False).to_csv(pos, index=False)
    t, d = shaft(n=720)
    xy = write_xy(tmp_path / "xy.csv", t, d)
    folder = tmp_path / "machine"
    folder.mkdir()
    for cmd, date in ((("positioning", pos), "2026-03-04"), (("roundness", xy), "2026-02-01"),
                      (("positioning", pos), "2025-12-24")):
        out = cli(*cmd, "--date", date, "--machine", "HBG 130", "--json")
        assert out.returncode == 0, out.stderr
        j = json.loads(out.stdout)
        assert j["details"]["conditions"]["date"] == date and j["details"]["conditions"]["machine"] == "HBG 130"
        f = folder / f"{cmd[0]}-{date}.json"
        f.write_text(out.stdout)
        os.utime(f, (0, 0))                                   # the file time says 1970: the --date must win
    trend = json.loads(cli("history", folder, "--json").stdout)
    assert [t["date"][:10] for t in trend["positioning"]["tests"]] == ["2025-12-24", "2026-03-04"]
    assert [t["date"][:10] for t in trend["roundness"]["tests"]] == ["2026-02-01"]
