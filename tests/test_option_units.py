"""Units of the temperature options of ``positioning`` and the feed of ``circular-test``: a value given in another
unit than the option's (1/K for µm/(m·K), °F for °C, m/min for mm/min) is refused or warned about, naming the
likely unit; a unit written with the value is accepted. Before: 11.5e-6 applied no correction, 79 (°F) gave
A = 661 µm, --feed 1 gave a servo mismatch of -41 ms, all without a word."""
from __future__ import annotations

import json

import numpy as np
import pytest

from datasets.positioning import axis_test, to_frame
from cli_calls import cli, one_error_line


@pytest.fixture
def axis_file(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(1), pitch=(0.0, 0.01), reversal=-0.002)
    p = tmp_path / "a.csv"
    to_frame(data, actual=False).to_csv(p, index=False)
    return p


def run(path, temp, alpha):
    out = cli("positioning", path, "--json", "--material-temperature", temp, "--expansion-coefficient", alpha)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def test_a_coefficient_in_one_per_kelvin_is_refused_naming_the_unit(axis_file):
    one_error_line(cli("positioning", axis_file, "--material-temperature", 26, "--expansion-coefficient", "11.5e-6"),
                   "11.5e-6 looks like 1/K", "give 11.5", "or 11.5e-6/K")
    si, bare, ppm = (run(axis_file, 26, a) for a in ("11.5e-6/K", "11.5", "11.5ppm/K"))
    assert si["E"] == bare["E"] == ppm["E"]
    assert si["temperature_correction"]["expansion_coefficient_um_per_m_k"] == pytest.approx(11.5)
    assert si["temperature_correction"]["correction_um_per_m"] == pytest.approx(-69.0)


def test_a_fahrenheit_temperature_is_refused_naming_the_unit(axis_file):
    one_error_line(cli("positioning", axis_file, "--material-temperature", 79, "--expansion-coefficient", 11.5),
                   "79 °C is outside a workshop's 10 to 40 °C", "is it °F (26.1 °C)? give 79F", "79C to confirm °C")
    f = run(axis_file, "79F", 11.5)
    c = run(axis_file, (79 - 32) * 5 / 9, 11.5)
    assert f["temperature_correction"]["material_temperature_c"] == pytest.approx(26.111111, abs=1e-6)
    assert f["E"] == pytest.approx(c["E"], abs=1e-12)
    assert run(axis_file, "79C", 11.5)["temperature_correction"]["material_temperature_c"] == 79.0   # confirmed
    assert run(axis_file, "299.15K", 11.5)["temperature_correction"]["material_temperature_c"] == pytest.approx(26.0)
    text = cli("positioning", axis_file, "--material-temperature", "79F", "--expansion-coefficient", 11.5).stdout
    assert "material at 26.11 °C (79F), expansion coefficient 11.5 µm/(m·K)" in text
    one_error_line(cli("positioning", axis_file, "--material-temperature", "26 bananas", "--expansion-coefficient", 11.5),
                   "give °C as a bare number")


def test_a_feed_in_metres_per_minute_is_warned_about(tmp_path):
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    r = 150 + 0.002 * np.cos(2 * t)
    for name, sign in (("cw.csv", -1), ("ccw.csv", 1)):
        np.savetxt(tmp_path / name, np.column_stack([r * np.cos(sign * t), r * np.sin(sign * t)]), delimiter=",",
                   header="x,y", comments="")
    args = ("circular-test", tmp_path / "cw.csv", tmp_path / "ccw.csv", "--nominal-radius", 150, "--nominal-center", 0, 0)
    slow = cli(*args, "--feed", 1)
    assert slow.returncode == 0
    assert "warning: --feed 1 mm/min: one revolution of the R 150 mm circle would take 15.7 h" in slow.stderr
    assert "is it m/min? --feed 1000" in slow.stderr
    assert "--feed" not in cli(*args, "--feed", 1000).stderr
