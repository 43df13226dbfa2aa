"""A temperature correction baked into the controller tables is said in every table file and in the output. Before,
`--material-temperature 24 --expansion-coefficient 11.5` put -46 µm/m (46 µm at 1000 mm, on an axis that errs by
less than 1 µm) into the csv, SINUMERIK and FANUC tables and none of the three files mentioned it. The correction is
checked against the difference of the tables with and without it, computed here (alpha (T - 20) (P - R))."""
from __future__ import annotations

import numpy as np
import pytest
import pandas as pd

from cli_calls import cli

EXAMPLE = "docs/examples/positioning.csv"


def tables(tmp_path, tag, *extra):
    paths = {fmt: tmp_path / f"{tag}.{ext}" for fmt, ext in (("csv", "csv"), ("siemens-eec", "mpf"), ("fanuc-pitch", "tap"))}
    args = [a for fmt, p in paths.items() for a in ("--compensation", fmt, p)]
    out = cli("positioning", EXAMPLE, "--axis", "X1", "--interval", "100mm", *extra, *args)
    assert out.returncode == 0, out.stderr
    return out, paths


def test_every_table_file_and_the_output_say_the_temperature_correction(tmp_path):
    T, alpha = 24.0, 11.5
    out, corrected = tables(tmp_path, "th", "--material-temperature", T, "--expansion-coefficient", alpha)
    _, raw = tables(tmp_path, "raw")
    read = {k: pd.read_csv(p[("csv")], comment="#") for k, p in (("th", corrected), ("raw", raw))}
    P = read["th"].position_mm.to_numpy()
    slope = alpha * 1e-6 * (T - 20.0)
    # independent: the corrected table differs from the raw one by alpha (T - 20) (P - R), R = 0 here
    np.testing.assert_allclose(read["th"].compensation_mm - read["raw"].compensation_mm, slope * P, atol=2e-6)
    ends = f"{-slope * P[0] * 1e3 + 0.0:+.3f} um at {P[0]:g} mm, {-slope * P[-1] * 1e3:+.3f} um at {P[-1]:g} mm"
    assert ends == "+0.000 um at 0 mm, -46.000 um at 1000 mm"
    for fmt, path in corrected.items():
        head = path.read_text().upper()
        assert "TEMPERATURE-CORRECTED" in head and "MATERIAL TEMPERATURE OF 24 C" in head, fmt
        assert "11.5 UM/" in head and "-46 UM/M" in head and ends.upper().replace(",", "") in head.replace(",", ""), fmt
    for fmt, path in raw.items():
        assert "TEMPERATURE" not in path.read_text().upper(), fmt
    assert ends.replace("um", "µm") in out.stdout
    assert "the compensation tables hold the deviations corrected to 20 °C from 24 °C" in out.stdout


def test_the_api_table_carries_the_correction():
    import methods
    from datasets.io import read_positioning
    from fitbench.compensation import compensation_table, write_csv
    from methods.positioning.data import thermal_correction
    data = thermal_correction(read_positioning(EXAMPLE), 26.0, 11.5)
    assert data.thermal["correction_at_ends_mm"][1] == pytest.approx((1000.0, -11.5e-6 * 6 * 1000.0), rel=1e-12)
    text = write_csv(compensation_table(methods.fit("positioning.gls_polynomial", data), data))
    assert "TEMPERATURE-CORRECTED" in text and "-69.000 um at 1000 mm" in text
