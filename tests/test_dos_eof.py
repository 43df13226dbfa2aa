"""A DOS end-of-file mark (Ctrl-Z, 0x1A) after a file's last line, as old instrument PCs write it, is ignored: the
file reads as without it (small files by Python, large ones by pandas, tables line by line). Before: 'line 3602: 1
field where the header (line 1) has 2: '\\x1a''. So is the mark alone on the last line ('\\x1a\\r\\n' or
'\\x1a\\n', as some DOS tools write it; it was refused the same way, and a positioning table's ''\\x1a' is not a
data row'). A Ctrl-Z elsewhere is still refused."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from datasets.positioning import axis_test, to_frame


def circle_text(n):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 10 + 0.002 * np.cos(3 * t)
    return "x [mm],y [mm]\r\n" + "".join(f"{x:.9f},{y:.9f}\r\n" for x, y in zip(r * np.cos(t), r * np.sin(t)))


def fitted(path):
    out = cli("fit", "circle.kasa", path, "--json", "--no-residuals")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    return {k: d[k] for k in ("center", "radius", "form_error")}


@pytest.mark.parametrize("n", [360, 3600])   # below and above the 64 KiB of the reader without pandas
@pytest.mark.parametrize("end", [b"\x1a", b"\x1a\r\n", b"\x1a\n", b"\x1a\x1a\r\n"])   # the mark, or a line of it
def test_a_trailing_ctrl_z_is_ignored(tmp_path, n, end):
    text = circle_text(n)
    plain, dos = tmp_path / "plain.csv", tmp_path / "dos.csv"
    plain.write_bytes(text.encode())
    dos.write_bytes(text.encode() + end)
    assert (dos.stat().st_size > 1 << 16) == (n > 1000)
    assert fitted(dos) == fitted(plain)


def test_a_ctrl_z_after_an_unterminated_last_line(tmp_path):
    text = circle_text(360)
    plain, dos = tmp_path / "plain.csv", tmp_path / "dos.csv"
    plain.write_bytes(text.encode())
    dos.write_bytes(text.rstrip("\r\n").encode() + b"\x1a")
    assert fitted(dos) == fitted(plain)


@pytest.mark.parametrize("end", [b"\x1a", b"\x1a\n"])
def test_a_positioning_table_with_a_trailing_ctrl_z(tmp_path, end):
    data, _ = axis_test(rng=np.random.default_rng(1), pitch=(0.0, 0.01), reversal=-0.002)
    plain, dos = tmp_path / "plain.csv", tmp_path / "dos.csv"
    to_frame(data, actual=False).to_csv(plain, index=False)
    dos.write_bytes(plain.read_bytes() + end)
    a, b = (cli("positioning", p, "--json") for p in (plain, dos))
    assert b.returncode == 0, b.stderr
    da, db = json.loads(a.stdout), json.loads(b.stdout)
    assert {k: db[k] for k in ("A", "E", "R")} == {k: da[k] for k in ("A", "E", "R")}


def test_a_ctrl_z_inside_the_file_is_still_refused(tmp_path):
    lines = circle_text(360).splitlines(keepends=True)
    p = tmp_path / "mid.csv"
    p.write_bytes("".join(lines[:100] + ["\x1a\r\n"] + lines[100:]).encode())
    one_error_line(cli("fit", "circle.kasa", p), "line 101")
