"""``roundness --tolerance``: ISO 1101's roundness tolerance is a zone of two concentric circles t apart (the
minimum zone, also ISO 12181-2's default reference), so without ``--reference`` the verdict is judged about the
MZCI; the other circles' figures are shown for information. A part whose MZCI RONt was within tolerance read
FAIL overall because its LSCI and MCCI RONt were checked too. The MZCI RONt is checked here against an
independent linear program (linearised minimum zone, scipy.optimize.linprog)."""
from __future__ import annotations

import json

import numpy as np
from scipy.optimize import linprog

from cli_calls import cli


def profile(path, n=720):
    t = 2 * np.pi * np.arange(n) / n
    r = (10.0 + 1.5e-3 * np.cos(3 * t + 0.3) + 0.6e-3 * np.cos(2 * t + 1.0) + 0.4e-3 * np.cos(15 * t)
         + np.random.default_rng(7).normal(0, 5e-5, n))
    x, y = 0.014 + r * np.cos(t), -0.008 + r * np.sin(t)
    path.write_text("x [mm],y [mm]\n" + "\n".join(f"{a:.9f},{b:.9f}" for a, b in zip(x, y)) + "\n")
    return np.c_[x, y]


def minimum_zone_width(p):
    """min t: r_i - (a cos + b sin)_i in [c, c + t] about the centroid (linear in a, b, c, t for deviations << R)."""
    q = p - p.mean(axis=0)
    r, phi = np.hypot(*q.T), np.arctan2(q[:, 1], q[:, 0])
    A = np.c_[np.cos(phi), np.sin(phi)]
    one = np.ones(len(r))
    # variables a, b, c, t: r - A ab <= c + t ; r - A ab >= c
    A_ub = np.r_[np.c_[-A, -one, -one], np.c_[A, one, 0 * one]]
    b_ub = np.r_[-r, r]
    got = linprog([0, 0, 0, 1], A_ub=A_ub, b_ub=b_ub, bounds=[(None, None)] * 3 + [(0, None)], method="highs")
    return got.x[3]


def test_the_verdict_is_judged_about_the_minimum_zone_unless_a_reference_is_chosen(tmp_path):
    pts = profile(tmp_path / "part.csv")
    mz = minimum_zone_width(pts)
    full = json.loads(cli("roundness", tmp_path / "part.csv", "--cutoff", "none", "--json").stdout)["references"]
    assert abs(full["mzci"]["RONt"] - mz) < 2e-6                       # the figure the verdict uses, independently
    lsci = full["lsci"]["RONt"]
    assert lsci > mz + 5e-5                                             # a tolerance between them tells the rules apart
    tol_um = 1e3 * (mz + lsci) / 2
    out = cli("roundness", tmp_path / "part.csv", "--cutoff", "none", "--tolerance", f"RONt={tol_um:.4f}", "--json")
    v = json.loads(out.stdout)["verdict"]
    assert v["overall"] == "PASS" and v["reference"] == "mzci"
    assert [(c["figure"], c["result"]) for c in v["checks"]] == [("RONt MZCI", "PASS")]
    assert ("RONt LSCI", "FAIL") in [(c["figure"], c["result"]) for c in v["information"]]
    text = cli("roundness", tmp_path / "part.csv", "--cutoff", "none", "--tolerance", f"RONt={tol_um:.4f}").stdout
    assert "verdict      PASS (about the MZCI: minimum zone" in text and "for information (not part of the verdict)" in text
    chosen = json.loads(cli("roundness", tmp_path / "part.csv", "--cutoff", "none", "--reference", "lsci",
                            "--tolerance", f"RONt={tol_um:.4f}", "--json").stdout)["verdict"]
    assert chosen["overall"] == "FAIL" and chosen["reference"] == "lsci" and chosen["information"] == []
