"""``fitbench magnify --delta`` below the largest contouring error is refused in the option's terms, with units: the
refusal echoed the method's bare data-unit numbers ('delta = 0.005 must be larger than the largest contouring error
(0.0056)', mm unsaid, for --delta 5um)."""
import numpy as np

from cli_calls import cli, one_error_line
from test_magnify_contouring_error import l_path_with_a_cut_corner, polyline_distance, write


def test_a_too_small_delta_is_refused_in_micrometres(tmp_path):
    ref, meas = l_path_with_a_cut_corner()
    r, m = write(tmp_path / "ref.csv", ref, "mm"), write(tmp_path / "meas.csv", meas, "mm")
    e_um = polyline_distance(np.loadtxt(m, delimiter=",", skiprows=1), np.loadtxt(r, delimiter=",", skiprows=1)).max() * 1e3
    for delta in ("5um", "0.005"):
        called = cli("magnify", r, m, "--eta", 500, "--delta", delta)
        one_error_line(called, f"--delta 5 µm must be larger than the largest contouring error ({e_um:.4g} µm)",
                       "choose a larger --delta")
        assert "0.005" not in called.stderr, called.stderr
    code, out, err = cli("magnify", r, m, "--eta", 500, "--delta", f"{2 * e_um:.3g}um")
    assert code == 0, err
