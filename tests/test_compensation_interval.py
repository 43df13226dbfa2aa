"""``--interval`` of a compensation table: the table covers the measured travel, never extrapolates the model
beyond it, and an interval too coarse to represent the measured curve (or longer than the travel) is refused,
naming one that does. Before: --interval 5000 on a -400..600 mm axis wrote -5000, 0, 5000 mm holding the cubic
extrapolated 4.4 m (7.47 mm), exit 0; --interval 700 left 15.6 of 22.6 µm in the simulated controller."""
from __future__ import annotations

import re

import numpy as np
import pytest

import methods
from compensation_controllers import READERS, remeasure
from datasets.positioning import axis_test, to_frame
from fitbench.compensation import REPRESENT_SHARE, WRITERS, CompensationError, compensation_table
from methods.positioning.model import evaluate_band
from cli_calls import cli, one_error_line

KW = {"travel": (-400.0, 600.0), "pitch": (0.0, 0.060, -0.090, 0.045), "reversal": -0.004, "repeatability": 0.0004,
      "irregular": 0.3}


def axis(seed=4):
    data, truth = axis_test(rng=np.random.default_rng(seed), **KW)
    return data, truth, methods.fit("positioning.gls_polynomial", data)


@pytest.mark.parametrize("interval, why", [("5000", "longer than the measured travel (1000 mm)"),
                                           ("700", "too coarse")])
@pytest.mark.parametrize("fmt", list(WRITERS))
def test_a_coarse_interval_writes_nothing_and_names_one_that_works(tmp_path, interval, why, fmt):
    data, truth, res = axis()
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--interval", interval, "--axis", "X1", "--compensation", fmt, tmp_path / "t.txt")
    one_error_line(out, f"--interval {interval} mm is {why}", "or finer", "leave it out")
    assert not (tmp_path / "t.txt").exists()
    ok = float(re.search(r"give --interval (\S+) or finer", out.stderr).group(1))
    assert ok < 1000.0
    # the interval the message names works, and the controller applying it halves the error
    good = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--interval", ok, "--axis", "X1", "--compensation", fmt, tmp_path / "t.txt")
    assert good.returncode == 0, good.stderr
    before = methods.fit("positioning.iso230_2", data).figures
    encoder, _ = READERS[fmt]((tmp_path / "t.txt").read_text())
    after = methods.fit("positioning.iso230_2", remeasure(data, truth, encoder, np.random.default_rng(9))).figures
    assert after["M"] <= 0.5 * before["M"], (before["M"], after["M"])


@pytest.mark.parametrize("source", ["model", "mean"])
def test_values_beyond_the_targets_are_the_end_targets_values(source):
    """A table reaching a step beyond the travel holds the end targets' values there (the model is never
    extrapolated), and every table it passes reproduces the curve at the targets within the bound."""
    data, _, res = axis()
    res_iso = methods.fit("positioning.iso230_2", data) if source == "mean" else res
    t = compensation_table(res_iso, data, interval=70.0, source=source)   # -420 ... 630 mm
    P = data.targets
    assert t.position_mm.iloc[0] < P[0] and t.position_mm.iloc[-1] > P[-1]       # covers the travel, beyond it
    if source == "model":
        ends = np.mean([evaluate_band(res.polynomial[d], P[[0, -1]])[0] for d in ("up", "down")], axis=0)
    else:
        ends = res_iso.per_target["mean_bidirectional"][[0, -1]]
    before, after = t.position_mm < P[0], t.position_mm > P[-1]
    np.testing.assert_allclose(t.deviation_mm[before], ends[0], atol=1e-15)
    np.testing.assert_allclose(t.deviation_mm[after], ends[-1], atol=1e-15)
    assert "held at" in WRITERS["csv"](t)


def test_the_bound_is_what_the_refusal_says():
    """The refusal's figures: the miss at the targets of the table interpolated linearly, against
    REPRESENT_SHARE of the curve's span."""
    data, _, res = axis()
    with pytest.raises(CompensationError) as err:
        compensation_table(res, data, interval=700.0)
    miss, span, tol = (float(v) for v in re.search(r"by up to (\S+) µm of the (\S+) µm the curve spans \(at most (\S+) µm",
                                                   str(err.value)).groups())
    assert miss > tol == pytest.approx(REPRESENT_SHARE * span, rel=2e-3)


def test_a_default_table_that_misses_the_means_is_warned_about():
    """Means at irregular targets with a 2 µm periodic error are a broken line an equally spaced grid cannot pass
    through: the default table (no --interval asked for) is written, with a warning giving the miss; the model's
    default table of the same axis, and a regular axis' mean table, are not warned about."""
    data, _ = axis_test(rng=np.random.default_rng(0), irregular=0.4, periodic_amplitude=0.002, periodic_period=130)
    iso = methods.fit("positioning.iso230_2", data)
    with pytest.warns(UserWarning, match=r"misses the means at the targets by up to \S+ µm of the \S+ µm"):
        compensation_table(iso, data, source="mean")
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        compensation_table(methods.fit("positioning.gls_polynomial", data), data)
        regular, _ = axis_test(rng=np.random.default_rng(0))
        compensation_table(methods.fit("positioning.iso230_2", regular), regular, source="mean")


def test_the_default_table_of_irregular_targets_fits_the_sinumerik(tmp_path):
    """ISO 230-2's irregular targets make the smallest spacing (the default step) far finer than the mean spacing:
    21 targets on 1000 mm gave 272 points and the default siemens-eec table was refused (200 points). The default
    is now the finest step that fits, said in the output, and the simulated controller halves M with it."""
    from datasets.positioning import pitch_curve
    from methods.positioning.data import PositioningData
    rng = np.random.default_rng(21)
    T = np.sort(np.r_[0, 1000, rng.uniform(20, 980, 19)]).round(1)         # the review's irregular targets
    assert np.min(np.diff(T)) < 1000.0 / 199                                 # the smallest spacing gives > 200 points
    truth = {"up": lambda x: pitch_curve(np.asarray(x) / 1000.0, KW["pitch"]) + KW["reversal"] / 2,
             "down": lambda x: pitch_curve(np.asarray(x) / 1000.0, KW["pitch"]) - KW["reversal"] / 2, "delta": 0.0}
    data = PositioningData(targets=T, up=truth["up"](T)[:, None] + rng.normal(0, KW["repeatability"], (21, 5)),
                           down=truth["down"](T)[:, None] + rng.normal(0, KW["repeatability"], (21, 5)), unit="mm")
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X1",
              "--compensation", "siemens-eec", tmp_path / "t.mpf", "--compensation", "fanuc-pitch", tmp_path / "t.tap")
    assert out.returncode == 0, out.stderr
    step = float(re.search(r"every (\S+) mm, the finest step whose table fits siemens-eec's 200 points", out.stdout).group(1))
    # the FANUC tape gets the SINUMERIK's step, and the output says a finer one is there for it alone
    assert "so fanuc-pitch gets siemens-eec's step: written without siemens-eec, it takes a finer one" in out.stdout
    alone = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X1",
                "--compensation", "fanuc-pitch", tmp_path / "t.tap")
    assert float(re.search(r"fanuc-pitch, every (\S+) mm", alone.stdout).group(1)) < step
    encoder, info = READERS["siemens-eec"]((tmp_path / "t.mpf").read_text())
    assert len(info["values"]) <= 200 and abs(step * 199 - 1000.0) < 1.0           # 200 points, no coarser than needed
    before = methods.fit("positioning.iso230_2", data).figures
    after = methods.fit("positioning.iso230_2", remeasure(data, truth, encoder, np.random.default_rng(9))).figures
    assert after["M"] <= 0.5 * before["M"], (before["M"], after["M"])


def test_the_named_interval_ends_the_table_at_the_travel_end(tmp_path):
    """The interval a refusal names is travel / k rounded up to 0.001 mm, so its table reaches the last target at
    its k-th step (within k x 0.001 mm). Before it was rounded down (47.619 for 1000 / 21): the grid stopped
    0.021 mm short of the last target and the table added a point 47.6 mm beyond the travel."""
    data, _ = axis_test(rng=np.random.default_rng(0), irregular=0.4, periodic_amplitude=0.002, periodic_period=130)
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    args = ("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X1", "--compensation-from", "mean")
    out = cli(*args, "--interval", "300", "--compensation", "csv", tmp_path / "t.csv")
    one_error_line(out, "--interval 300 mm is too coarse", "or finer")
    named = float(re.search(r"give --interval (\S+) or finer", out.stderr).group(1))
    assert cli(*args, "--interval", named, "--compensation", "csv", tmp_path / "t.csv").returncode == 0
    grid = read_csv_table(tmp_path / "t.csv")
    steps = len(grid) - 1
    assert grid[0] == data.targets[0] and 0.0 <= grid[-1] - data.targets[-1] <= steps * 0.001 + 1e-9, (named, grid[-1])


def read_csv_table(path):
    import pandas as pd
    return pd.read_csv(path, comment="#").position_mm.to_numpy()
