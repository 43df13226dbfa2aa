"""Angle + radial deviation files whose angle unit, angle column or revolution count is not what the file says.

Angles in degrees read as radians (a header ``theta [rad]`` over 0..359, or ``--angle-unit rad`` given wrongly) wound
the profile 57 times round: roundness gave RONt 0.34 µm for a 4.08 µm part, circular-test G 1.43 instead of 5.08 µm,
exit 0. They are refused naming the span in revolutions; data that really turns more than once in radians (a
circular test's two runs in one column, with overrun) is still read. Deviations in mm under a µm header (G 0.01 µm,
RONt 0.004 µm, exit 0 without a word) are warned about naming mm. A column in an angle unit is the angle whatever its
name ('C [deg]' was told to be renamed mm). A roundness trace over more than one revolution names the lines to keep.

Angles written in radians but read as degrees (--angle-unit deg, or a header saying deg) are named as such: a
revolution in radians (0 to 6.28) read as degrees is a 6° arc, which roundness refused as open ('no point between
6.3° and 0.0° (a gap of 354°)') without naming the likely cause. Now the line asks whether the angles are in radians
and says what to give; fit (which may fit an arc) notes it."""
from __future__ import annotations

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from profile_lines import circle_lines


def polar_file(path, angles, deviation_um, header="Angle,Radial deviation [um]", direction=None):
    cols = [angles, deviation_um] if direction is None else [direction, angles, deviation_um]
    with open(path, "w") as fh:
        fh.write(header + "\n")
        for row in zip(*cols):
            fh.write(",".join(str(v) if isinstance(v, str) else f"{v:.6f}" for v in row) + "\n")
    return path


def profile_deg(n=360):
    """A closed profile in degrees (0..359 at 1°): 2 µm of 3-lobing."""
    deg = np.arange(n) * 360.0 / n
    return deg, 2.0 * np.cos(np.radians(3 * deg))


def test_degrees_under_a_radian_header_are_refused(tmp_path):
    deg, dev = profile_deg()
    p = polar_file(tmp_path / "degasrad.csv", deg, dev, header="theta [rad],dr [um]")
    turns = f"{np.ptp(deg) / (2 * np.pi):.3g}"            # 359 / 2 pi = 57.1
    for args in (("roundness", p), ("fit", "circle.minimum_zone", p)):
        one_error_line(cli(*args), "span 359 rad", f"({turns} revolutions", "they look like degrees",
                       "correct the header of 'theta [rad]' to [deg]")
    code, out, err = cli("roundness", polar_file(tmp_path / "deg.csv", deg, dev, header="theta [deg],dr [um]"))
    assert code == 0 and "RONt" in out, err


def test_degrees_given_angle_unit_rad_are_refused(tmp_path):
    deg, dev = profile_deg()
    p = polar_file(tmp_path / "ang.csv", deg, dev, header="Angle,Deviation [um]")
    one_error_line(cli("roundness", p, "--angle-unit", "rad"), "they look like degrees", "give --angle-unit deg, not rad")
    code, out, err = cli("roundness", p, "--angle-unit", "deg")
    assert code == 0 and "RONt" in out, err


def test_circular_test_runs_in_degrees_under_a_radian_header(tmp_path):
    deg = np.arange(0, 360, 0.5)
    angles = np.r_[deg[::-1], deg]
    runs = np.r_[["CW"] * len(deg), ["CCW"] * len(deg)]
    p = polar_file(tmp_path / "bb.csv", angles, 3.0 * np.cos(np.radians(2 * angles)),
                   header="Direction,Angle [rad],Deviation [um]", direction=runs)
    one_error_line(cli("circular-test", p, "--nominal-radius", 150), "they look like degrees",
                   "correct the header of 'Angle [rad]' to [deg]")


def test_radians_turning_more_than_once_are_still_read(tmp_path):
    """Both runs of a circular test in one radian column, each unwrapped its own way with 20° of overrun (4.2 pi),
    and a fit of three revolutions in radians: not taken for degrees."""
    t = np.linspace(0, 2 * np.pi + np.radians(20), 760)
    angles = np.r_[-t, t]
    runs = np.r_[["CW"] * len(t), ["CCW"] * len(t)]
    p = polar_file(tmp_path / "bb_rad.csv", angles, 3.0 * np.cos(2 * angles),
                   header="Direction,Angle [rad],Deviation [um]", direction=runs)
    code, out, err = cli("circular-test", p, "--nominal-radius", 150)
    assert code == 0 and "G  CW / CCW" in out and "degrees" not in err, err
    t3 = np.linspace(0, 6 * np.pi, 1080, endpoint=False)
    q = polar_file(tmp_path / "three_turns.csv", t3, 2.0 * np.cos(3 * t3), header="Angle [rad],Deviation [um]")
    code, out, err = cli("fit", "circle.gauss_newton", q, "--nominal-radius", 50)
    assert code == 0 and "degrees" not in err, err


def test_deviations_in_mm_under_a_micrometre_header_are_warned_about(tmp_path):
    """4 µm of 3-lobing written in mm (0.002 .. -0.002) under 'Deviation [um]': read as µm it spans 0.004 µm, below
    the 10 nm any instrument resolves; the warning names the span (the file's own numbers) and mm."""
    deg, dev = profile_deg()
    p = polar_file(tmp_path / "mm_as_um.csv", deg, dev * 1e-3, header="Angle [deg],Deviation [um]")
    span = f"{np.ptp(np.round(dev * 1e-3, 6)):.3g}"      # the numbers in the file, read as µm
    for args in (("roundness", p), ("fit", "circle.minimum_zone", p), ("roundness", p, "--nominal-radius", 10)):
        code, out, err = cli(*args)
        assert code == 0 and f"span {span} µm (read as µm, as the header of 'Deviation [um]' says)" in err, err
        assert "is the column in mm? (correct the header to [mm])" in err and len(err.strip().splitlines()) == 1, err
    q = polar_file(tmp_path / "nounit.csv", deg, dev * 1e-3, header="Angle [deg],Deviation")
    code, out, err = cli("roundness", q, "--unit", "um")
    assert code == 0 and "as --unit says" in err and "give --unit mm" in err, err
    code, out, err = cli("roundness", polar_file(tmp_path / "um.csv", deg, dev, header="Angle [deg],Deviation [um]"))
    assert code == 0 and "span" not in err, err                 # the same trace in µm: nothing to say


def test_circular_test_deviations_in_mm_under_a_micrometre_header(tmp_path):
    deg = np.arange(0, 360, 0.5)
    angles = np.r_[deg[::-1], deg]
    runs = np.r_[["CW"] * len(deg), ["CCW"] * len(deg)]
    p = polar_file(tmp_path / "bb.csv", angles, 3e-3 * np.cos(np.radians(2 * angles)),
                   header="Direction,Angle [deg],Deviation [um]", direction=runs)
    code, out, err = cli("circular-test", p, "--nominal-radius", 150)
    assert code == 0 and "span 0.006 µm" in err and "is the column in mm?" in err, err


def ron_mzci(out):
    return next(ln.split()[4] for ln in out.splitlines() if ln.startswith("minimum zone circles (MZCI)"))


@pytest.mark.parametrize("name", ["Drehwinkel [°]", "C [deg]", "Position [deg]", "Point angle [deg]", "Angle CCW (deg)",
                                  "Theta [rad]"])
def test_a_column_in_an_angle_unit_is_the_angle_whatever_its_name(tmp_path, name):
    """Exports name the angle column as they like; its unit says what it is. Each is read as the same profile under
    'Angle [deg]' (same RONt), never told to rename its unit to mm."""
    deg, dev = profile_deg()
    ang = np.radians(deg) if name.endswith("[rad]") else deg
    p = polar_file(tmp_path / "named.csv", ang, dev, header=f"{name},Deviation (um)")
    code, out, err = cli("roundness", p)
    assert code == 0, err
    code, ref, err = cli("roundness", polar_file(tmp_path / "ref.csv", deg, dev, header="Angle [deg],Deviation (um)"))
    assert ron_mzci(out) == ron_mzci(ref) and float(ron_mzci(ref)) == pytest.approx(4.0, abs=0.01)   # 2 µm x 2


def test_an_angle_column_named_by_columns_among_two_angle_units(tmp_path):
    """Two columns in degrees and none named an angle: asked which; --columns naming one (by name or number) reads
    it as the angle; two angles named are refused saying so; a lone one beside x, y is the points' polar angle."""
    deg, dev = profile_deg()
    p = tmp_path / "two.csv"
    p.write_text("Point angle [deg],Table [deg],Deviation (um)\n" +
                 "".join(f"{a:.6f},{a + 90:.6f},{d:.6f}\n" for a, d in zip(deg, dev)))
    one_error_line(cli("roundness", p), "which two columns?")
    for cols in (("Point angle [deg]", "Deviation (um)"), ("0", "2"), ("2", "0")):
        code, out, err = cli("roundness", p, "--columns", *cols)
        assert code == 0 and float(ron_mzci(out)) == pytest.approx(4.0, abs=0.01), err
    one_error_line(cli("roundness", p, "--columns", "0", "1"), "are both angles", "--columns ANGLE DEVIATION")
    q = tmp_path / "xyc.csv"
    t = np.radians(deg)
    q.write_text("X [mm],Y [mm],C [deg]\n" + "".join(f"{10 * np.cos(a):.6f},{10 * np.sin(a):.6f},{d:.3f}\n"
                                                       for a, d in zip(t, deg)))
    code, out, err = cli("fit", "circle.gauss_newton", q)
    assert code == 0 and "radius" in out, err


def test_an_angle_read_as_a_length_is_not_told_to_be_renamed_mm(tmp_path):
    p = tmp_path / "angles.csv"
    p.write_text("C [deg],Dev [deg]\n" + "".join(f"{a},{a / 100}\n" for a in range(0, 360, 10)))
    err = cli("roundness", p).stderr
    one_error_line(cli("roundness", p), "column 'C [deg]' is an angle (deg) where a length is read", "--columns")
    assert "[mm]" not in err


def test_a_trace_over_more_than_one_revolution_names_the_lines_to_keep(tmp_path):
    """0 to 369.9° at 0.1° (instruments overlap to check closure): was 'two points lie at the same polar angle
    (point 3666) ... (drop a repeated closing point)'. The lines are the file's (header on line 1)."""
    deg = np.round(np.arange(3700) * 0.1, 1)
    dev = 2.0 * np.cos(np.radians(3 * deg)) + 0.5 * deg / deg[-1]          # a drift: the overlap differs
    past = np.flatnonzero(deg >= 360.0)                                    # 100 points, 360.0 .. 369.9
    want = (f"covers 369.9°, more than one revolution ({past.size} points at or beyond 360° from the first, "
            f"lines {past[0] + 2}-{past[-1] + 2}); a roundness profile is one revolution (ISO 12181-1): "
            f"keep lines 2-{past[0] + 1}")
    for label, angles in (("unwrapped", deg), ("wrapped", deg % 360.0)):
        p = polar_file(tmp_path / f"{label}.csv", angles, dev, header="Angle [deg],Deviation [um]")
        one_error_line(cli("roundness", p), f"{label}.csv: the profile " + want)
        code, out, err = cli("fit", "circle.gauss_newton", p, "--nominal-radius", 10)   # a fit takes it
        assert code == 0, err
    first = polar_file(tmp_path / "first.csv", deg[:past[0]], dev[:past[0]], header="Angle [deg],Deviation [um]")
    code, out, err = cli("roundness", first)
    assert code == 0 and "RONt" in out, err


def test_one_closing_point_with_another_value_is_named_by_its_line(tmp_path):
    deg, dev = profile_deg()
    p = polar_file(tmp_path / "closed.csv", np.r_[deg, 360.0], np.r_[dev, dev[0] + 0.05],
                   header="Angle [deg],Deviation [um]")
    one_error_line(cli("roundness", p), f"closed.csv line {deg.size + 2}:", "same polar angle as the first point's (line 2)",
                   f"drop line {deg.size + 2}")
    q = polar_file(tmp_path / "repeat.csv", np.r_[deg, 360.0], np.r_[dev, dev[0]], header="Angle [deg],Deviation [um]")
    code, out, err = cli("roundness", q)                     # the first point written again: dropped with a note
    assert code == 0 and "repeats the first" in out, (out, err)


def test_an_xy_trace_over_more_than_one_revolution_names_both_points(tmp_path):
    """x, y points have no angle column: a trace over more than a revolution is refused by the reader naming the lines
    to keep (their polar angles about their circle's centre); one closing point at the first one's angle with another
    radius is left to the evaluation, whose refusal names both points 1-based in the order given (was 'point 3666',
    a 0-based index of one of them)."""
    deg = np.round(np.arange(3700) * 0.1, 1)
    t = np.radians(deg)
    p = tmp_path / "xy.csv"
    p.write_text("X [mm],Y [mm]\n" + "".join(f"{10 * np.cos(a):.6f},{10 * np.sin(a):.6f}\n" for a in t))
    one_error_line(cli("roundness", p), "covers 369.9° (the points' polar angles about their circle's centre)",
                   "lines 3602-3701", "keep lines 2-3601")
    q = tmp_path / "closed.csv"
    q.write_text("X [mm],Y [mm]\n" + "".join(f"{10 * np.cos(a):.6f},{10 * np.sin(a):.6f}\n" for a in t[:3600])
                 + "10.001000,0.000000\n")
    one_error_line(cli("roundness", q), "(points 1 and 3601 in the order given)", "keep one revolution")


def test_an_overlap_whose_angles_do_not_repeat_is_refused_too(tmp_path):
    """A time-sampled trace (steps of 0.10003°: no angle of the overlap repeats one of the first revolution) was
    evaluated as one profile, exit 0; gradians labelled degrees (0 .. 399.9) likewise, RONt 3.93 of a 4.08 µm part."""
    deg = np.arange(3719) * 0.10003
    dev = 2.0 * np.cos(np.radians(3 * deg)) + 0.8 * deg / deg[-1]
    past = np.flatnonzero(deg >= 360.0)
    p = polar_file(tmp_path / "timed.csv", deg, dev, header="Angle [deg],Deviation [um]")
    one_error_line(cli("roundness", p), f"covers {deg[-1]:.6g}°", f"({past.size} points at or beyond 360°",
                   f"keep lines 2-{past[0] + 1}")
    assert "gon" not in cli("roundness", p).stderr
    gon = np.arange(4000) * 0.1
    q = polar_file(tmp_path / "gon.csv", gon, 2.0 * np.cos(np.radians(3 * 0.9 * gon)), header="Angle [deg],Deviation [um]")
    one_error_line(cli("roundness", q), "covers 399.9°", "in gon (400 a revolution), multiply the column by 0.9")


def test_two_profiles_separated_by_a_blank_line_are_refused(tmp_path):
    """Two diameters exported one after the other (R 10.000 and 10.020 mm, a blank line between): were read as one
    profile, RONt 3.01 µm 'ok'. The blocks are named by their lines (header on line 1, the blank on line 362)."""
    a, b = circle_lines(10.0), circle_lines(10.02, phase=0.5)
    p = tmp_path / "two.csv"
    p.write_text("X [mm],Y [mm]\n" + "\n".join(a) + "\n\n" + "\n".join(b) + "\n")
    for args in (("roundness", p), ("fit", "circle.minimum_zone", p)):
        one_error_line(cli(*args), f"two.csv: 2 blocks of points separated by blank lines (lines 2-{len(a) + 1}, "
                                   f"{len(a) + 3}-{len(a) + len(b) + 2})", "save each block in its own file")
    one = tmp_path / "one.csv"                               # blank lines before the data and at the end: one block
    one.write_text("X [mm],Y [mm]\n\n" + "\n".join(a) + "\n\n\n")
    code, out, err = cli("roundness", one)
    assert code == 0 and "RONt" in out, err


def test_a_blank_line_between_labelled_runs_is_read(tmp_path):
    """A ballbar export's two runs, labelled in a Direction column, separated by a blank line: read as before."""
    deg = np.arange(0, 360, 0.5)
    cw = [f"CW,{a:.3f},{3 * np.cos(np.radians(2 * a)):.4f}" for a in deg[::-1]]
    ccw = [f"CCW,{a:.3f},{3 * np.cos(np.radians(2 * a)):.4f}" for a in deg]
    p = tmp_path / "bb.csv"
    p.write_text("Direction,Angle [deg],Deviation [um]\n" + "\n".join(cw) + "\n\n" + "\n".join(ccw) + "\n")
    code, out, err = cli("circular-test", p, "--nominal-radius", 150)
    assert code == 0 and "G  CW / CCW" in out, err


def test_a_radius_column_holding_deviations_is_warned_about(tmp_path):
    """'Radius (um)' holding the deviations + 10 µm (a form tester's offset): read as radii, a 10 µm circle whose form
    is 40 % of it, RONt 3.89 µm 'ok'. The warning names the range and the fraction (span / median radius)."""
    deg, dev = profile_deg()
    r = dev + 10.0
    p = polar_file(tmp_path / "radius.csv", deg, r, header="Angle (deg),Radius (um)")
    frac = f"{np.ptp(r) / np.median(r):.0%}"
    for args in (("roundness", p), ("fit", "circle.minimum_zone", p)):
        code, out, err = cli(*args)
        assert code == 0 and f"radii in {p} run from 8 to 12 µm (column 'Radius (um)'): they vary by {frac}" in err, err
        assert "name it 'Deviation [µm]'" in err, err
    q = polar_file(tmp_path / "part.csv", deg, 10.0 + dev * 1e-3, header="Angle (deg),Radius (mm)")   # a real R 10
    code, out, err = cli("roundness", q)
    assert code == 0 and "radii" not in err, err
    neg = polar_file(tmp_path / "neg.csv", deg, dev, header="Angle (deg),Radius (um)")
    one_error_line(cli("roundness", neg), "radii must be > 0", "if the column holds radial deviations, name it 'Deviation'")


@pytest.mark.parametrize("text", ["Deviation [µm]\n", "Deviation_um\n", "Radial deviation um\n", ""], ids=["name [unit]",
                                  "one token", "suffix", "no header"])
def test_one_column_of_deviations_says_an_angle_is_needed(tmp_path, text):
    """Radial deviations alone, one per line (equally spaced over the revolution): was 'line 2: 1 field where the
    header (line 1) has 2' (the name split at its space), which sent the user looking for a missing field."""
    deg, dev = profile_deg()
    p = tmp_path / "devonly.txt"
    p.write_text(text + "".join(f"{d:.4f}\n" for d in dev), encoding="utf-8")
    for args in (("roundness", p), ("circular-test", p, "--nominal-radius", 150), ("fit", "circle.kasa", p)):
        one_error_line(cli(*args), "one column of numbers", "add an angle column (i x 360/N deg")
    if text:
        assert f"({text.strip()!r})" in cli("roundness", p).stderr


# ------------------------------------------------------------------- radians read as degrees
@pytest.mark.parametrize("start", [0.0, -np.pi], ids=["0..2pi", "-pi..pi"])
def test_roundness_names_radians_read_as_degrees(tmp_path, start):
    t = np.linspace(start, start + 2 * np.pi, 720, endpoint=False)
    p = polar_file(tmp_path / "polar_rad.csv", t, 2.0 * np.cos(3 * t))
    one_error_line(cli("roundness", p, "--angle-unit", "deg"), "are they in radians?", "give --angle-unit rad")
    code, out, err = cli("roundness", p, "--angle-unit", "rad")   # read as radians: a closed profile, evaluated
    assert code == 0 and "RONt" in out, err


def test_header_saying_deg_is_named(tmp_path):
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    p = polar_file(tmp_path / "polar_rad.csv", t, 2.0 * np.cos(3 * t), header="Angle [deg],Radial deviation [um]")
    one_error_line(cli("roundness", p), "are they in radians?", "correct the header of 'Angle [deg]' to [rad]")


def test_circular_test_names_radians_read_as_degrees(tmp_path):
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    angles = np.r_[t[::-1], t]
    runs = np.r_[["cw"] * len(t), ["ccw"] * len(t)]
    p = polar_file(tmp_path / "ballbar.csv", angles, 3.0 * np.cos(2 * angles),
                   header="Direction,Angle,Radial deviation [um]", direction=runs)
    one_error_line(cli("circular-test", p, "--nominal-radius", 150, "--angle-unit", "deg"),
                   "are they in radians?", "less than the 90° needed")


def test_fit_notes_it_and_a_real_small_arc_in_degrees_is_not_refused(tmp_path):
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    p = polar_file(tmp_path / "polar_rad.csv", t, 2.0 * np.cos(3 * t))
    code, out, err = cli("fit", "circle.gauss_newton", p, "--angle-unit", "deg", "--nominal-radius", 50)
    assert "note: " in out and "are they in radians?" in out, (out, err)
    deg = np.linspace(0, 120, 121)     # a 120° arc in degrees: nothing to ask
    q = polar_file(tmp_path / "arc_deg.csv", deg, 2.0 * np.cos(np.radians(3 * deg)))
    code, out, err = cli("fit", "circle.gauss_newton", q, "--angle-unit", "deg", "--nominal-radius", 50)
    assert code == 0 and "radians" not in out + err, (out, err)
