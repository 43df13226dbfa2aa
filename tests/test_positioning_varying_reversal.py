"""A reversal that varies along the travel (worn screw, nut preload changing along it): a table of the mean
bidirectional deviation with one backlash (-B mean) leaves (B_i - B mean)/2 in each direction. Before, the tables
were written without a word (the review's axis: B_i from -2.5 to -12.4 µm, 5.4 µm left after compensation). The
test of the variation is checked against an independent two-way analysis of variance (target x direction with
replication: the interaction is the reversal varying), computed here from the long table."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from cli_calls import cli


def bidirectional_file(path, reversal_slope_um, seed=5):
    """11 targets 0-1000 mm, 5 runs, pitch 15 µm/m - 8 µm/m², reversal x_up - x_down from -2 µm at 0 mm to
    -2 - reversal_slope_um at 1000 mm, 0.5 µm repeatability (the review's bidir.py with slope 10)."""
    rng = np.random.default_rng(seed)
    P = np.linspace(0, 1000, 11)
    base = 0.015 * (P / 1000) - 0.008 * (P / 1000) ** 2
    B = -(0.002 + reversal_slope_um * 1e-3 * P / 1000)
    rows = []
    for d, curve in (("+", base + B / 2), ("-", base - B / 2)):
        runs = curve[:, None] + rng.normal(0, 0.0005, (11, 5))
        rows += [(t, d, j + 1, 1e3 * runs[i, j]) for i, t in enumerate(P) for j in range(5)]
    pd.DataFrame(rows, columns=["Target (mm)", "Direction", "Run", "Deviation (um)"]).to_csv(path, index=False,
                                                                                         float_format="%.4f")
    return path


def two_way_interaction(path):
    """F and p of the target x direction interaction (balanced two-way ANOVA with n replicates), and B_i (µm)."""
    df = pd.read_csv(path)
    df.columns = ["t", "d", "r", "x"]
    n = df.groupby(["t", "d"]).size().iloc[0]
    cell = df.groupby(["t", "d"])["x"].mean().unstack()
    grand = cell.to_numpy().mean()
    inter = cell.to_numpy() - cell.mean(axis=1).to_numpy()[:, None] - cell.mean(axis=0).to_numpy()[None, :] + grand
    a, b = cell.shape
    ss_inter = n * np.sum(inter ** 2)
    ss_within = float(((df["x"] - df.groupby(["t", "d"])["x"].transform("mean")) ** 2).sum())
    dfi, dfw = (a - 1) * (b - 1), a * b * (n - 1)
    F = (ss_inter / dfi) / (ss_within / dfw)
    return F, stats.f.sf(F, dfi, dfw), (dfi, dfw), (cell["+"] - cell["-"]).to_numpy()


def test_a_varying_reversal_is_warned_with_its_figures_in_the_output_and_every_header(tmp_path):
    f = bidirectional_file(tmp_path / "bidir.csv", 10.0)
    F, p, dof, B_i = two_way_interaction(f)
    assert p < 1e-6
    out = cli("positioning", f, "--axis", "X1", "--compensation", "fanuc-pitch", tmp_path / "t.tap",
              "--compensation", "siemens-eec", tmp_path / "t.mpf", "--compensation", "csv", tmp_path / "t.csv")
    assert out.returncode == 0, out.stderr
    line = next(ln for ln in out.stderr.splitlines() if "reversal B_i varies" in ln)
    assert f"from {B_i.min():.3f} to {B_i.max():.3f} um" in line and f"mean {B_i.mean():.3f} um" in line
    assert f"F = {F:.3g} on {dof[0]} and {dof[1]} degrees of freedom" in line
    left = np.max(np.abs(B_i - B_i.mean())) / 2
    assert f"up to {left:.3f} um, of opposite sign" in line and "deviation_up_mm and deviation_down_mm" in line
    for name in ("t.tap", "t.mpf", "t.csv"):
        head = (tmp_path / name).read_text().upper()
        assert f"VARIES ALONG THE TRAVEL FROM {B_i.min():.3f} TO {B_i.max():.3f} UM" in head, name


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_constant_reversal_is_not_warned(tmp_path, seed):
    """The same axis with a constant -2 µm reversal: the interaction test does not reject, and nothing is said."""
    f = bidirectional_file(tmp_path / "const.csv", 0.0, seed=seed)
    assert two_way_interaction(f)[1] > 0.05
    out = cli("positioning", f, "--axis", "X1", "--compensation", "csv", tmp_path / "t.csv")
    assert out.returncode == 0 and "reversal B_i varies" not in out.stderr + out.stdout
    assert "VARIES ALONG THE TRAVEL" not in (tmp_path / "t.csv").read_text().upper()


def test_the_variation_test_is_the_two_way_interaction():
    """methods.positioning.iso230_2.reversal_variation's F and p equal the two-way ANOVA's interaction test."""
    import tempfile
    from pathlib import Path
    from datasets.io import read_positioning
    from methods.positioning.iso230_2 import reversal_variation
    with tempfile.TemporaryDirectory() as tmp:
        for slope, seed in ((0.0, 4), (1.0, 4), (10.0, 5)):
            f = bidirectional_file(Path(tmp) / "a.csv", slope, seed)
            F, p, dof, _ = two_way_interaction(f)
            rv = reversal_variation(read_positioning(f))
            assert rv["F"] == pytest.approx(F, rel=1e-9) and rv["p_value"] == pytest.approx(p, rel=1e-6, abs=1e-300)
            assert rv["dof"] == dof and rv["significant"] == (p < 0.05)
