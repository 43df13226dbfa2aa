"""Exports that used to be read as wrong numbers with exit 0, or refused with a traceback or a misleading hint:
digit grouping read as decimal commas, a units row under the header, a file cut in the middle of its last
number, a header with more names than the rows have fields, grouped numbers and a Unicode minus, header units
of the multilateration reader, a unit in braces. Every file is small and written here."""
from __future__ import annotations

import io
import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line  # the CLI in this process, and its one-line error
from datasets.io import (SMALL_FILE_BYTES, DataFileError, decimal_marks, read_multilateration, read_points,
                         read_positioning, read_profile)


def circle(n, r=20.0, cx=0.0, cy=0.0):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t)])


def wide_positioning(targets, fmt=lambda v: f"{v:.4f}", tfmt=lambda t: f"{t:g}", sep="\t", header=None):
    """A wide ISO 230-2 table (target, 5 runs up, 5 runs down) with deviations in µm."""
    rng = np.random.default_rng(4)
    head = header or sep.join(["Target (mm)"] + [f"Run {k} Forward (µm)" for k in range(1, 6)]
                              + [f"Run {k} Reverse (µm)" for k in range(1, 6)])
    rows = [sep.join([tfmt(t)] + [fmt(v) for v in rng.normal(2.0, 1.5, 10)]) for t in targets]
    return [head] + rows


# ------------------------------------------------------------------ digit grouping is not a decimal comma
def test_a_grouped_target_beside_decimal_points_is_refused_naming_line_and_token(tmp_path):
    """Excel's "Text (Tab delimited)" writes numbers as displayed: the 1000 mm target as '1,000' beside
    deviations '3.7308'; it was read as 1 mm (exit 0)."""
    path = tmp_path / "tab.txt"
    lines = wide_positioning(range(0, 1001, 100), tfmt=lambda t: f"{t:,}")
    assert lines[11].startswith("1,000\t")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(DataFileError, match=r"line 12: '1,000' looks like a thousands separator.*export without digit "
                                            r"grouping"):
        read_positioning(path)
    one_error_line(cli("positioning", path), "line 12", "'1,000'", "thousands separator")


def test_an_all_grouped_nm_export_is_refused_as_ambiguous(tmp_path):
    """The same export in nm with '#,##0' everywhere ('2,908', '-1,140', '25'): every grouped number was read
    /1000 (A 2.673 µm instead of 9.418 µm)."""
    path = tmp_path / "nm.txt"
    lines = wide_positioning(range(0, 1001, 100), fmt=lambda v: f"{round(v * 1000):,}", tfmt=lambda t: f"{t:,}")
    path.write_text("\n".join(lines).replace("(µm)", "(nm)") + "\n", encoding="utf-8")
    with pytest.raises(DataFileError, match="looks like a thousands separator.*without one"):
        read_positioning(path)


@pytest.mark.parametrize("n", [60, 3000])
def test_a_grouped_coordinate_in_a_points_file_is_refused_at_any_size(tmp_path, n):
    """Below the small-file size the comma was read as a decimal comma; above it (past the sniffed lines) the
    pandas parser refused it with a misleading --skip-rows hint."""
    pts = circle(n, r=600.0, cx=800.0)
    lines = ["x\ty"] + [f"{x:,.6f}\t{y:.6f}" for x, y in pts]
    path = tmp_path / "grouped.txt"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert (path.stat().st_size > SMALL_FILE_BYTES) == (n == 3000)
    first = next(k for k, ln in enumerate(lines) if "," in ln) + 1
    with pytest.raises(DataFileError, match=f"line {first}: '.*' looks like a number with a thousands separator"):
        read_points(path)


def test_grouped_numbers_whose_small_integers_come_late_are_refused(tmp_path):
    """The first 200 lines (the sniffed ones) hold only '1,234'-shaped numbers; an integer below 1000 comes
    later: every line of a small file is checked."""
    lines = ["x;y"] + [f"{1000 + 7 * k:,};{2000 + 3 * k:,}" for k in range(300)] + ["25;-80"]
    path = tmp_path / "late.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert path.stat().st_size <= SMALL_FILE_BYTES
    with pytest.raises(DataFileError, match="line 2: '1,000' looks like a thousands separator.*line 302 writes '25'"):
        read_points(path)


def grouped_then(tmp_path, tail, head=None, n=6000):
    """A 'x;y' file of ``n`` lines (> SMALL_FILE_BYTES: pandas' C parser reads it) whose x are ``head`` (default
    '1,234'-shaped numbers, >= 1000 with ',' grouping) and then ``tail`` (x fields placed in its last lines)."""
    head = head or [f"{1000 + 7 * k:,}" for k in range(n - len(tail))]
    xs = [*head[:n - len(tail)], *tail]
    lines = ["x;y"] + [f"{x};{k},{k % 97:04d}" for k, x in enumerate(xs)]
    path = tmp_path / "late_big.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert path.stat().st_size > SMALL_FILE_BYTES
    return path, lines


def test_grouped_numbers_whose_small_integers_come_late_are_refused_in_a_large_file(tmp_path):
    """The same as above past the small-file size: the sniffed lines alone decided, and '1,000' was read as 1.0
    (and '25' as 25) without a word."""
    path, lines = grouped_then(tmp_path, ["25"])
    with pytest.raises(DataFileError, match=f"line 2: '1,000' looks like a thousands separator.*line {len(lines)} "
                                            "writes '25'"):
        read_points(path)
    one_error_line(cli("fit", "circle.kasa", path), "line 2:", "thousands separator", f"line {len(lines)} writes '25'")
    path, lines = grouped_then(tmp_path, ["2,908"], head=["25", "-80", "7"] * 2000)   # integers first, grouping later
    with pytest.raises(DataFileError, match=f"line {len(lines)}: '2,908' looks like a thousands separator.*line 2 "
                                            "writes '25'"):
        read_points(path)


@pytest.mark.parametrize("tail", [["12,5", "25"],          # a comma field that is no grouping: decimal commas
                                  ["2,908e0", "25"],       # an exponent: not grouping (checked line by line)
                                  [",5", "25"],            # unreadable with ',' as thousands separator
                                  ["0,000", "25"],         # a zero with decimals: the column is not grouping
                                  ["25"], ["2,908", "-7"], ["1,234", "0", "999"]])
def test_a_large_file_is_judged_as_a_small_one(tmp_path, tail):
    """Every line of a large file of decimal commas is judged by the rule of the small files
    (datasets.io.decimal_marks over all its lines): refused or read alike."""
    path, lines = grouped_then(tmp_path, tail)
    rows = [(k, ln.split(";")[:1]) for k, ln in enumerate(lines[1:], start=2)]
    try:
        decimal_marks(str(path), rows)
        want = None
    except DataFileError as exc:
        want = str(exc)
    if want is None:
        got = read_points(path)
        np.testing.assert_array_equal(got[:, 0], [float(ln.split(";")[0].replace(",", ".")) for ln in lines[1:]])
    else:
        with pytest.raises(DataFileError) as exc:
            read_points(path)
        assert str(exc.value) == want


def test_decimal_points_and_decimal_commas_in_one_file_are_refused(tmp_path):
    path = tmp_path / "mixed.csv"
    path.write_text("x;y\n1,5;2,25\n3.5;4,75\n5,5;6,25\n", encoding="utf-8")
    with pytest.raises(DataFileError, match="one decimal mark"):
        read_points(path)
    big = tmp_path / "mixed_big.csv"
    lines = ["x;y"] + [f"{x:.6f};{y:.6f}".replace(".", ",") for x, y in circle(3000)]
    lines[2500] = lines[2500].replace(",", ".", 1)
    big.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(DataFileError, match="line 2501: .* has a decimal point where the file's numbers have decimal "
                                            "commas"):
        read_points(big)


@pytest.mark.parametrize("fmt", ["{:.4f}", "{:.3f}"])
def test_genuine_decimal_comma_files_keep_working(tmp_path, fmt):
    """Semicolon-separated decimal commas (3 decimals too: a column of 'd,ddd' alone cannot be told from
    grouping and is read as decimals), with an integer zero among them."""
    pts = circle(360, r=3.0, cx=1.5, cy=-0.7) * 1e3
    lines = ["X [µm];Y [µm]"] + [f"{fmt.format(x)};{fmt.format(y)}".replace(".", ",") for x, y in pts]
    lines[5] = "0;" + lines[5].split(";")[1]
    path = tmp_path / "dc.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    got = read_points(path)
    want = np.array([[float(v.replace(",", ".")) for v in ln.split(";")] for ln in lines[1:]]) * 1e-3
    np.testing.assert_array_equal(got, want)


# ------------------------------------------------------------------ a units row under the header
def pin_files(tmp_path, sep=";"):
    """A 6 mm pin in µm with decimal commas: the header with units, and header + units row."""
    pts = circle(720, r=3000.0, cx=1500.0, cy=-700.0)
    pts += 0.5 * np.column_stack([np.cos(np.arange(720) * 0.1)] * 2)
    data = [f"{x:.4f}{sep}{y:.4f}".replace(".", ",") for x, y in pts]
    ok, row = tmp_path / "ok.csv", tmp_path / "units_row.csv"
    ok.write_text("\n".join([f"X [µm]{sep}Y [µm]"] + data) + "\n", encoding="utf-8")
    row.write_text("\n".join([f"X{sep}Y", f"µm{sep}µm"] + data) + "\n", encoding="utf-8")
    return ok, row


def test_a_units_row_under_the_header_gives_the_units(tmp_path):
    """'X;Y' then 'µm;µm': was refused with the hint --skip-rows 1, which read the µm values as mm (RONt
    982 µm instead of 0.98 µm)."""
    ok, row = pin_files(tmp_path)
    np.testing.assert_array_equal(read_points(row), read_points(ok))
    assert abs(read_points(row)[:, 0].mean() - 1.5) < 1e-3   # mm
    a, b = cli("roundness", ok, "--json"), cli("roundness", row, "--json")
    assert a.returncode == b.returncode == 0, (a.stderr, b.stderr)
    ja, jb = json.loads(a.stdout), json.loads(b.stdout)
    assert ja["form_error"] == jb["form_error"] < 0.01 and ja["raw_lsci"] == jb["raw_lsci"]   # mm


def test_a_header_of_unit_names_is_refused_and_no_hint_makes_one(tmp_path):
    _, row = pin_files(tmp_path)
    one_error_line(cli("roundness", row, "--skip-rows", "1"), "line 2", "names units, not columns", "drop --skip-rows")
    pre = tmp_path / "preamble.csv"
    pre.write_text("Roundness export\nOperator;A. N. Other\n" + row.read_text(encoding="utf-8"), encoding="utf-8")
    out = cli("fit", "circle.kasa", pre)
    one_error_line(out, "--skip-rows 2 ")     # the header line kept, the units row under it read as units
    np.testing.assert_array_equal(read_points(pre, skip_rows=2), read_points(row))


def test_a_polar_units_row_gives_the_angle_unit(tmp_path):
    t = np.arange(0, 360, 0.5)
    dev = 2.0 * np.cos(np.radians(3 * t))
    data = [f"{a:.4f};{d:.4f}".replace(".", ",") for a, d in zip(t, dev)]
    row, named = tmp_path / "polar_row.csv", tmp_path / "polar.csv"
    row.write_text("\n".join(["Angle;Radial deviation", "deg;µm"] + data) + "\n", encoding="utf-8")
    named.write_text("\n".join(["Angle [deg];Radial deviation [µm]"] + data) + "\n", encoding="utf-8")
    got = read_profile(row, nominal_radius=10.0)
    assert got.angle_unit == "deg" and got.unit == "µm"
    np.testing.assert_array_equal(got.runs[0][1], read_profile(named, nominal_radius=10.0).runs[0][1])


@pytest.mark.parametrize("units, match", [("mm;mm", None), ("cm;cm", "carries the unit 'cm'"),
                                          ("[µm];[µm]", None)])
def test_units_rows_known_and_unknown(tmp_path, units, match):
    path = tmp_path / "u.csv"
    path.write_text("X;Y\n" + units + "\n" + "\n".join(f"{x:.3f};{y:.3f}" for x, y in circle(50)) + "\n",
                    encoding="utf-8")
    if match:
        with pytest.raises(DataFileError, match=match):
            read_points(path)
    else:
        np.testing.assert_allclose(read_points(path), np.round(circle(50), 3) * (1e-3 if "µ" in units else 1))


def test_a_units_row_contradicting_the_header_is_refused(tmp_path):
    path = tmp_path / "u.csv"
    path.write_text("X [mm];Y [mm]\nµm;µm\n1;2\n3;4\n5;6\n", encoding="utf-8")
    with pytest.raises(DataFileError, match="line 2: the units row says µm for column 'X \\[mm\\]'"):
        read_points(path)


def test_a_units_row_in_a_positioning_table(tmp_path):
    named = wide_positioning(range(0, 501, 100), sep=";")
    plain = named[0].replace(" (mm)", "").replace(" (µm)", "")
    row = tmp_path / "row.csv"
    row.write_text("\n".join([plain, ";".join(["mm"] + ["µm"] * 10)] + named[1:]) + "\n", encoding="utf-8")
    ok = tmp_path / "ok.csv"
    ok.write_text("\n".join(named) + "\n", encoding="utf-8")
    a, b = read_positioning(row, with_units=True), read_positioning(ok, with_units=True)
    assert a[1:] == b[1:] == ("mm", "µm")
    np.testing.assert_array_equal(a[0].targets, b[0].targets)
    np.testing.assert_array_equal(a[0].up, b[0].up)
    np.testing.assert_array_equal(a[0].down, b[0].down)


# ------------------------------------------------------------------ a file cut in its last number
@pytest.mark.parametrize("n", [60, 3000])
def test_a_file_cut_in_its_last_number_is_refused(tmp_path, n):
    """A copy cut 5 characters before its end ('1046.207378,393.5', no line end) was read (G tripled)."""
    text = "x,y\n" + "\n".join(f"{x:.6f},{y:.6f}" for x, y in circle(n, r=299.0, cx=1200.0, cy=650.0)) + "\n"
    path = tmp_path / "cut.csv"
    path.write_text(text[:-6], encoding="utf-8")
    with pytest.raises(DataFileError, match=f"line {n + 1}: the file ends without a line end in '.*', which has 1 "
                                            "digit.* other numbers have 6: the file looks cut"):
        read_points(path)
    whole = tmp_path / "whole.csv"       # a complete last line without a line end is read
    whole.write_text(text[:-1], encoding="utf-8")
    assert read_points(whole).shape == (n, 2)


def test_a_positioning_table_cut_in_its_last_number_is_refused(tmp_path):
    path = tmp_path / "cut.csv"
    path.write_text("\n".join(wide_positioning(range(0, 501, 100), sep=","))[:-3], encoding="utf-8")
    one_error_line(cli("positioning", path), "line 7", "the file looks cut")


# ------------------------------------------------------------------ fewer fields than the header names
@pytest.mark.parametrize("text", ["x,y\n1\n2\n3\n4\n", "x y\n1\n2\n3\n"])   # one named column: test_polar_angle_units
def test_rows_shorter_than_the_header_are_one_line(tmp_path, text):
    path = tmp_path / "short.txt"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(DataFileError, match="line 2: 1 field where the header \\(line 1\\) has 2"):
        read_points(path)
    one_error_line(cli("roundness", path), "line 2: 1 field where the header")
    one_error_line(cli("fit", "circle.kasa", path), "line 2: 1 field where the header")


def test_a_one_line_preamble_over_shorter_rows_still_gets_the_skip_rows_hint(tmp_path):
    path = tmp_path / "pre.txt"
    path.write_text("Ballbar export 2026\n" + "\n".join(f"{x:.4f} {y:.4f}" for x, y in circle(20)) + "\n",
                    encoding="utf-8")
    one_error_line(cli("fit", "circle.kasa", path), "line 2: 2 fields where the header (line 1) has 3",
                   "give --skip-rows 1 ")


@pytest.mark.parametrize("sep", [";", ","])
def test_a_header_with_a_trailing_separator_is_still_read(tmp_path, sep):
    path = tmp_path / "trail.csv"
    path.write_text(f"X{sep}Y{sep}\n" + "\n".join(f"{x:.6f}{sep}{y:.6f}" for x, y in circle(50)) + "\n",
                    encoding="utf-8")
    np.testing.assert_array_equal(read_points(path), np.round(circle(50), 6))


def test_rows_shorter_than_the_header_in_a_study_are_one_line(tmp_path, capsys):
    from experiments import run as runner
    (tmp_path / "r15.txt").write_text("x,y\n1\n2\n3\n4\n", encoding="utf-8")
    study = tmp_path / "short.toml"
    study.write_text('name = "short"\ntitle = "t"\nseed = 7\n[[datasets]]\nfile = "r15.txt"\n[[methods]]\n'
                     'id = "circle.kasa"\n', encoding="utf-8")
    code = runner.main([str(study), "--out", str(tmp_path / "out"), "--jobs", "1", "--no-report"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "line 2: 1 field where the header (line 1) has 2" in err and "\n" not in err, err


# ------------------------------------------------------------------ grouped numbers, dashes and the Unicode minus
@pytest.mark.parametrize("token, says", [("1.045,933304", "thousands separator ('.')"),
                                         ("1\u00a0045,933304", "no-break space (U+00A0)"),
                                         ("1\u202f045,933304", "narrow no-break space (U+202F)"),
                                         ("1 045,933304", "thousands separator (a space)"),
                                         ("1'045,933304", "thousands separator (an apostrophe)"),
                                         ("\u2013154,066696", "an en dash '\u2013' (U+2013), not a minus sign"),
                                         ("\u2012154,066696", "a figure dash '\u2012' (U+2012), not a minus sign"),
                                         ("\uff0d154,066696", "a fullwidth hyphen-minus '\uff0d' (U+FF0D)")])
@pytest.mark.parametrize("n", [150, 3000])
def test_grouped_numbers_and_dashes_are_named_without_a_skip_rows_hint(tmp_path, token, says, n):
    """x > 1000 mm written with grouping: the hint was '--skip-rows 103' (the first ungrouped row). A dash is not
    read as a minus sign (it also marks ranges and empty cells): it is named."""
    pts = circle(n, r=300.0, cx=700.0)
    lines = ["X;Y"] + [f"{x:.6f};{y:.6f}".replace(".", ",") for x, y in pts]
    lines[1] = f"{token};393,728548"
    path = tmp_path / "g.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    out = cli("fit", "circle.kasa", path)
    one_error_line(out, "line 2:", says)
    assert "--skip-rows" not in out.stderr


@pytest.mark.parametrize("space, says", [("\u00a0", "a no-break space (U+00A0)"),
                                         ("\u202f", "a narrow no-break space (U+202F)")])
@pytest.mark.parametrize("n", [150, 3000])
@pytest.mark.parametrize("header", [True, False])
def test_french_grouping_in_a_whitespace_table_is_named_not_split(tmp_path, space, says, n, header):
    """Python's str.split() split '1 045,9' (no-break space grouping) into '1' and '045,9': a header-less file read
    with --columns 0 1 gave x = 1 and y = 45.9 without a word (pandas' C parser, above the small-file size, kept
    the field whole and failed elsewhere). Fields of a whitespace table are split at spaces and tabs only."""
    pts = circle(n, r=300.0, cx=1200.0, cy=1650.0)
    rows = [f"{x:,.6f} {y:,.6f}".replace(",", space).replace(".", ",") for x, y in pts]
    path = tmp_path / "fr.txt"
    path.write_text("\n".join((["X Y"] if header else []) + rows) + "\n", encoding="utf-8")
    out = cli("fit", "circle.kasa", path, *([] if header else ["--columns", "0", "1"]))
    one_error_line(out, f"line {2 if header else 1}:", says, "thousands separator", "export without digit grouping")


def test_french_grouping_in_a_whitespace_positioning_table_is_named(tmp_path):
    lines = wide_positioning(range(0, 2001, 250), sep=" ", fmt=lambda v: f"{v:.4f}".replace(".", ","),
                             tfmt=lambda t: f"{t:,}".replace(",", "\u00a0"),
                             header=" ".join(["Target"] + [f"R{k}F" for k in range(1, 6)] + [f"R{k}R" for k in range(1, 6)]))
    path = tmp_path / "fr.txt"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    one_error_line(cli("positioning", path), "line 6:", "'1\\xa0000'", "a no-break space (U+00A0)")


@pytest.mark.parametrize("n", [150, 3000])                  # small files and pandas' C parser
@pytest.mark.parametrize("encoding", ["utf-8", "utf-16"])
@pytest.mark.parametrize("mark", [",", "."])
def test_the_unicode_minus_sign_is_read_as_a_minus(tmp_path, n, encoding, mark):
    """U+2212, as spreadsheets and instrument software write negative numbers, reads as '-' (it was refused)."""
    pts = circle(n, r=300.0, cx=-700.0, cy=-20.0)
    sep = ";" if mark == "," else ","
    text = "\n".join(["X" + sep + "Y"] + [f"{x:.6f}{sep}{y:.6f}".replace(".", mark).replace("-", "\u2212")
                                          for x, y in pts]) + "\n"
    assert text.count("\u2212") > n
    path = tmp_path / "m.csv"
    path.write_text(text, encoding=encoding)
    np.testing.assert_array_equal(read_points(path), np.round(pts, 6))
    ascii_path = tmp_path / "a.csv"
    ascii_path.write_text(text.replace("\u2212", "-"), encoding=encoding)
    np.testing.assert_array_equal(read_points(path), read_points(ascii_path))


def test_a_unicode_minus_at_the_end_of_a_read_of_the_c_parser_waits_for_its_digit():
    from datasets.io import _AsciiMinus
    text = "1;\u22122\n\u22123;4\n"
    for size in range(1, len(text) + 1):
        reader, got = _AsciiMinus(io.StringIO(text)), ""
        while chunk := reader.read(size):
            got += chunk
        assert got == "1;-2\n-3;4\n", size


def test_a_unicode_minus_in_a_positioning_table_is_read_as_a_minus(tmp_path):
    lines = wide_positioning(range(0, 501, 100), sep=";")
    minus = [*lines[:3], lines[3].replace(";", ";\u2212", 1), *lines[4:]]
    ascii_ = [*lines[:3], lines[3].replace(";", ";-", 1), *lines[4:]]
    got = []
    for name, rows in (("m.csv", minus), ("a.csv", ascii_)):
        path = tmp_path / name
        path.write_text("\n".join(rows) + "\n", encoding="utf-8")
        out = cli("positioning", path, "--json")
        assert out.returncode == 0, out.stderr
        got.append(json.loads(out.stdout))
        assert got[-1]["details"]["conditions"].pop("files") == [str(path)]
    assert got[0] == got[1]


# ------------------------------------------------------------------ header units of multilateration files
def multilateration_rows(scale_xyz=1.0, scale_len=1.0):
    rng = np.random.default_rng(1)
    rows = []
    for s in ("LT1", "LT2", "LT3", "LT4"):
        for p in rng.uniform(0, 500, (6, 3)):
            rows.append(f"{s},{p[0] * scale_xyz:.9f},{p[1] * scale_xyz:.9f},{p[2] * scale_xyz:.9f},"
                        f"{(400 + p.sum() / 10) * scale_len:.9f}")
    return rows


def test_multilateration_reads_units_in_its_header(tmp_path):
    """'x [mm]' was refused as 'missing column(s) x'; 'length [m]' (lengths in metres) likewise."""
    plain, mm, m = tmp_path / "plain.csv", tmp_path / "mm.csv", tmp_path / "m.csv"
    plain.write_text("station,x,y,z,length\n" + "\n".join(multilateration_rows()) + "\n", encoding="utf-8")
    mm.write_text("station,x [mm],y [mm],z [mm],length [mm]\n" + "\n".join(multilateration_rows()) + "\n",
                  encoding="utf-8")
    m.write_text("station,x,y,z,length [m]\n" + "\n".join(multilateration_rows(scale_len=1e-3)) + "\n",
                 encoding="utf-8")
    ref = read_multilateration(plain)
    np.testing.assert_array_equal(read_multilateration(mm).lengths, ref.lengths)
    got, units = read_multilateration(m, with_units=True)
    assert units == {"x": "mm", "y": "mm", "z": "mm", "length": "m"}
    np.testing.assert_allclose(got.lengths, ref.lengths, rtol=0, atol=1e-6)   # mm: 9 decimals of m are 1 nm
    with pytest.raises(DataFileError, match="the header says column 'length \\[m\\]' is in m but --unit says mm"):
        read_multilateration(m, unit="mm")


# ------------------------------------------------------------------ a unit the reader cannot take apart
def test_a_unit_in_braces_is_read_and_an_unparsed_one_is_refused(tmp_path):
    pts = circle(40, r=3000.0, cx=30000.0)
    body = "\n".join(f"{x:.6f},{y:.6f}" for x, y in pts) + "\n"
    brace, angle = tmp_path / "brace.csv", tmp_path / "angle.csv"
    brace.write_text("X {µm},Y {µm}\n" + body, encoding="utf-8")
    angle.write_text("X <µm>,Y <µm>\n" + body, encoding="utf-8")
    np.testing.assert_allclose(read_points(brace), pts * 1e-3, rtol=0, atol=1e-9)   # mm
    with pytest.raises(DataFileError, match="cannot tell the unit of column 'X <µm>'"):
        read_points(angle)


def test_a_small_pin_in_um_read_as_mm_is_warned_about_by_roundness(tmp_path):
    """A 6 mm pin in µm under a header without units: 3000 'mm' passed the 5 m profile limit silently (RONt
    982 µm instead of 0.98 µm); roundness warns above a 1 m half-width, naming µm; fit keeps the 5 m limit."""
    pts = circle(720, r=3000.0, cx=1500.0, cy=-700.0)
    path = tmp_path / "pin.csv"
    path.write_text("X;Y\n" + "\n".join(f"{x:.4f};{y:.4f}".replace(".", ",") for x, y in pts) + "\n",
                    encoding="utf-8")
    out = cli("roundness", path)
    assert out.returncode == 0 and "profile radii (half the points' span) up to 3000" in out.stderr and "--unit um" in out.stderr
    assert "implausible" not in cli("fit", "circle.kasa", path).stderr
