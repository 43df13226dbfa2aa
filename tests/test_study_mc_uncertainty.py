"""Monte-Carlo uncertainty in the findings of ellipse_angle (RMS / first-order prediction) and noise (radius RMSE /
KCR bound): ratios carry their standard error, classifications and 'consistent' claims are made with it."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest


def test_ratio_standard_error_is_the_scatter_of_an_rms_of_n_gaussian_draws():
    from experiments.studies.ellipse_angle import ratio_standard_error
    rng = np.random.default_rng(1)
    for n in (40, 400):
        rms = np.sqrt(np.mean(rng.standard_normal((20000, n)) ** 2, axis=1))
        assert np.std(rms) == pytest.approx(ratio_standard_error(n), rel=0.05)


def test_consistency_text_names_the_rows_beyond_two_standard_errors():
    """The committed 40-copy ratios: 0.82 is 1.6 s.e. below 1 (consistent), 1.42 is 3.7 s.e. above (named)."""
    from experiments.studies.ellipse_angle import consistency_text, ratio_standard_error
    se = np.full(3, ratio_standard_error(40))
    text = consistency_text("m", np.array([1.00, 0.82, 1.416]), se, np.array([0.0005, 0.001, 1.0]))
    assert "within 2 standard errors of 1 at 2 of 3 a − b" in text
    assert "3.7 s.e. above at a − b = 1 mm (1.42)" in text and "0.001 mm" not in text


def _ellipse_rows(scale_last: float, reps: int, n_points: int = 200):
    """Angle errors drawn with the first-order s.d. (the last a - b scaled by ``scale_last``)."""
    from experiments.studies.ellipse_angle import predicted_angle_sd
    from datasets.synthetic import ellipse_points
    params = {"center": [0.0, 0.0], "angle_deg": 30.0, "n": n_points, "noise": 0.001}
    rng = np.random.default_rng(2)
    rows = []
    axes = [[10.0, 9.99], [10.0, 9.9]]
    for k, (a, b) in enumerate(axes):
        sd = predicted_angle_sd(ellipse_points((0, 0), (a, b), np.radians(30.0), n_points), np.array([0, 0, a, b, np.radians(30.0)]), 0.001)
        sd *= scale_last if k == len(axes) - 1 else 1.0
        e = rng.standard_normal(reps)
        e *= sd / np.sqrt(np.mean(e ** 2))        # RMS exactly sd: the ratio is exactly 1 (or scale_last)
        for m in ("ellipse.halir_flusser", "ellipse.orthogonal"):
            rows += [{"data_semi_axes": json.dumps([a, b]), "method": m, "status": "ok", "angle_error": v} for v in e]
    return pd.DataFrame(rows), {"datasets": [{"params": params}]}


def test_ellipse_angle_table_and_findings_carry_the_standard_error(tmp_path):
    from experiments.studies.ellipse_angle import EllipseAngleStudy
    df, cfg = _ellipse_rows(1.3, reps=50)
    an = EllipseAngleStudy().analyse(df, cfg, tmp_path, lambda s: None)
    t = an.tables[0].data
    assert list(t["ellipse.halir_flusser ratio"].round(6)) == [1.0, 1.3]
    assert np.allclose(t["ratio s.e."], 0.1)                       # 1 / sqrt(2 x 50)
    assert an.tables[0].decimals["ratio s.e."] == 3 and an.tables[0].decimals["ellipse.orthogonal ratio"] == 2
    # 1.3 is 3.0 standard errors above: named, not read as the prediction's range
    assert "within 2 standard errors of 1 at 1 of 2 a − b; 3.0 s.e. above at a − b = 0.1 mm (1.30)" in an.findings
    assert "one Monte-Carlo standard error of a ratio is ±10.0 %" in an.findings
    assert an.values["ratio_standard_error"]["ellipse.orthogonal"] == pytest.approx([0.1, 0.1])
