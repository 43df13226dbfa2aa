"""``fitbench fit`` of an angle + radial deviation file without --nominal-radius: the deviations are evaluated alone
(the limaçon approximation, ISO 12181-1), whose form error is wrong by up to e²/(2R) for a part e off the spindle axis.
``fitbench roundness`` warned of it; ``fitbench fit`` of the same file said nothing. Checked against NumPy's first
harmonic of the deviations (test_roundness_eccentric.limacon)."""
from __future__ import annotations

import json
import re

import pytest

from cli_calls import cli
from test_roundness_eccentric import R, instrument_file, limacon


@pytest.mark.parametrize("method", ["circle.gauss_newton", "circle.minimum_zone"])
def test_fit_of_an_uncentred_part_without_its_radius_is_warned_about(tmp_path, method):
    th, dev = instrument_file(tmp_path / "p.txt", 0.117)
    e, _ = limacon(th, dev)
    out = cli("fit", method, tmp_path / "p.txt")
    assert out.returncode == 0, out.stderr
    m = re.search(r"warning: the profile is (\S+) µm off centre \(.* x RONt (\S+) µm.*for R below (\S+) mm; "
                  r"give --nominal-radius", out.stderr)
    assert m and out.stderr.count("\n") == 1, out.stderr
    assert float(m.group(1)) == pytest.approx(e * 1e3, abs=0.1)
    form_um = float(re.search(r"form error\s+(\S+) mm", out.stdout).group(1)) * 1e3
    assert float(m.group(2)) == pytest.approx(form_um, rel=1e-3)    # the form error this fit printed
    assert float(m.group(3)) == pytest.approx(e ** 2 / (2 * 0.05 * form_um * 1e-3), rel=2e-3)
    got = json.loads(cli("fit", method, tmp_path / "p.txt", "--json", "--no-residuals").stdout)
    assert any("off centre" in w for w in got["warnings"])


def test_fit_with_the_radius_or_of_a_centred_part_is_not_warned_about(tmp_path):
    instrument_file(tmp_path / "p.txt", 0.117)
    given = cli("fit", "circle.gauss_newton", tmp_path / "p.txt", "--nominal-radius", R)
    assert given.returncode == 0 and given.stderr == "", given.stderr
    instrument_file(tmp_path / "c.txt", 0.003)
    centred = cli("fit", "circle.gauss_newton", tmp_path / "c.txt")
    assert centred.returncode == 0 and "warning" not in centred.stderr, centred.stderr
