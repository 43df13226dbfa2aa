"""A header unit fitbench does not read is refused saying what to do, and doing it gives the right figures: 'X [cm]'
said "carries the unit 'cm'; expected a length unit (nm, µm, mm, m, in)" (cm is a length unit); two columns in
different units name the factor that brings one to the other."""
import json
import re

import numpy as np
import pytest

from cli_calls import cli, one_error_line


def ring(n=120, r=5.0, cx=2.0, cy=-1.0, lobes=0.0004):
    t = 2 * np.pi * np.arange(n) / n
    rr = r + lobes * np.cos(3 * t)
    return np.c_[cx + rr * np.cos(t), cy + rr * np.sin(t)]


def write(path, header, cols):
    path.write_text(header + "\n" + "".join(",".join(f"{v:.9g}" for v in row) + "\n" for row in np.c_[cols]),
                    encoding="utf-8")
    return path


def fitted(path):
    out = cli("fit", "circle.gauss_newton", path, "--json", "--no-residuals")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def followed(message: str):
    """The refusal's advice applied: (factor, unit) read from 'multiply ... by F and name ... [UNIT]' (or 'divide ...
    by D': factor 1 / D)."""
    m = re.search(r"(multiply|divide) (?:the column|column '[^']*') by ([0-9.e+-]+) and name (?:its unit \w+ \('[^']*|"
                  r"it '[^']*) \[(\w+)\]'", message)
    assert m, message
    return (float(m.group(2)) if m.group(1) == "multiply" else 1.0 / float(m.group(2))), m.group(3)


def test_a_centimetre_column_says_how_to_convert_and_that_gives_the_circle(tmp_path):
    pts = ring()
    out = cli("fit", "circle.gauss_newton", write(tmp_path / "cm.csv", "X [cm],Y [cm]", pts / 10))
    one_error_line(out, "column 'X [cm]' carries the unit 'cm', which fitbench does not read (it reads nm, µm, mm, m, "
                        "in)")
    factor, unit = followed(out.stderr)
    assert unit == "mm"
    d = fitted(write(tmp_path / "mm.csv", f"X [{unit}],Y [{unit}]", pts / 10 * factor))
    assert d["radius"] == pytest.approx(5.0, abs=1e-6) and d["center"] == pytest.approx([2.0, -1.0], abs=1e-6)


def test_two_columns_in_different_units_name_the_factor_that_makes_them_one(tmp_path):
    pts = ring()
    out = cli("fit", "circle.gauss_newton", write(tmp_path / "mixed.csv", "X [mm],Y [um]", np.c_[pts[:, 0], pts[:, 1] * 1e3]))
    one_error_line(out, "the columns X [mm], Y [um] are in different units (mm, µm)")
    factor, unit = followed(out.stderr)
    d = fitted(write(tmp_path / "one.csv", f"X [mm],Y [{unit}]", np.c_[pts[:, 0], pts[:, 1] * 1e3 * factor]))
    assert d["radius"] == pytest.approx(5.0, abs=1e-6)


def test_an_angle_in_milliradians_says_how_to_convert(tmp_path):
    t = np.arange(0, 360, 2.0)
    dev = 2.0 * np.cos(np.radians(3 * t))
    out = cli("roundness", write(tmp_path / "mrad.csv", "Angle [mrad],Deviation [um]", np.c_[np.radians(t) * 1e3, dev]))
    one_error_line(out, "column 'Angle [mrad]' carries the unit 'mrad', which fitbench does not read (it reads deg, "
                        "rad)")
    factor, unit = followed(out.stderr)
    good = write(tmp_path / "rad.csv", f"Angle [{unit}],Deviation [um]", np.c_[np.radians(t) * 1e3 * factor, dev])
    ref = write(tmp_path / "deg.csv", "Angle [deg],Deviation [um]", np.c_[t, dev])
    got, want = (json.loads(cli("roundness", p, "--json").stdout) for p in (good, ref))
    assert got["references"]["mzci"]["RONt"] == pytest.approx(want["references"]["mzci"]["RONt"], rel=1e-9)


@pytest.mark.parametrize("command, header", [
    (("fit", "circle.kasa"), "X [%],Y [%]"),
    (("positioning",), "Target [cm],Run 1 + (µm),Run 1 - (µm),Run 2 + (µm),Run 2 - (µm)"),
])
def test_other_commands_and_unknown_units_say_what_to_do(tmp_path, command, header):
    rows = np.c_[np.arange(6.0), np.ones((6, header.count(",")))] if command[0] == "positioning" else ring() / 10
    out = cli(*command, write(tmp_path / "f.csv", header, rows))
    if "%" in header:
        one_error_line(out, "column 'X [%]' carries the unit '%', not a length unit: name the column's unit in the "
                            "header (nm, µm, mm, m, in; e.g. 'X [mm]')")
    else:
        one_error_line(out, "column 'Target [cm]' carries the unit 'cm'", "multiply the column by 10", "'Target [mm]'")


@pytest.mark.parametrize("unit, per_degree", [("arcmin", 60), ("arcsec", 3600)])
def test_minutes_and_seconds_of_arc_are_converted_exactly(tmp_path, unit, per_degree):
    """The advice divides by 60 or 3600: 'multiply the column by 0.0166667' (a rounded 1/60) stretched 360° to
    360.0007°; dividing as said gives the degree file's angles to the last bit, and its figures."""
    t = np.arange(0, 360, 2.0)
    dev = 2.0 * np.cos(np.radians(3 * t))
    out = cli("roundness", write(tmp_path / f"{unit}.csv", f"Angle [{unit}],Deviation [um]", np.c_[t * per_degree, dev]))
    one_error_line(out, f"column 'Angle [{unit}]' carries the unit '{unit}'",
                   f"divide the column by {per_degree} and name its unit deg ('Angle [deg]')")
    divisor = float(re.search(r"divide the column by ([0-9.]+)", out.stderr).group(1))
    assert np.array_equal(t * per_degree / divisor, t)       # the degrees written, to the last bit
    got = json.loads(cli("roundness", write(tmp_path / "conv.csv", "Angle [deg],Deviation [um]",
                                            np.c_[t * per_degree / divisor, dev]), "--json").stdout)
    want = json.loads(cli("roundness", write(tmp_path / "deg.csv", "Angle [deg],Deviation [um]", np.c_[t, dev]),
                          "--json").stdout)
    assert got["references"]["mzci"]["RONt"] == want["references"]["mzci"]["RONt"]


def test_an_inch_column_beside_mm_is_divided_by_25_4(tmp_path):
    pts = ring()
    out = cli("fit", "circle.gauss_newton", write(tmp_path / "mixed.csv", "X [in],Y [mm]", np.c_[pts[:, 0] / 25.4, pts[:, 1]]))
    one_error_line(out, "the columns X [in], Y [mm] are in different units (in, mm)",
                   "divide column 'Y [mm]' by 25.4 and name it 'Y [in]'")
    factor, unit = followed(out.stderr)
    d = fitted(write(tmp_path / "one.csv", f"X [in],Y [{unit}]", np.c_[pts[:, 0] / 25.4, pts[:, 1] * factor]))
    assert d["radius"] == pytest.approx(5.0, abs=1e-6)

