"""Positioning (ISO 230-2) and the GLS polynomial model."""
import json

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import methods
from cli_calls import cli
from datasets.positioning import axis_test, to_frame
from methods import InvalidInputError
from datasets.io import read_positioning as read_csv
from methods.positioning.data import PositioningData
from methods.positioning.model import evaluate_band


@settings(max_examples=80, deadline=None)
@given(m=st.integers(2, 12), n=st.integers(2, 7), seed=st.integers(0, 2**32 - 1),
       standard=st.sampled_from(["iso230-2:2014", "iso230-2:1988"]))
def test_invariants(m, n, seed, standard):
    rng = np.random.default_rng(seed)
    data = PositioningData(targets=np.sort(rng.uniform(0, 500, m)) + np.arange(m), up=rng.normal(0, 0.01, (m, n)) + rng.normal(0, 0.01),
                           down=rng.normal(0, 0.01, (m, n)) + rng.normal(0, 0.01))
    f = methods.fit("positioning.iso230_2", data, standard=standard).figures
    assert f["E"] >= max(f["E_up"], f["E_down"]) - 1e-15
    assert f["A"] >= max(f["A_up"], f["A_down"]) - 1e-15
    assert f["R"] >= max(f["R_up"], f["R_down"]) - 1e-15
    assert f["M"] <= f["E"] + 1e-15


def test_figures_by_hand():
    """A 2-target, 2-run example computed by hand (k = 2)."""
    data = PositioningData(targets=np.array([0.0, 100.0]), up=np.array([[1.0, 3.0], [4.0, 4.0]]),
                           down=np.array([[0.0, 0.0], [2.0, 6.0]]))
    f = methods.fit("positioning.iso230_2", data).figures
    r2 = np.sqrt(2.0)  # means up (2, 4), s up (sqrt 2, 0); means down (0, 4), s down (0, 2 sqrt 2)
    assert f["E_up"] == pytest.approx(2.0) and f["E_down"] == pytest.approx(4.0) and f["E"] == pytest.approx(4.0)
    assert f["B"] == pytest.approx(2.0) and f["B_mean"] == pytest.approx(1.0)  # B_i = (2, 0)
    assert f["M"] == pytest.approx(3.0)  # bidirectional means (1, 4)
    assert f["R_up"] == pytest.approx(4 * r2) and f["R_down"] == pytest.approx(8 * r2)
    assert f["R"] == pytest.approx(8 * r2)  # max(2 r2 + 0 + 2, 4 r2) and max(0 + 4 r2 + 0, 8 r2)
    assert f["A_up"] == pytest.approx((2 + 2 * r2) - (2 - 2 * r2))
    assert f["A_down"] == pytest.approx((4 + 4 * r2) - (4 - 4 * r2))
    assert f["A"] == pytest.approx((4 + 4 * r2) - (4 - 4 * r2))


def test_gls_without_instrument_error_is_weighted_least_squares(rng):
    data, _ = axis_test(rng=rng, repeatability=0.001)
    res = methods.fit("positioning.gls_polynomial", data, instrument_u=0.0)
    per = res.per_target
    w = 1.0 / (per["s_up"] ** 2 / data.runs)
    X = np.vander(data.targets, 4, increasing=True)
    W = np.diag(w)
    beta = np.linalg.solve(X.T @ W @ X, X.T @ W @ per["mean_up"])
    np.testing.assert_allclose(res.polynomial["up"]["coefficients"], beta, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(res.polynomial["up"]["covariance"], np.linalg.inv(X.T @ W @ X), rtol=1e-5, atol=1e-30)


def test_gls_with_large_instrument_error_tends_to_ols():
    """With equal scatter at every target, GLS is OLS whatever u(delta); in general the common error never
    changes the estimate when the polynomial has a constant term (it only adds u^2(delta) to the constant's
    variance): the constant term's uncertainty grows like u(delta)."""
    rng = np.random.default_rng(5)
    m, n = 11, 5
    targets = np.linspace(0, 1000, m)
    noise = rng.normal(0, 1, (m, n))
    noise = (noise - noise.mean(axis=1, keepdims=True)) / noise.std(axis=1, ddof=1, keepdims=True) * 0.001
    curve = (1e-3 + 2e-6 * targets - 3e-9 * targets ** 2)[:, None]
    data = PositioningData(targets=targets, up=curve + noise + rng.normal(0, 3e-4, (m, 1)), down=curve + noise)
    ols = methods.fit("positioning.ols_polynomial", data)
    sd = []
    for ud in (1e-1, 1e1, 1e3):
        gls = methods.fit("positioning.gls_polynomial", data, instrument_u=ud)
        np.testing.assert_allclose(gls.polynomial["up"]["coefficients"], ols.polynomial["up"]["coefficients"],
                                   rtol=1e-6, atol=1e-15)
        sd.append(np.sqrt(gls.polynomial["up"]["covariance"][0, 0]))
    assert sd[1] / sd[0] == pytest.approx(100, rel=1e-3) and sd[2] / sd[1] == pytest.approx(100, rel=1e-6)
    # unequal scatter: the estimate is GLS with u(delta) = 0 (weighted least squares), the constant's variance + u^2
    data, _ = axis_test(rng=np.random.default_rng(3))
    w0 = methods.fit("positioning.gls_polynomial", data, instrument_u=0.0).polynomial["up"]
    w1 = methods.fit("positioning.gls_polynomial", data, instrument_u=0.01).polynomial["up"]
    np.testing.assert_allclose(w1["coefficients"], w0["coefficients"], rtol=1e-9)
    assert w1["covariance"][0, 0] - w0["covariance"][0, 0] == pytest.approx(1e-4, rel=1e-9)


@pytest.mark.parametrize("ud", [0.0, 3e-4, 2e-3])
def test_gls_equals_the_dense_formula(ud, rng):
    """eq. 8-10 literally: U = diag(s_i^2 / n) + u^2(delta) 1 1^T, beta = (X^T U^-1 X)^-1 X^T U^-1 x."""
    data, _ = axis_test(rng=rng)
    res = methods.fit("positioning.gls_polynomial", data, instrument_u=ud).polynomial["down"]
    per = methods.fit("positioning.iso230_2", data).per_target
    U = np.diag(per["s_down"] ** 2 / data.runs) + ud ** 2 * np.ones((11, 11))
    X = np.vander(data.targets, 4, increasing=True)
    Ui = np.linalg.inv(U)
    cov = np.linalg.inv(X.T @ Ui @ X)
    beta = cov @ X.T @ Ui @ per["mean_down"]
    np.testing.assert_allclose(res["coefficients"], beta, rtol=1e-6)
    np.testing.assert_allclose(np.sqrt(np.diag(res["covariance"])), np.sqrt(np.diag(cov)), rtol=1e-5)


def test_mpe_is_rectangular(rng):
    data, _ = axis_test(rng=rng)
    a = methods.fit("positioning.gls_polynomial", data, mpe=0.003)
    b = methods.fit("positioning.gls_polynomial", data, instrument_u=0.003 / np.sqrt(3))
    np.testing.assert_allclose(a.polynomial["down"]["covariance"], b.polynomial["down"]["covariance"])
    with pytest.raises(InvalidInputError, match="not both"):
        methods.fit("positioning.gls_polynomial", data, mpe=0.003, instrument_u=0.001)


def test_exact_cubic_is_recovered():
    data, truth = axis_test(repeatability=1e-9, reversal=0.004, rng=np.random.default_rng(0))
    res = methods.fit("positioning.gls_polynomial", data, instrument_u=1e-9)
    P = np.linspace(0, 1000, 50)
    for d in ("up", "down"):
        v, U = evaluate_band(res.polynomial[d], P)
        np.testing.assert_allclose(v, truth[d](P), atol=1e-8)


def test_band_coverage_when_the_model_holds():
    """Monte Carlo: with Gaussian errors and a cubic truth, the k = 2 band covers the true curve at a
    random position about 95 % of the time (measured 94.5 % over 1500 tests; the binomial standard
    error of 1000 trials is 0.7 %); a rectangular instrument error makes it conservative instead."""
    hits, trials = 0, 1000
    rng = np.random.default_rng(42)
    for _ in range(trials):
        data, truth = axis_test(rng=rng, instrument_sd=0.001, repeatability=0.001)
        res = methods.fit("positioning.gls_polynomial", data, instrument_u=0.001)
        P = rng.uniform(0, 1000)
        v, U = evaluate_band(res.polynomial["up"], P)
        hits += abs(v[0] - truth["up"](P)) <= U[0]
    assert 0.925 <= hits / trials <= 0.975


def test_reader_accepts_and_refuses(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(1))
    df = to_frame(data)
    p = tmp_path / "ok.csv"
    df.to_csv(p, index=False)
    got = read_csv(p)
    np.testing.assert_allclose(got.up, data.up, atol=1e-12)
    df2 = to_frame(data, actual=False).replace({"+": "up", "-": "down"})
    p2 = tmp_path / "ok2.csv"
    df2.to_csv(p2, sep=";", index=False)
    np.testing.assert_allclose(read_csv(p2).down, data.down, atol=1e-12)
    lines = p.read_text().splitlines()
    cases = {
        "text": (lines[:3] + [lines[3].replace(lines[3].split(",")[3], "abc")] + lines[4:], "line 4: actual 'abc' is not a finite number"),
        "missing_run": ([lines[0]] + [l for l in lines[1:] if not l.startswith("0.0,+,2,")], "target 0 misses run"),
        "one_run": ([lines[0]] + [l for l in lines[1:] if not (l.startswith("100.0,-,") and not l.startswith("100.0,-,1,"))], "target 100 has 1 run"),
        "direction": ([lines[0], lines[1].replace(",+,", ",sideways,")] + lines[2:], "direction 'sideways'"),
        "columns": (["target,way,run,actual"] + lines[1:], "missing column 'direction'"),
    }
    for name, (content, match) in cases.items():
        f = tmp_path / f"{name}.csv"
        f.write_text("\n".join(content) + "\n")
        with pytest.raises(InvalidInputError, match=match):
            read_csv(f)


def test_cli_json_keys_and_plot(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(2), mpe=0.002)
    p = tmp_path / "axis.csv"
    to_frame(data).to_csv(p, index=False)
    out = cli("positioning", p, "--mpe", "0.002", "--json", "--plot", tmp_path / "axis.png")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    for key in ("A", "A_up", "A_down", "E", "E_up", "E_down", "M", "R", "R_up", "R_down", "B", "B_mean", "per_target",
                "polynomial"):
        assert key in d
    for direction in ("up", "down"):
        assert len(d["polynomial"][direction]["coefficients"]) == 4
        assert np.array(d["polynomial"][direction]["covariance"]).shape == (4, 4)
    assert (tmp_path / "axis.png").stat().st_size > 10_000
    bad = cli("positioning", p, "--mpe", "1", "--instrument-u", "1")
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
