"""circular-test: a diagnostic that prints as 0.000 in its unit (or whose contribution to the circle prints as
0.00 µm) gets no sign meaning ('Z lags behind X', 'lost motion', 'inward spike' were printed for nm-level rounding
noise on a clean ellipse): the text says 'none at this resolution', and never '-0.000'."""
from __future__ import annotations

import re

import numpy as np

from cli_calls import cli
from fitbench.plots.circular_test import SHORT, meaning

WORDS = {w for pair in SHORT.values() for w in pair}


def clean_runs(tmp_path):
    """A pure 2-UPR ellipse (X travels 66.7 µm/m further than Y) in CW and CCW, coordinates rounded to 1 nm."""
    t = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    paths = []
    for name, sign in (("cw.csv", -1), ("ccw.csv", 1)):
        a = sign * t
        xy = np.column_stack([150.005 * np.cos(a), 149.995 * np.sin(a)])
        np.savetxt(tmp_path / name, np.round(xy, 6), delimiter=",", header="x,y", comments="", fmt="%.6f")
        paths.append(tmp_path / name)
    return paths


def test_no_sign_meaning_below_the_printed_resolution(tmp_path):
    out = cli("circular-test", *clean_runs(tmp_path), "--nominal-radius", 150, "--nominal-center", 0, 0)
    assert out.returncode == 0, out.stderr
    rows = re.findall(r"^  (\S.{21})\s+([+-]\d+\.\d{3}) \+- (\d+\.\d{3}) \S+\s+contribution\s+(\d+\.\d{2}) µm\s*(.*)$",
                      out.stdout, re.M)
    assert len(rows) >= 6, out.stdout
    zero = [r for r in rows if float(r[1]) == 0 or float(r[3]) == 0]
    assert len(zero) >= 5                                     # servo, backlash, spikes, squareness: rounding noise
    for label, value, u, contrib, words in zero:
        assert words == "none at this resolution", (label, value, contrib, words)
        assert value != "-0.000"
    scale = [r for r in rows if r[0].startswith("scale mismatch")][0]
    assert float(scale[1]) > 60 and scale[4] == "X travels further"     # a real finding keeps its meaning
    assert not (WORDS & {r[4] for r in zero})


def test_meaning_rule():
    assert meaning("servo_mismatch", 0.0004, 1e-6) == "none at this resolution"        # prints as +0.000
    assert meaning("reversal_spike_x", -0.001, 1e-5, contribution=0.001) == "none at this resolution"
    assert meaning("reversal_spike_x", -0.5, 0.01, contribution=0.5) == "inward spike"
    assert meaning("backlash_x", 0.1, 0.1, contribution=0.1) == ""                    # within 2 u
