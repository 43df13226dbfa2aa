"""x, y runs that start with a radial feed-in (the recording begins before the circle does): 20 samples from 98 to
100 mm at 0° before a 7 µm trace gave G 2003 µm, exit 0, and warnings that blamed the nominal centre and radius.
The run is refused naming the samples and the --lead-in that removes them; with it, G is the trace's (checked
against the radial span of the generating points about their least-squares centre, NumPy)."""
from __future__ import annotations

import json

import numpy as np

from methods.circular_test.runs import off_circle_ends
from cli_calls import cli, one_error_line

R = 100.0


def run(sign, seed, feed_in=20, feed_out=0):
    rng = np.random.default_rng(seed)
    t = sign * np.arange(720) * 2 * np.pi / 720
    r = R + 0.003 * np.cos(2 * t) + rng.normal(0, 2e-4, t.size)
    circle = np.c_[r * np.cos(t), r * np.sin(t)]
    approach = np.c_[98 + 2 * np.arange(feed_in) / 20, np.zeros(feed_in)]
    leave = np.c_[100 - 2 * np.arange(1, feed_out + 1) / 20, np.zeros(feed_out)]
    return circle, np.vstack([approach, circle, leave])


def write(path, pts):
    path.write_text("X [mm];Y [mm]\n" + "\n".join(f"{a:.7f};{b:.7f}" for a, b in pts) + "\n")
    return path


def g_um(pts):
    q = pts - pts.mean(axis=0)
    sol = np.linalg.lstsq(np.c_[2 * q, np.ones(len(q))], (q * q).sum(1), rcond=None)[0]
    return float(np.ptp(np.hypot(*(q - sol[:2]).T))) * 1e3


def test_a_radial_feed_in_is_refused_naming_the_samples_and_lead_in_removes_it(tmp_path):
    (cw, cw_file), (ccw, ccw_file) = run(-1, 1), run(1, 2)
    a, b = write(tmp_path / "cw.csv", cw_file), write(tmp_path / "ccw.csv", ccw_file)
    out = cli("circular-test", a, b, "--nominal-radius", R, "--nominal-center", 0, 0)
    one_error_line(out, "CW run: samples 1-20 at its start", "inside", "--lead-in 0.1")
    ok = cli("circular-test", a, b, "--nominal-radius", R, "--nominal-center", 0, 0, "--lead-in", 0.1, "--json")
    assert ok.returncode == 0, ok.stderr
    got = json.loads(ok.stdout)
    # --lead-in 0.1 also drops the circle's first sample at 0°: G of the other 719
    assert abs(got["G_cw"] * 1e3 - g_um(cw[1:])) < 0.05 and abs(got["G_ccw"] * 1e3 - g_um(ccw[1:])) < 0.05


def test_a_feed_out_is_named_and_a_clean_run_passes():
    _, pts = run(1, 3, feed_in=0, feed_out=15)
    msg = off_circle_ends(pts, (0.0, 0.0), "CCW")
    assert msg.startswith("CCW run: samples 721-735 at its end") and "--lead-out" in msg
    clean, _ = run(1, 3, feed_in=0)
    assert off_circle_ends(clean, (0.0, 0.0), "CCW") is None
