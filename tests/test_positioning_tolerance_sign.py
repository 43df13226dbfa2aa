"""``--tolerance B_mean=...`` judges the magnitude of the mean reversal value B̄, which carries a sign: the verdict
line names it |B_mean| so that one output does not print the same figure as -3.218 in the table and 3.218 µm on the
verdict line under one name; the JSON check says so (``judged``). B̄ is computed here from the example export by
its definition (the mean over the targets of mean ↑ - mean ↓). Before: 'B_mean      3.218 µm  tolerance 3 µm ...
FAIL' under 'B_mean  mean reversal value  -3.218'."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from cli_calls import cli

EXAMPLE = Path(__file__).resolve().parents[1] / "docs/examples/positioning.csv"


def b_mean_um() -> float:
    rows = [line.split(";") for line in EXAMPLE.read_text(encoding="utf-8").splitlines()[1:] if line.strip()]
    values = np.array([[float(v) for v in r[1:]] for r in rows])      # µm, runs as Run k +, Run k -
    return float(np.mean(values[:, 0::2].mean(axis=1) - values[:, 1::2].mean(axis=1)))


@pytest.mark.parametrize("tolerance, result", [("3", "FAIL"), ("3.5um", "PASS")])
def test_the_verdict_line_names_the_magnitude_it_judges(tolerance, result):
    want = b_mean_um()
    assert want < 0
    out = cli("positioning", EXAMPLE, "--tolerance", f"B_mean={tolerance}", "--tolerance", "A=10")
    assert out.returncode == 0, out.stderr
    table = re.search(r"^\s+B_mean\s+mean reversal value\s+(\S+)$", out.stdout, re.MULTILINE)
    assert float(table.group(1)) == pytest.approx(want, abs=5e-4)
    line = re.search(r"^\s+\|B_mean\|\s+(\S+) µm\s+tolerance (\S+) µm.*\s(PASS|FAIL)$", out.stdout, re.MULTILINE)
    assert line, out.stdout
    assert float(line.group(1)) == pytest.approx(abs(want), abs=5e-4) and line.group(3) == result
    assert not re.search(r"^\s+B_mean\s+\d", out.stdout, re.MULTILINE)     # no unsigned value under the signed name
    assert re.search(r"^\s+A\s+8\.498 µm\s+tolerance 10 µm", out.stdout, re.MULTILINE)
    got = json.loads(cli("positioning", EXAMPLE, "--tolerance", f"B_mean={tolerance}", "--json").stdout)
    check = got["verdict"]["checks"][0]
    assert check["figure"] == "B_mean" and check["judged"] == "|B_mean|" and check["result"] == result
    assert check["value_mm"] == abs(got["B_mean"]) and got["B_mean"] * 1e3 == pytest.approx(want, abs=1e-9)
