"""A column whose unit is not a length's was told to have its unit renamed mm ('e.g. Target [mm]'): following the
advice evaluates degrees, a filter cutoff or a temperature as millimetres. A rotary positioning file (targets in
degrees, deviations in arcsec) is refused as not supported; a column of another quantity ('Temp [°C]') is named as
such, never advised to be mm; an instrument's preamble above the header ('Cutoff (UPR);50', or a numeric '50;3600'
taken for data) gets the --skip-rows hint that reads the file."""
from __future__ import annotations

import numpy as np
import pytest

from cli_calls import cli, one_error_line


def wide_positioning(path, target_unit, deviation_unit):
    runs = ";".join(f"Run {r} {d} ({deviation_unit})" for r in (1, 2, 3, 4, 5) for d in "+-")
    rng = np.random.default_rng(3)
    rows = [f"{t:.3f};" + ";".join(f"{v:.2f}" for v in rng.normal(0, 1, 10)) for t in (0, 30, 60, 90, 120)]
    path.write_text(f"Target ({target_unit});{runs}\n" + "\n".join(rows) + "\n")
    return path


def test_a_rotary_positioning_file_is_refused_as_not_supported(tmp_path):
    one_error_line(cli("positioning", wide_positioning(tmp_path / "rot.csv", "deg", "arcsec")),
                         "'Target (deg)' holds targets in an angle unit: a rotary axis", "not supported",
                         "linear axes")
    code, _, err = cli("positioning", wide_positioning(tmp_path / "rot.csv", "deg", "arcsec"))
    assert "[mm]" not in err, err
    one_error_line(cli("positioning", wide_positioning(tmp_path / "pitch.csv", "mm", "arcsec")),
                   "'Run 1 + (arcsec)' holds deviations in an angle unit", "not supported")
    code, out, err = cli("positioning", wide_positioning(tmp_path / "lin.csv", "mm", "um"))
    assert code == 0, err


def profile_rows():
    deg = np.arange(0, 360, 1.0)
    return "".join(f"{a:.3f};{2 * np.cos(np.radians(3 * a)):.4f}\n" for a in deg)


@pytest.mark.parametrize("preamble, skip", [("Cutoff (UPR);50\nPoints;3600\n", 2), ("50;3600\n", 1),
                                            ("50;3600\n1;2\n", 2)])
def test_a_preamble_above_the_header_gets_the_skip_rows_hint(tmp_path, preamble, skip):
    p = tmp_path / "pre.csv"
    p.write_text(preamble + "Winkel [°];Abweichung [µm]\n" + profile_rows())
    called = cli("roundness", p)
    one_error_line(called, f"give --skip-rows {skip}")
    assert "[mm]" not in called.stderr, called.stderr
    code, out, err = cli("roundness", p, "--skip-rows", skip)
    assert code == 0 and "RONt" in out, err


def test_a_temperature_column_is_not_advised_to_be_mm(tmp_path):
    p = tmp_path / "tc.csv"
    p.write_text("Temp [°C];Deviation [um]\n" + "".join(f"{0.1 * k:.5f};{np.cos(k / 9):.5f}\n" for k in range(60)))
    called = cli("roundness", p)
    one_error_line(called, "'Temp [°C]' carries the unit '°c', a temperature, not a length")
    assert "[mm]" not in called.stderr, called.stderr
