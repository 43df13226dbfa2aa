"""What a reader must not decide silently: the unit of a deviation column that names none, which two of three
coordinate columns to take, whether a spreadsheet is text. Each case through the command a user runs (in this
process, as tests/test_frontdoor.py does) and, where the reader decides, through the API."""
from __future__ import annotations

import io
import json
import re

import numpy as np
import pytest

from cli_calls import cli


def polar_file(path, dev_um, header="Angle [deg],Deviation", sep=","):
    """An angle + radial-deviation export whose deviation column names no unit (values in µm, as written)."""
    theta = np.arange(len(dev_um)) * 360.0 / len(dev_um)
    path.write_text(header + "\n" + "\n".join(f"{a:.4f}{sep}{d:.4f}" for a, d in zip(theta, dev_um)) + "\n")
    return path


def lobed(n=720):
    t = np.arange(n) * 2 * np.pi / n
    return 1.5 * np.cos(3 * t) + 0.6 * np.cos(2 * t)   # µm: RONt (unfiltered) about 4 µm


# ------------------------------------------------------------------------ a deviation column without a unit
def test_roundness_says_its_input_unit_and_warns_about_unitless_micrometres(tmp_path):
    p = polar_file(tmp_path / "polar_nounit.csv", lobed())
    got = cli("roundness", p, "--cutoff", "none", "--reference", "lsci")
    assert got.returncode == 0, got.stderr
    first = got.stdout.splitlines()[0]
    assert "roundness: input unit mm" in first, first
    assert "'Deviation' names no unit: read as mm" in got.stdout
    warning = [ln for ln in got.stderr.splitlines() if "warning" in ln]
    assert len(warning) == 1 and "names no unit" in warning[0] and "--unit um" in warning[0] and "2.1 mm" in warning[0], got.stderr
    # declared: no warning, the µm figures (RONt of 1.5 cos 3t + 0.6 cos 2t: about 3.9 µm, not 3900)
    um = cli("roundness", p, "--cutoff", "none", "--reference", "lsci", "--unit", "um", "--json")
    assert um.returncode == 0 and "warning" not in um.stderr, um.stderr
    d = json.loads(um.stdout)
    assert d["input_unit"] == "µm" and 3.5e-3 < d["references"]["lsci"]["RONt"] < 4.5e-3
    assert "warning" not in cli("roundness", p, "--unit", "mm").stderr          # mm confirmed
    # a column that names its unit is read in it without a note
    named = polar_file(tmp_path / "polar_um.csv", lobed(), header="Angle [deg],Deviation [um]")
    got = cli("roundness", named, "--cutoff", "none")
    assert "input unit µm (converted to mm)" in got.stdout.splitlines()[0] and "names no unit" not in got.stdout
    assert "warning" not in got.stderr


def test_plausible_unitless_deviations_are_noted_not_warned(tmp_path):
    p = polar_file(tmp_path / "mm.csv", lobed() * 1e-3)          # 0.0021 mm: plausible as mm
    got = cli("roundness", p)
    assert got.returncode == 0 and "warning" not in got.stderr, got.stderr
    assert "names no unit: read as mm" in got.stdout


def test_circular_test_warns_about_unitless_ballbar_deviations(tmp_path):
    t = np.arange(720) * 0.5
    dev = 0.8 * np.cos(np.radians(2 * t)) + 0.1   # µm, as the ballbar wrote them, no unit in the header
    cw = tmp_path / "bbn_cw.txt"
    ccw = tmp_path / "bbn_ccw.txt"
    for path, angles in ((cw, t[::-1]), (ccw, t)):
        path.write_text("Angle [deg]\tDeviation\n" + "\n".join(f"{a:.4f}\t{d:.4f}" for a, d in zip(angles, dev)) + "\n")
    got = cli("circular-test", cw, ccw, "--nominal-radius", 150)
    assert "input unit mm" in got.stdout.splitlines()[0]
    lines = [ln for ln in got.stderr.splitlines() if "names no unit" in ln]
    assert len(lines) == 2 and all("--unit um" in ln for ln in lines), got.stderr
    um = cli("circular-test", cw, ccw, "--nominal-radius", 150, "--unit", "um", "--json")
    assert um.returncode == 0 and "names no unit" not in um.stderr
    assert json.loads(um.stdout)["G_cw"] == pytest.approx(1.6e-3, rel=1e-3)   # 1.6 µm, not 1.6 mm


def test_reader_api_flags_the_assumed_unit(tmp_path):
    from datasets.io import read_profile
    from methods.units import UnitWarning
    p = polar_file(tmp_path / "p.csv", lobed())
    with pytest.warns(UnitWarning, match="names no unit"):
        got = read_profile(p)
    assert got.unit == "mm" and got.unit_assumed
    assert not read_profile(p, unit="um").unit_assumed


# ------------------------------------------------------------------------ three coordinate columns
def zx_circle(path, rng, sign=1.0):
    """A R 150 mm circle in the ZX plane written with all three coordinates (y = 25 mm within instrument noise),
    as a CMM / tracker export of a vertical-plane test writes it."""
    t = sign * np.arange(720) * 2 * np.pi / 720
    x, z = 150 * np.sin(t), 150 * np.cos(t) + 0.005 * np.cos(2 * t)
    y = 25 + rng.normal(0, 1e-4, t.size)
    path.write_text("x,y,z\n" + "\n".join(f"{a:.6f},{b:.6f},{c:.6f}" for a, b, c in zip(x, y, z)) + "\n")
    return path


def test_xyz_file_is_never_read_as_xy_without_a_choice(tmp_path, rng):
    from datasets.io import DataFileError, read_points, read_profile
    ccw, cw = zx_circle(tmp_path / "zx_ccw.csv", rng), zx_circle(tmp_path / "zx_cw.csv", rng, -1.0)
    for got in (cli("fit", "circle.gauss_newton", ccw), cli("roundness", ccw),
                cli("circular-test", cw, ccw, "--nominal-radius", 150), cli("magnify", cw, ccw, "--eta", 10)):
        assert got.returncode == 2 and "Traceback" not in got.stderr, (got.stdout, got.stderr)
        err = got.stderr.strip().splitlines()
        assert len(err) == 1 and "three coordinate columns (x, y, z)" in err[0] and "give --plane zx" in err[0], err
    for read in (read_points, read_profile):
        with pytest.raises(DataFileError, match="three coordinate columns"):
            read(ccw)
    # the user's choice is read as given: the ZX circle is the circle
    d = json.loads(cli("fit", "circle.gauss_newton", ccw, "--plane", "zx", "--json").stdout)
    assert d["radius"] == pytest.approx(150.0, abs=1e-3)
    assert read_points(ccw, ("z", "x")).shape == (720, 2)


def test_two_columns_that_are_not_the_plane_are_named_not_blamed_on_the_unit(tmp_path, rng):
    ccw, cw = zx_circle(tmp_path / "zx_ccw.csv", rng), zx_circle(tmp_path / "zx_cw.csv", rng, -1.0)
    for got in (cli("roundness", ccw, "--columns", "x", "y"),
                cli("circular-test", cw, ccw, "--nominal-radius", 150, "--columns", "x", "y")):
        assert got.returncode == 2, got.stderr
        err = got.stderr.strip().splitlines()[-1]
        assert "lie on a straight line" in err and "--plane" in err, err
        assert "µm" not in err and "same polar angle" not in err
    fit = cli("fit", "circle.gauss_newton", ccw, "--columns", "x", "y")
    assert re.search(r"warning: .*lie on a straight line", fit.stderr), fit.stderr


# ------------------------------------------------------------------------ spreadsheets and other binary files
def test_spreadsheets_archives_and_pdfs_are_named_not_read_as_cp1252(tmp_path):
    import gzip
    import zipfile
    from datasets.io import DataFileError, read_points
    xlsx = tmp_path / "ccw.xlsx"
    with zipfile.ZipFile(xlsx, "w") as z:     # what Excel saves: a zip of XML parts
        z.writestr("[Content_Types].xml", "<Types/>")
        z.writestr("xl/worksheets/sheet1.xml", "<worksheet><sheetData><row><c t='inlineStr'><is><t>x</t></is></c>"
                                               "</row></sheetData></worksheet>")
    xls = tmp_path / "ccw.xls"
    xls.write_bytes(b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + bytes(504) + "x;y µ°".encode("cp1252") * 20)
    gz = tmp_path / "ccw.csv.gz"
    gz.write_bytes(gzip.compress(b"x,y\n1,2\n3,4\n5,7\n"))
    pdf = tmp_path / "report.pdf"
    pdf.write_bytes(b"%PDF-1.7\n%\xe2\xe3\xcf\xd3\n1 0 obj\n")
    cases = {xlsx: "an Excel workbook (a zip archive), not a text table: save it as CSV",
             xls: "an Excel 97-2003 workbook", gz: "gzip-compressed", pdf: "a PDF document"}
    for path, said in cases.items():
        for command in (("fit", "circle.kasa", path), ("roundness", path), ("positioning", path),
                        ("multilaterate", path), ("circular-test", path, path, "--nominal-radius", 150)):
            got = cli(*command)
            err = got.stderr.strip().splitlines()
            assert got.returncode == 2 and len(err) == 1, (command, got.stderr)
            assert said in err[0] and "cp1252" not in err[0] and "no data lines" not in err[0], err
        with pytest.raises(DataFileError, match="not a text table"):
            read_points(path)
