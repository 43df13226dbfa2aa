"""A positioning test the GLS polynomial model cannot be fitted to still gets its ISO 230-2 figures (they need no
model). Before: every run reading 0.000 at one target (the laser zeroed there at each run's start) refused the whole
evaluation ('the covariance U(x) is singular ...'), and a 2-target test 'a degree-3 polynomial needs at least 4
targets, got 2', with no A, E, M, R, B. Now the figures are printed and a note says why the model is not given and
what would give it; a compensation table from the model is refused naming --compensation-from mean. The figures
are checked against ISO 230-2's definitions computed here (k = 2)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line


def wide(path, targets, dev):
    head = ";".join(["Target (mm)"] + [f"Run {r + 1} {d} (µm)" for r in range(dev['+'].shape[1]) for d in "+-"])
    rows = [";".join([f"{t:.4f}"] + [f"{dev[d][i, r]:.3f}" for r in range(dev['+'].shape[1]) for d in "+-"])
            for i, t in enumerate(targets)]
    path.write_text(head + "\n" + "\n".join(rows) + "\n")
    return path


def iso(dev) -> dict:
    """A, E, R, B by ISO 230-2's definitions (k = 2, s with n - 1), µm."""
    m = {d: v.mean(axis=1) for d, v in dev.items()}
    s = {d: v.std(axis=1, ddof=1) for d, v in dev.items()}
    hi = max(np.max(m[d] + 2 * s[d]) for d in dev)
    lo = min(np.min(m[d] - 2 * s[d]) for d in dev)
    e = max(np.max(m[d]) for d in dev) - min(np.min(m[d]) for d in dev)
    r = np.maximum.reduce([4 * s["+"], 4 * s["-"], 2 * s["+"] + 2 * s["-"] + np.abs(m["+"] - m["-"])])
    return {"A": hi - lo, "E": e, "R": float(np.max(r)), "B": float(np.max(np.abs(m["+"] - m["-"])))}


@pytest.fixture
def zeroed(tmp_path):
    rng = np.random.default_rng(5)
    targets = np.array([0.0, 97.3, 201.6, 298.1, 402.7, 499.2])
    dev = {d: np.round((6 * targets / 500 + b)[:, None] + rng.normal(0, 0.6, (len(targets), 5)), 3)
           for d, b in (("+", -1.8), ("-", 1.8))}
    dev["+"][0] = 0.0                                         # the laser zeroed at target 0 before each run
    return wide(tmp_path / "z.csv", targets, dev), dev


def test_zero_scatter_at_one_target_gives_the_figures_and_says_why_no_model(zeroed, tmp_path):
    path, dev = zeroed
    out = cli("positioning", path, "--json")
    assert out.returncode == 0, out.stderr
    got, want = json.loads(out.stdout), iso(dev)
    for k in ("A", "E", "R", "B"):
        assert got[k] * 1e3 == pytest.approx(want[k], abs=1e-9), k
    assert got["polynomial"] is None     # no model: null (was an empty object), the note says why
    note = next(n for n in got["notes"] if n.startswith("the polynomial model and its U(P) are not given"))
    assert "every run reads the same at target 0 mm (↑)" in note and "--mpe or --instrument-u" in note
    with_u = json.loads(cli("positioning", path, "--mpe", "2um", "--json").stdout)
    assert set(with_u["polynomial"]) == {"up", "down"} and with_u["A"] == got["A"]
    one_error_line(cli("positioning", path, "--compensation", "csv", tmp_path / "t.csv"),
                   "the polynomial model is not given", "--compensation-from mean")
    assert cli("positioning", path, "--compensation", "csv", tmp_path / "t.csv", "--compensation-from",
               "mean").returncode == 0


def test_two_targets_give_the_figures_and_name_the_degree(tmp_path):
    dev = {"+": np.array([[1.0, 1.5, 0.8], [2.0, 2.4, 2.1]]), "-": np.array([[3.0, 3.2, 2.7], [4.0, 4.6, 4.2]])}
    out = cli("positioning", wide(tmp_path / "p2.csv", np.array([0.0, 100.0]), dev), "--json")
    assert out.returncode == 0, out.stderr
    got, want = json.loads(out.stdout), iso(dev)
    for k in ("A", "E", "R", "B"):
        assert got[k] * 1e3 == pytest.approx(want[k], abs=1e-9), k
    assert any("a degree-3 polynomial needs at least 4 targets and this test has 2; give --degree 1 (or lower)" in n
               for n in got["notes"])
    line = cli("positioning", tmp_path / "p2.csv", "--degree", 1, "--json")
    assert set(json.loads(line.stdout)["polynomial"]) == {"up", "down"}
