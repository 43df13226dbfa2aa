"""A DOS end-of-file mark alone on the last line ('\\x1a\\r\\n' or '\\x1a\\n', as some DOS tools write it) reads as
the bare trailing mark does: it was refused ('line 3602: 1 field where the header (line 1) has 2: '\\x1a'', a
positioning table's ''\\x1a' is not a data row')."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli
from datasets.positioning import axis_test, to_frame
from test_dos_eof import circle_text, fitted


@pytest.mark.parametrize("n", [360, 3600])
@pytest.mark.parametrize("end", [b"\x1a\r\n", b"\x1a\n", b"\x1a\x1a\r\n"])
def test_a_ctrl_z_line_at_the_end_is_ignored(tmp_path, n, end):
    text = circle_text(n)
    plain, dos = tmp_path / "plain.csv", tmp_path / "dos.csv"
    plain.write_bytes(text.encode())
    dos.write_bytes(text.encode() + end)
    assert fitted(dos) == fitted(plain)


def test_a_positioning_table_with_a_ctrl_z_line(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(1), pitch=(0.0, 0.01), reversal=-0.002)
    plain, dos = tmp_path / "plain.csv", tmp_path / "dos.csv"
    to_frame(data, actual=False).to_csv(plain, index=False)
    dos.write_bytes(plain.read_bytes() + b"\x1a\n")
    a, b = (cli("positioning", p, "--json") for p in (plain, dos))
    assert b.returncode == 0, b.stderr
    da, db = json.loads(a.stdout), json.loads(b.stdout)
    assert {k: db[k] for k in ("A", "E", "R")} == {k: da[k] for k in ("A", "E", "R")}
