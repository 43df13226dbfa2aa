"""``--nominal-radius`` of roundness and fit. A value typed in µm for a 10 mm part (10000) was warned about as the
file's unit ('profile radii (half the points' span) up to 10000 mm (read as µm) are implausible; is the file in nm?
(--unit nm)'), though the header said µm; the warning now names the option and the value to give, as circular-test
does for its own. An angle + radius file, or an x, y file, given --nominal-radius ignored it without a word; a note
says it is not used."""
from __future__ import annotations

import numpy as np
import pytest

from cli_calls import cli

N = 720


def profile(tmp_path, kind):
    """A 10 mm part with a 3-lobe form of 2 µm amplitude: 'dev' angle [deg] + deviation [µm], 'rad' angle [rad] +
    radius [mm], 'xy' x, y [mm]."""
    t = np.arange(N) * 2 * np.pi / N
    dev_um = 2.0 * np.cos(3 * t)
    path = tmp_path / f"{kind}.csv"
    if kind == "dev":
        path.write_text("Angle [deg];Deviation [µm]\n" + "".join(
            f"{np.degrees(a):.4f};{d:.5f}\n".replace(".", ",") for a, d in zip(t, dev_um)))
    elif kind == "rad":
        path.write_text("theta [rad],r [mm]\n" + "".join(f"{a:.9f},{10 + d * 1e-3:.9f}\n" for a, d in zip(t, dev_um)))
    else:
        r = 10 + dev_um * 1e-3
        path.write_text("x [mm],y [mm]\n" + "".join(f"{x:.9f},{y:.9f}\n" for x, y in zip(r * np.cos(t), r * np.sin(t))))
    return path


def test_a_nominal_radius_typed_in_micrometres_is_blamed_on_the_option(tmp_path):
    path = profile(tmp_path, "dev")
    out = cli("roundness", path, "--nominal-radius", 10000)
    assert out.returncode == 0, out.stderr
    assert ("fitbench: warning: --nominal-radius 10000 mm is implausible for a roundness part (radii above 1000 mm); "
            "is it in µm? give --nominal-radius 10 (or 10000um)") in out.stderr
    assert "--unit" not in out.stderr and "is the file in" not in out.stderr
    fit = cli("fit", "circle.minimum_zone", path, "--nominal-radius", 10000)
    assert fit.returncode == 0 and "--nominal-radius 10000 mm is implausible for a profile" in fit.stderr
    for ok in (10, "10mm", "10000um"):
        good = cli("roundness", path, "--nominal-radius", ok)
        assert good.returncode == 0 and "warning" not in good.stderr, (ok, good.stderr)


@pytest.mark.parametrize("kind, what", [("rad", "radii, not radial deviations"), ("xy", "x, y coordinates")])
def test_a_nominal_radius_a_file_does_not_use_is_said_to_be_unused(tmp_path, kind, what):
    path = profile(tmp_path, kind)
    for command in (("roundness",), ("fit", "circle.kasa")):
        out = cli(*command, path, "--nominal-radius", 10)
        assert out.returncode == 0, out.stderr
        assert f"note: --nominal-radius 10 mm is not used: the file gives {what}" in out.stdout, (command, out.stdout)
        assert "not used" not in cli(*command, path).stdout
    dev = cli("roundness", profile(tmp_path, "dev"), "--nominal-radius", 10)
    assert "not used" not in dev.stdout


def test_a_nominal_radius_typed_in_metres_is_blamed_on_the_option(tmp_path):
    """--nominal-radius 0.01 for a 10 mm part (review16 V6) was 'radial deviations up to 0.002 mm (read as µm) are
    implausible; is the file in µm? (--unit um)', blaming a file whose header says µm."""
    path = profile(tmp_path, "dev")
    for command in (("roundness",), ("fit", "circle.kasa")):
        out = cli(*command, path, "--nominal-radius", 0.01)
        assert out.returncode == 0, out.stderr
        assert ("warning: --nominal-radius 0.01 mm is implausibly small for these deviations (up to 2 µm, 20% of it); "
                "is it in m? give --nominal-radius 10 (or 0.01m)") in out.stderr, (command, out.stderr)
        assert "--unit" not in out.stderr


def test_a_roundness_part_of_micrometres_is_warned_about(tmp_path):
    """An x, y file in mm read with --unit um (a part of radius 0.01 mm, RONt in nm) was evaluated without a word
    (review16 V3)."""
    path = profile(tmp_path, "xy")
    path.write_text(path.read_text().replace("x [mm],y [mm]", "x,y"))     # no unit in the header
    out = cli("roundness", path, "--unit", "um")
    assert out.returncode == 0, out.stderr
    assert ("warning: profile radii (half the points' span) of 0.01 mm (read as µm) are implausibly small for a "
            "roundness part (below 0.05 mm); is the file in mm? (--unit mm)") in out.stderr
    assert "warning" not in cli("roundness", path).stderr
