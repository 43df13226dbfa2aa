"""'; ' (a separator and a space) after the last field of every line, header included: the blank-named last column
of spaces is dropped as the unnamed empty one is (it was 'line 2: missing field(s): ' ' is empty')."""
from __future__ import annotations

import json

import pytest

from cli_calls import cli
from positioning_tables import iso_a_um, runs
from test_positioning_separators import NAMES, rows, write


@pytest.mark.parametrize("end", ["; ", ";  ", ";\t"])
def test_a_separator_and_a_space_after_every_line_is_read(tmp_path, end):
    dev = runs(seed=4)
    path = write(tmp_path / "ws.csv", ";".join(NAMES) + end, rows(dev), end=end)
    out = cli("positioning", path, "--json")
    assert out.returncode == 0 and not out.stderr, out.stderr
    assert json.loads(out.stdout)["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)
