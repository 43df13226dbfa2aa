"""Lack of fit of the positioning model: the cubic's U(P) (positioning paper eq. 8-10) holds between the targets only
if the cubic describes the axis. Before: a ball-screw axis with a 1.5 µm periodic error of period 130 mm, which
the cubic misses by 2.46 µm (weighted chi-square per degree of freedom 155), was printed with "max U(P_i) = 0.167 µm
(k = 2)", plotted as "expanded uncertainty anywhere on the travel", and its compensation table written from the
cubic without a word. The statistic is checked against an independent weighted polynomial fit (numpy.polyfit)."""
from __future__ import annotations

import json

import numpy as np
import pytest

import methods
from cli_calls import cli, one_error_line
from datasets.positioning import axis_test
from methods.positioning.model import lack_of_fit


def periodic_file(path):
    """A 1000 mm ball-screw axis, 21 irregular targets, 5 runs per direction: 10 µm/m linear - 12 µm/m² and a
    1.5 µm periodic error of period 130 mm, ±1.5 µm reversal, 0.3 µm noise (the review's recipe)."""
    rng = np.random.default_rng(21)
    T = np.sort(np.r_[0, 1000, rng.uniform(20, 980, 19)]).round(1)

    def err(p):
        return 1e-3 * (10 * (p / 1000) - 12 * (p / 1000) ** 2 + 1.5 * np.sin(2 * np.pi * p / 130))
    rows = []
    for r in range(1, 6):
        for d, off in (("+", 0.0015), ("-", -0.0015)):
            for t in (T if d == "+" else T[::-1]):
                rows.append((t, d, r, err(t) + off + rng.normal(0, 0.0003)))
    path.write_text("target,direction,run,deviation\n" + "".join(f"{t},{d},{r},{e:.6f}\n" for t, d, r, e in rows))
    return path


def independent_chi2(targets, runs):
    """Weighted cubic by numpy.polyfit (weights 1/u, u = s/sqrt(n)): chi-square, largest |residual| (mm)."""
    x, s = runs.mean(axis=1), runs.std(axis=1, ddof=1)
    u = s / np.sqrt(runs.shape[1])
    c = np.polyfit(targets / 1000.0, x, 3, w=1.0 / u)
    r = x - np.polyval(c, targets / 1000.0)
    return float(np.sum((r / u) ** 2)), float(np.max(np.abs(r)))


def test_a_rejected_cubic_is_said_so_and_gives_no_uncertainty(tmp_path):
    f = periodic_file(tmp_path / "periodic.csv")
    out = cli("positioning", f, "--json")
    assert out.returncode == 0, out.stderr
    j = json.loads(out.stdout)
    import pandas as pd
    df = pd.read_csv(f)
    for d, sign, review in (("up", "+", 155), ("down", "-", 72)):
        piv = df[df.direction == sign].pivot(index="target", columns="run", values="deviation")
        chi2, miss = independent_chi2(piv.index.to_numpy(float), piv.to_numpy(float))
        lof = j["polynomial"][d]["lack_of_fit"]
        assert lof["chi2"] == pytest.approx(chi2, rel=1e-6) and lof["dof"] == 21 - 4
        assert lof["max_abs_residual"] == pytest.approx(miss, rel=1e-6)
        assert lof["chi2_per_dof"] == pytest.approx(review, rel=0.01)       # the reviewer's own computation
        assert lof["rejected"] and lof["p_value"] < 0.05
        assert j["polynomial"][d]["U_at_targets"] is None                    # withheld, not "anywhere on the travel"
    assert any("rejected by its lack of fit" in n for n in j["notes"])
    text = cli("positioning", f).stdout
    assert "max U(P_i)" not in text and text.count("U(P) not given") == 2 and "REJECTED" in text
    assert "χ²/ν = 155" in text and "2.458 µm" in text


def test_a_rejected_model_is_plotted_without_a_band(tmp_path):
    from fitbench.plots.positioning import plot
    from datasets.io import read_positioning
    data = read_positioning(periodic_file(tmp_path / "p.csv"))
    res = methods.fit("positioning.gls_polynomial", data)
    labels = plot(res, tmp_path / "p.png", data=data)
    assert "REJECTED" in labels["model_title"] and "anywhere" not in labels["model_title"]
    assert not any(lab.startswith("U(P)") for lab in labels["model_labels"])


def test_no_table_from_a_rejected_model_unless_asked(tmp_path):
    f = periodic_file(tmp_path / "periodic.csv")
    table = tmp_path / "per.mpf"
    out = cli("positioning", f, "--deviation-unit", "mm", "--compensation", "siemens-eec", table, "--axis", "X1", "--interval", "10")
    one_error_line(out, "rejected by its lack of fit", "2.46 um", "--compensation-from mean", "--compensation-from model")
    assert not table.exists()
    out = cli("positioning", f, "--deviation-unit", "mm", "--compensation", "siemens-eec", table, "--axis", "X1", "--interval", "10",
              "--compensation-from", "mean")
    assert out.returncode == 0 and table.exists() and "WARNING" not in table.read_text()
    out = cli("positioning", f, "--deviation-unit", "mm", "--compensation", "siemens-eec", table, "--axis", "X1", "--interval", "10",
              "--compensation-from", "model")
    assert out.returncode == 0 and "leaves that misfit uncompensated" in out.stderr
    assert table.read_text().splitlines()[1].startswith("; WARNING: the cubic is rejected by its lack of fit")


def simulated_chi2(rng, tests, targets, runs, sd):
    """Independent null sample: ``tests`` axes whose error is a cubic, ``runs`` approaches of s.d. ``sd`` (one per
    target, or a callable drawing them) at ``targets``; chi2 of a weighted cubic by numpy.polyfit (weights 1/u,
    u = s/sqrt(n))."""
    t = targets / 1000.0
    out = np.empty(tests)
    for k in range(tests):
        sig = sd(rng) if callable(sd) else sd
        runs_ = (0.004 * t - 0.01 * t ** 2 + 0.006 * t ** 3)[:, None] + rng.normal(0.0, 1.0, (len(t), runs)) * sig[:, None]
        x, s = runs_.mean(axis=1), runs_.std(axis=1, ddof=1)
        u = s / np.sqrt(runs)
        out[k] = np.sum(((x - np.polyval(np.polyfit(t, x, 3, w=1.0 / u), t)) / u) ** 2)
    return out


def test_the_printed_5_percent_limit_rejects_5_percent_of_correct_cubics():
    """The limit is the 95 % point of the statistic actually used. 4000 independent correct cubics (11 targets,
    5 runs, equal scatter: the case the simulated null distribution is exact for) must be rejected in 5 % of
    the tests within 3 binomial standard errors (sqrt(0.05 0.95 / 4000) = 0.34 %) plus 0.15 % for the limit's own
    Monte Carlo error; before, the F(7, 4) limit 6.09 rejected 0.65 % (the review's 20 000 tests). With unequal
    scatter (s.d. uniform 0.5-1.5 per target, the review's case) the level is 4.4-5.6 % by 200 000-test
    simulations: here within 3.5-6.5 %."""
    P = np.linspace(0.0, 1000.0, 11)
    lof = lack_of_fit(np.zeros(11), np.ones(11), 5, np.zeros(11), 4)
    assert lof["level"] == 0.05 and lof["dof"] == 7
    tests = 4000
    rate = np.mean(simulated_chi2(np.random.default_rng(11), tests, P, 5, np.full(11, 1e-3)) / 7 > lof["critical"])
    assert abs(rate - 0.05) < 3 * np.sqrt(0.05 * 0.95 / tests) + 0.0015, rate
    rate = np.mean(simulated_chi2(np.random.default_rng(12), tests, P, 5,
                                  lambda rng: rng.uniform(0.5e-3, 1.5e-3, 11)) / 7 > lof["critical"])
    assert 0.035 < rate < 0.065, rate
    # the review's case: a 1.2 µm periodic error, 1 µm repeatability (chi2/nu 4.97 and 4.67) is now rejected
    data, _ = axis_test(rng=np.random.default_rng(27), targets=11, repeatability=0.001, periodic_amplitude=0.0012,
                        periodic_period=130.0)
    for d, p in methods.fit("positioning.gls_polynomial", data).polynomial.items():
        assert 3.6 < p["lack_of_fit"]["chi2_per_dof"] < 6.0 and p["lack_of_fit"]["rejected"], d


def test_the_p_value_is_that_of_the_simulated_distribution():
    """p is the share of the null sample at or above chi2: below the level exactly when rejected, 1 at chi2 = 0
    and at most 1e-4 far out (the periodic axis's chi2/nu 155)."""
    x = np.r_[0.0, 1.0, -1.0, 0.5, -0.5, 0.0, 0.2, -0.3, 0.1, 0.4, -0.2] * 1e-3
    base = lack_of_fit(np.zeros(11), np.full(11, 1e-3), 5, np.zeros(11), 4)
    assert base["p_value"] == 1.0
    for scale in (0.5, 1.0, 2.0, 3.0, 5.0):
        got = lack_of_fit(x * scale, np.full(11, 1e-3), 5, np.zeros(11), 4)
        assert (got["p_value"] < 0.05) == got["rejected"]
    assert lack_of_fit(x * 30, np.full(11, 1e-3), 5, np.zeros(11), 4)["p_value"] < 1e-4


def test_a_correct_cubic_is_not_rejected_more_than_its_level_and_the_instrument_error_does_not_count():
    """200 simulated axes whose error is a cubic (5 runs, 11 targets) through the method: about 5 % rejected (at most
    10 % here), the chi-square quantile (the variances being estimated from 5 runs) rejects far more."""
    from scipy import stats
    rejected, chi_rule = 0, 0
    for seed in range(200):
        data, _ = axis_test(rng=np.random.default_rng(seed), repeatability=0.001)
        lof = methods.fit("positioning.gls_polynomial", data).polynomial["up"]["lack_of_fit"]
        rejected += lof["rejected"]
        chi_rule += lof["chi2"] > stats.chi2.ppf(0.95, lof["dof"])
    assert rejected <= 20 and chi_rule > 2 * max(rejected, 5)
    data, _ = axis_test(rng=np.random.default_rng(1), periodic_amplitude=0.002, periodic_period=130.0)
    a = methods.fit("positioning.gls_polynomial", data).polynomial["up"]["lack_of_fit"]
    b = methods.fit("positioning.gls_polynomial", data, mpe=0.005).polynomial["up"]["lack_of_fit"]
    assert a["rejected"] and b["chi2"] == pytest.approx(a["chi2"], rel=1e-9)


def test_not_testable_is_said():
    assert "no degree of freedom" in lack_of_fit(np.zeros(4), np.ones(4), 5, np.zeros(4), 4)["reason"]
    got = lack_of_fit(np.zeros(6), np.r_[0.0, np.ones(5)], 5, np.zeros(6), 4)
    assert not got["tested"] and not got["rejected"] and "zero scatter" in got["reason"]
