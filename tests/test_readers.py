"""The instrument reader (datasets.io) on hostile files: one number grammar for every size, long lines, header-less
tab files with decimal commas, ragged point lists, and the same refusals through every table reader."""
from __future__ import annotations

import codecs

import numpy as np
import pytest

import methods
from datasets.io import (MAX_LINE_CHARS, SMALL_FILE_BYTES, DataFileError, read_multilateration, read_points,
                         read_positioning)
from methods import InvalidInputError


def circle_lines(n, r=20.0):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return [f"{r * np.cos(a):.6f},{r * np.sin(a):.6f}" for a in t]


@pytest.mark.parametrize("token", ["117_677670", "1d3", "0x1A", "١٢", "1e", "--1", "1.2.3"])
def test_one_number_grammar_below_and_above_the_small_file_size(tmp_path, token):
    """Python's float() accepts '117_677670' (and Arabic-Indic digits); pandas does not: the same token is now
    refused with the same message whatever the file's size."""
    messages = []
    for n in (40, 4000):
        lines = ["x,y"] + circle_lines(n)
        lines[6] = f"{token},1.0"
        path = tmp_path / f"f{n}.csv"
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        assert (path.stat().st_size > SMALL_FILE_BYTES) == (n == 4000)
        with pytest.raises(DataFileError) as exc:
            read_points(path)
        messages.append(str(exc.value).replace(str(path), "FILE"))
    assert messages[0] == messages[1]
    assert messages[0].startswith(f"FILE line 7: {token!r} is not a number: correct the value, or delete the line")


def test_the_grammar_accepts_what_instruments_write(tmp_path):
    path = tmp_path / "ok.csv"
    path.write_text("x,y\n+1.5,-2\n.5,3.\n1e-3,-2.5E+02\n 7 , 8 \n")
    np.testing.assert_array_equal(read_points(path), [[1.5, -2], [0.5, 3.0], [1e-3, -250.0], [7, 8]])


def test_table_readers_use_the_same_grammar(tmp_path):
    pos = tmp_path / "pos.csv"
    pos.write_text("target,direction,run,deviation\n0,+,1,0.001\n0,+,2,117_677670\n")
    with pytest.raises(DataFileError, match=r"line 3: deviation '117_677670' is not a finite number"):
        read_positioning(pos)
    ml = tmp_path / "ml.csv"
    ml.write_text("station,x,y,z,length\nA,0,0,0,1_0\n")
    with pytest.raises(DataFileError, match=r"line 2: x .* length '1_0' is not a finite number|line 2: length '1_0'"):
        read_multilateration(ml)


def test_a_line_longer_than_the_cap_is_refused_in_one_line(tmp_path):
    small = tmp_path / "small.csv"
    small.write_text("x,y\n" + "1" * (MAX_LINE_CHARS + 10) + ",2\n")
    big = tmp_path / "big.csv"
    big.write_text("\n".join(["x,y"] + circle_lines(5000) + ["0" * (3 * MAX_LINE_CHARS)]) + "\n")
    for path, line in ((small, 2), (big, 5002)):
        with pytest.raises(DataFileError, match=f"line {line}: longer than {MAX_LINE_CHARS} characters"):
            read_points(path)


@pytest.mark.parametrize("end", ["\r", "\r\n"], ids=["CR", "CRLF"])
def test_a_large_file_with_cr_or_crlf_line_ends_is_read_and_its_long_line_found(tmp_path, end):
    """An old Mac export ends its lines with CR alone: a file of them above 64 KiB was one 'line' longer than the cap
    and refused as not a table; its points are those of the same file with LF, and a line over the cap is still
    found, on its line (with CR LF too, one pair of which is split between the check's first two 4 MiB blocks)."""
    lines = ["x,y"] + circle_lines(5000)
    lf, other = tmp_path / "lf.csv", tmp_path / "other.csv"
    lf.write_text("\n".join(lines) + "\n", newline="")
    other.write_text(end.join(lines) + end, newline="")
    assert other.stat().st_size > 1 << 16
    np.testing.assert_array_equal(read_points(other), read_points(lf))
    big = tmp_path / "big.csv"
    filler = ["1.000000000000,2.000000000000"] * ((1 << 22) // 30 + 7)
    big.write_text(end.join(["x,y"] + filler + ["0" * (3 * MAX_LINE_CHARS)]) + end, newline="")
    with big.open("rb") as fh:
        fh.seek((1 << 22) - 1)
        assert fh.read(2) == (b"\r\n" if end == "\r\n" else b"\r1")   # a CR LF across the blocks
    with pytest.raises(DataFileError, match=f"line {len(filler) + 2}: longer than {MAX_LINE_CHARS} characters"):
        read_points(big)


def test_headerless_tab_separated_decimal_commas(tmp_path):
    """'1,5<TAB>2,25' was sniffed as comma-separated (three fields) and refused."""
    t = np.linspace(0, 2 * np.pi, 30, endpoint=False)
    pts = np.c_[10 + 3 * np.cos(t), -4 + 3 * np.sin(t)]
    for sep in ("\t", " "):
        path = tmp_path / "tab.txt"
        path.write_text("".join(f"{x:.6f}{sep}{y:.6f}\n".replace(".", ",") for x, y in pts))
        np.testing.assert_allclose(read_points(path), pts, atol=1e-6)
    # a comma-separated file with tab padding stays comma-separated
    path = tmp_path / "padded.csv"
    path.write_text("".join(f"{x:.6f},\t{y:.6f}\n" for x, y in pts))
    np.testing.assert_allclose(read_points(path), pts, atol=1e-6)


@pytest.mark.parametrize("method", ["circle.kasa", "circle.gauss_newton", "ellipse.halir_flusser"])
def test_a_ragged_point_list_is_the_projects_input_error(method):
    pts = [[0.0, 1.0], [1.0, 0.0], [0.0, -1.0], [-1.0, 0.0, 5.0], [0.7, 0.7]]
    with pytest.raises(InvalidInputError, match="ragged"):
        methods.fit(method, pts)


@pytest.mark.parametrize("token", ["nan", "NaN", "inf", "-inf"])
def test_a_non_finite_value_gets_the_same_message_in_points_and_positioning(tmp_path, token):
    """pandas' NA parsing turned 'nan' in a positioning file into 'missing field(s)'; every reader now says the
    value is not a finite number."""
    pts = tmp_path / "pts.csv"
    pts.write_text("x,y\n1,2\n3," + token + "\n4,5\n")
    pos = tmp_path / "pos.csv"
    pos.write_text("target,direction,run,deviation\n0,+,1,0.001\n0,+,2," + token + "\n")
    wanted = f"line 3: .*{token!r} is not a finite number; remove or repair the point"
    for read, path in ((read_points, pts), (read_positioning, pos)):
        with pytest.raises(DataFileError, match=wanted):
            read(path)
    pos.write_text("target,direction,run,deviation\n0,+,1,0.001\n0,+,2,\n")
    with pytest.raises(DataFileError, match="line 3: missing field"):
        read_positioning(pos)


@pytest.mark.parametrize("header, skip", [(True, 4), (False, 2)])
def test_a_preamble_without_skip_rows_is_answered_with_the_skip_rows_to_give(tmp_path, header, skip):
    """'which two columns? the header has Taylor, Hobson, Talyrond, 365' left the user guessing: the message
    now names --skip-rows N (keeping a header line just above the first row of numbers)."""
    pre = ["Taylor, Hobson, Talyrond, 365", "Operator: A", "Date: 2025-01-01" if header else None, "" if header else None]
    lines = [ln for ln in pre if ln is not None] + (["x,y"] if header else []) + circle_lines(12)
    path = tmp_path / "pre.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(DataFileError, match=f"give --skip-rows {skip} "):
        read_points(path)
    np.testing.assert_allclose(np.hypot(*read_points(path, skip_rows=skip).T), 20.0, atol=1e-5)


def test_a_preamble_above_rows_with_a_direction_label_gets_the_skip_rows_hint(tmp_path):
    """A ballbar export (Windows-1252, a preamble, then 'CW;0,250;1,9019': a direction label before the
    numbers) and a positioning table ('0;+;1;0,001') gave no --skip-rows hint: their rows are not numbers
    only. The hint is the x, y case's, and the number it names reads the file."""
    from datasets.io import EncodingNote, read_runs
    t = np.arange(0.0, 360.0, 2.5)
    rows = [f"{lab};{a:.3f};{2.0 + 0.3 * np.cos(np.radians(2 * a)) * (1 if lab == 'CW' else -1):.4f}".replace(".", ",")
            for lab in ("CW", "CCW") for a in t]
    ballbar = tmp_path / "ballbar.txt"
    ballbar.write_bytes("\r\n".join(["Renishaw Ballbar 20 Data File", "Machine: VMC-1", "Radius: 150.0000 mm",
                                       "Feedrate: 1000 mm/min", "Date: 25/11/2026", "",
                                       "Direction;Angle [°];Radial deviation (µm)", *rows, ""]).encode("cp1252"))
    with pytest.raises(DataFileError, match=r"give --skip-rows 6 \(the first row of numbers is line 8\)"):
        with pytest.warns(EncodingNote):
            read_runs(ballbar, nominal_radius=150.0)
    with pytest.warns(EncodingNote):
        runs = read_runs(ballbar, skip_rows=6, nominal_radius=150.0)
    assert [tag for tag, _ in runs.runs] == ["cw", "ccw"] and all(len(p) == len(t) for _, p in runs.runs)
    pos = tmp_path / "laser.csv"
    pos.write_text("\n".join(["Laser XL-80 linear export", "Axis: X", "", "target;direction;run;deviation",
                               *(f"{x};{d};{r};{0.001 * (r + x / 100) * (1 if d == '+' else -1):.4f}".replace(".", ",")
                                 for r in (1, 2) for x in (0, 100, 200, 300, 400) for d in "+-")]) + "\n")
    with pytest.raises(DataFileError, match=r"give --skip-rows 3 \(the first row of numbers is line 5\)"):
        read_positioning(pos)
    assert len(read_positioning(pos, skip_rows=3).targets) == 5


def test_a_labelled_data_row_is_never_taken_for_the_header(tmp_path):
    """'--skip-rows 6' on a ballbar export without a preamble skipped its header: the error listed 'the header
    has CW, 1,250, 2,2597'. A row of numbers with a direction label above more of them is named as data where
    the header should be, with what to do."""
    from datasets.io import read_runs
    rows = [f"{lab};{a:.3f};{2.0 + 0.1 * np.sin(np.radians(a)):.4f}".replace(".", ",")
            for lab in ("CW", "CCW") for a in np.arange(0.0, 360.0, 5.0)]
    path = tmp_path / "ballbar.txt"
    path.write_text("\n".join(["Direction;Angle [deg];Radial deviation (um)", *rows]) + "\n", encoding="utf-8")
    assert [tag for tag, _ in read_runs(path, nominal_radius=150.0).runs] == ["cw", "ccw"]
    with pytest.raises(DataFileError, match=r"line 7: 'CW;25,000;2,0423' is a row of data where the header should "
                                            r"be; if --skip-rows 6 skipped the header line, give fewer"):
        read_runs(path, skip_rows=6, nominal_radius=150.0)
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    with pytest.raises(DataFileError, match=r"line 1: 'CW;0,000;2,0000' is a row of data where the header should "
                                            r"be; add a header line naming the columns"):
        read_runs(path, nominal_radius=150.0)


@pytest.mark.parametrize("n", [12, 4000])          # below and above the small-file size (the pandas path)
@pytest.mark.parametrize("encoding, bom", [("utf-16-le", False), ("utf-16-be", False), ("utf-32-le", False),
                                           ("utf-32-be", False), ("utf-32", True)])
def test_utf16_and_utf32_tables_are_read_with_or_without_a_byte_order_mark(tmp_path, encoding, bom, n):
    """'Unicode' exports without a byte-order mark, and UTF-32 with one, were read as UTF-8 or UTF-16 and
    refused as "'\\x001\\x00' is not a number": each is read, and gives the UTF-8 file's numbers."""
    text = "x [µm];y [µm]\n" + "\n".join(circle_lines(n)).replace(",", ";") + "\n"
    utf8 = tmp_path / "utf8.csv"
    utf8.write_text(text, encoding="utf-8")
    wide = tmp_path / f"{encoding}.csv"
    wide.write_bytes(text.encode(encoding))               # Python's "utf-32" writes the BOM, the -le/-be forms none
    assert wide.read_bytes().startswith((codecs.BOM_UTF32_LE, codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)) == bom
    np.testing.assert_array_equal(read_points(wide), read_points(utf8))
    assert len(read_points(wide)) == n


def test_a_stray_nul_byte_is_named_in_one_line(tmp_path):
    path = tmp_path / "nul.csv"
    path.write_bytes(b"x,y\n1,0\n0,1\n-1,0\n0\x00,-1\n")
    with pytest.raises(DataFileError, match=r"line 5: holds NUL bytes, so it is not a text table; if it is UTF-16"):
        read_points(path)


@pytest.mark.parametrize("preamble, skip", [(["Roundness trace", "Part: shaft"], 2), (["Talyrond"], 1)])
def test_other_preamble_errors_name_the_skip_rows_too(tmp_path, preamble, skip):
    path = tmp_path / "pre.csv"
    path.write_text("\n".join(preamble + ["x,y"] + circle_lines(12)) + "\n", encoding="utf-8")
    with pytest.raises(DataFileError, match=f"give --skip-rows {skip} "):
        read_points(path)
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y\n1,2\n3,abc\n5,7\n")                   # a bad value below the first numbers: no hint
    with pytest.raises(DataFileError, match=r"line 3: 'abc' is not a number: correct the value, or delete the line"):
        read_points(bad)


@pytest.mark.parametrize("decimal_comma", [False, True])
def test_quoted_numeric_fields_are_read_below_and_above_the_small_file_size(tmp_path, decimal_comma):
    """'"1","0"' was refused below 64 KiB ('"1"' is not a number) and read above; quoted decimal commas
    ('"0,000","5,5035"') gave '4 fields where the first line has 2'. Both are read, whatever the size."""
    for n in (40, 4000):
        rows = circle_lines(n)
        if decimal_comma:
            rows = [",".join(f'"{v.replace(".", ",")}"' for v in r.split(",")) for r in rows]
        else:
            rows = [",".join(f'"{v}"' for v in r.split(",")) for r in rows]
        path = tmp_path / f"q{n}{decimal_comma}.csv"
        path.write_text('"x","y"\n' + "\n".join(rows) + "\n", encoding="utf-8")
        assert (path.stat().st_size > SMALL_FILE_BYTES) == (n == 4000)
        got = read_points(path)
        assert got.shape == (n, 2)
        np.testing.assert_allclose(np.hypot(*got.T), 20.0, atol=1e-5)
        headerless = tmp_path / f"h{n}{decimal_comma}.csv"
        headerless.write_text("\n".join(rows) + "\n", encoding="utf-8")
        np.testing.assert_array_equal(read_points(headerless), got)


def test_quoted_positioning_export_with_decimal_commas(tmp_path):
    plain = tmp_path / "plain.csv"
    plain.write_text("target,direction,run,deviation\n0,+,1,0.001\n0,+,2,0.002\n100,+,1,0.004\n100,+,2,0.003\n")
    quoted = tmp_path / "quoted.csv"
    quoted.write_text('"target","direction","run","deviation"\n"0","+","1","0,001"\n"0","+","2","0,002"\n'
                      '"100","+","1","0,004"\n"100","+","2","0,003"\n')
    np.testing.assert_array_equal(read_positioning(quoted).up, read_positioning(plain).up)


@pytest.mark.parametrize("encoding, noted", [("utf-8-sig", False), ("utf-16", False), ("cp1252", True),
                                             ("latin-1", True)])
def test_windows_exports_in_utf16_and_cp1252_are_read(tmp_path, encoding, noted):
    """A header with ° and µ in cp1252/Latin-1 or UTF-16 (with BOM) was refused ("cannot be read as text
    ('utf-8' codec ...)"); they are read, and a file that is not UTF-8 is said to be read as Windows-1252."""
    import warnings
    from datasets.io import read_profile
    t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    rows = [f"{np.degrees(a):.4f};{3.0 * np.cos(2 * a):.4f}".replace(".", ",") for a in t]
    path = tmp_path / f"talyrond-{encoding}.txt"
    path.write_text("Winkel (°);Abweichung (µm)\n" + "\n".join(rows) + "\n", encoding=encoding)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = read_profile(path, nominal_radius=20.0)
    assert got.unit == "µm" and got.angle_unit == "deg"
    np.testing.assert_allclose(np.hypot(*got.runs[0][1].T) - 20.0, 3e-3 * np.cos(2 * t), atol=2e-7)   # 4 decimals written
    notes = [str(w.message) for w in caught if "Windows-1252" in str(w.message)]
    assert bool(notes) == noted, [str(w.message) for w in caught]


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-16-be", "utf-32"])
@pytest.mark.parametrize("end", ["\n", "\r", "\r\n"], ids=["LF", "CR", "CRLF"])
def test_a_long_line_of_a_utf16_or_utf32_file_is_named_on_its_line(tmp_path, encoding, end):
    """The line-length check compares the code units of a UTF-16 or UTF-32 file, not its bytes: in UTF-16 a CR LF
    is 0D 00 0A 00, whose CR and LF bytes are not adjacent, and each CR LF counted two line ends (line 5999 named for
    line 3000)."""
    lines = ["x,y"] + circle_lines(3600)
    lines[2999] = "0" * (MAX_LINE_CHARS + 50)
    path = tmp_path / "wide.csv"
    path.write_bytes((end.join(lines) + end).encode(encoding))
    with pytest.raises(DataFileError, match=f"line 3000: longer than {MAX_LINE_CHARS} characters"):
        read_points(path)
