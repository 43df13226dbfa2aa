"""A clean backlash step sampled on a round angle grid: a sample exactly at the reversal angle (0 and 180 deg, as
exports resampled to a grid have) made the reversal-spike term fit that one sample as a spike of about the full
backlash (-2.9 u beyond 2 u, decay at its 0.1 deg bound) or end "NOT converged". The same machine sampled off
the reversal angles must give the same answer: backlash 3 um, no spike. The data follow the review's ballbar
recipe (R 100 mm, 0.2 deg steps, squareness 20 urad, scale X 15 um/m, backlash X 3 um as a step, 0.1 um noise)."""
from __future__ import annotations

import numpy as np
import pytest

from methods.circular_test import diagnose

R = 100.0


def runs(seed, offset_deg, step_deg=0.2):
    """(cw, ccw) points in mm; the X backlash a clean step at the X reversals, no spike."""
    rng = np.random.default_rng(seed)
    out = {}
    for d, sgn in (("ccw", 1), ("cw", -1)):
        th = sgn * np.radians(np.arange(0, 360, step_deg) + offset_deg)
        x, y = R * np.cos(th), R * np.sin(th)
        vx = -np.sin(th) if d == "ccw" else np.sin(th)
        bx = np.where(vx > 0, -1.5e-3, 1.5e-3)
        xm = x * (1 + 15e-6) + 20e-6 * y + bx
        dev = np.hypot(xm, y) - R + rng.normal(0, 1e-4, th.size)
        out[d] = np.c_[(R + dev) * np.cos(th), (R + dev) * np.sin(th)]
    return out["cw"], out["ccw"]


@pytest.mark.parametrize("seed", [1, 4])
@pytest.mark.parametrize("offset_deg", [0.0, 0.1])
def test_a_clean_backlash_step_gives_no_spike_on_either_grid(seed, offset_deg):
    got = diagnose(*runs(seed, offset_deg), R, (0.0, 0.0))
    assert got["_model"]["converged"], got["_model"]["message"]
    b, s = got["backlash_x"], got["reversal_spike_x"]
    assert abs(b["value"] - 3.0) < 0.1 and abs(b["value"] - 3.0) < 4 * b["u"] + 0.02
    assert abs(s["value"]) < 0.2 and abs(s["value"]) < 3 * s["u"], s
    assert got["_model"]["left_out_at_reversal"] == (6 if offset_deg == 0.0 else 0)  # 90, 180, 270 deg of each run
