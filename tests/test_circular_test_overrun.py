"""A run recorded beyond 360 deg covers its first angles twice: which end is trimmed, and a run that goes round twice.

The runs are written here (R 100 mm, 1 deg steps, 10 µm/m X scale, 0.1 µm noise) with an acceleration transient
on the lead-in or lead-out arc; G of the steady revolution is computed independently (scipy least_squares circle,
radial span about its centre), as ISO 230-4 defines it."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest
from scipy.optimize import least_squares

from cli_calls import cli, one_error_line
from methods.circular_test.runs import trim

R = 100.0
N = 360            # samples per revolution (1 deg)
EXTRA = 45         # samples (deg) recorded beyond one revolution


def run(sign: int, seed: int, *, transient_at: str | None = "start", drift_mm: float = 0.0):
    """(all samples, the steady revolution's samples): 405 deg from 0 deg, the transient (6 µm radial, decaying over
    10 samples) on the first or last 45 samples; a drift moves X by ``drift_mm`` over the run."""
    rng = np.random.default_rng(seed)
    m = N + EXTRA
    k = np.arange(m)
    th = sign * np.radians(k * 360.0 / N)
    x, y = R * np.cos(th) * (1 + 10e-6), R * np.sin(th)
    tr = np.zeros(m)
    if transient_at == "start":
        tr = 6e-3 * np.exp(-k / 10.0)
    elif transient_at == "end":
        tr = 6e-3 * np.exp(-(m - 1 - k) / 10.0)
    x, y = x + tr * np.cos(th) + drift_mm * k / m, y + tr * np.sin(th)
    pts = np.c_[x, y] + rng.normal(0, 1e-4, (m, 2))
    steady = pts[EXTRA:] if transient_at == "start" else pts[:N]
    return pts, steady


def iso_G(pts) -> float:
    """G (mm): radial span about the least-squares circle, by scipy (independent of fitbench's fitters)."""
    def res(p):
        return np.hypot(pts[:, 0] - p[0], pts[:, 1] - p[1]) - p[2]
    p = least_squares(res, [0.0, 0.0, R], xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    r = np.hypot(pts[:, 0] - p[0], pts[:, 1] - p[1])
    return float(r.max() - r.min())


def write(path, pts):
    np.savetxt(path, pts, fmt="%.7f", delimiter=",", header="X [mm],Y [mm]", comments="")
    return path


def test_lead_in_transient_keeps_the_steady_last_revolution(tmp_path):
    """The first 45 deg carry a 6 µm transient: the last 360 deg are kept (G of the steady revolution, not 5+ µm),
    the warning says why and which option keeps the other end, the note names the trimmed end."""
    (cw, cw_ok), (ccw, ccw_ok) = run(-1, 1), run(1, 2)
    out = cli("circular-test", write(tmp_path / "cw.csv", cw), write(tmp_path / "ccw.csv", ccw),
              "--nominal-radius", R, "--nominal-center", 0, 0, "--json")
    assert out.returncode == 0, out.stderr
    j = json.loads(out.stdout)
    assert j["G_cw"] == pytest.approx(iso_G(cw_ok), abs=1e-6)
    assert j["G_ccw"] == pytest.approx(iso_G(ccw_ok), abs=1e-6)
    assert iso_G(cw[:N]) - iso_G(cw_ok) > 3e-3            # the first revolution is the transient's (> 3 µm more)
    warnings = [ln for ln in out.stderr.splitlines() if ln.startswith("fitbench: warning:")]
    assert len([w for w in warnings if "lead-in transient; the first 45 point(s) trimmed" in w]) == 2, out.stderr
    assert all("--lead-out 44.5" in w and "Traceback" not in w for w in warnings)
    assert any("CW run: recorded 404.0°" in n and "the first 45 point(s)" in n for n in j["notes"]), j["notes"]
    assert j["details"]["conditions"]["trimming"]["cw"]["overrun_at"] == "start"


def test_lead_out_transient_trims_the_end_and_says_so(tmp_path):
    (cw, cw_ok), (ccw, ccw_ok) = run(-1, 3, transient_at="end"), run(1, 4, transient_at="end")
    out = cli("circular-test", write(tmp_path / "cw.csv", cw), write(tmp_path / "ccw.csv", ccw),
              "--nominal-radius", R, "--nominal-center", 0, 0, "--json")
    assert out.returncode == 0, out.stderr
    j = json.loads(out.stdout)
    assert j["G_cw"] == pytest.approx(iso_G(cw_ok), abs=1e-6) and j["G_ccw"] == pytest.approx(iso_G(ccw_ok), abs=1e-6)
    assert "warning" not in out.stderr
    note = [n for n in j["notes"] if n.startswith("CW run: recorded")][0]
    assert "the last 45 point(s) (overrun beyond 360°) trimmed" in note and "lead-out transient" in note, note


def test_clean_overrun_is_trimmed_at_the_end_without_a_warning(tmp_path):
    (cw, _), (ccw, _) = run(-1, 5, transient_at=None), run(1, 6, transient_at=None)
    out = cli("circular-test", write(tmp_path / "cw.csv", cw), write(tmp_path / "ccw.csv", ccw),
              "--nominal-radius", R, "--nominal-center", 0, 0, "--json")
    assert out.returncode == 0 and "warning" not in out.stderr, out.stderr
    j = json.loads(out.stdout)
    assert j["G_cw"] == pytest.approx(iso_G(cw[:N]), abs=1e-6)
    assert any("the last 45 point(s) (overrun beyond 360°) trimmed" in n for n in j["notes"]), j["notes"]


def test_passes_differing_throughout_keep_the_first_revolution_and_say_what_to_give(tmp_path):
    """A drift (3 µm in X over the run) makes the passes differ everywhere: not a transient at one end, so the
    first revolution is kept as before, with a warning naming --lead-in / --lead-out."""
    (cw, _), (ccw, _) = run(-1, 7, transient_at=None, drift_mm=3e-3), run(1, 8, transient_at=None, drift_mm=3e-3)
    out = cli("circular-test", write(tmp_path / "cw.csv", cw), write(tmp_path / "ccw.csv", ccw),
              "--nominal-radius", R, "--nominal-center", 0, 0, "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["G_cw"] == pytest.approx(iso_G(cw[:N]), abs=1e-6)
    w = [ln for ln in out.stderr.splitlines() if "CW run: its first" in ln][0]
    assert "at both ends of the overlap" in w and "the last 45 point(s) trimmed as overrun" in w, w
    assert "--lead-in 44.5" in w and "--lead-out 44.5" in w, w


def test_the_named_option_keeps_the_other_end(tmp_path):
    """The warning's --lead-out keeps the first revolution although the passes differ: given leads are obeyed."""
    (cw, _), (ccw, _) = run(-1, 1), run(1, 2)
    files = (write(tmp_path / "cw.csv", cw), write(tmp_path / "ccw.csv", ccw), "--nominal-radius", R,
             "--nominal-center", 0, 0, "--json")
    told = re.search(r"CW run: .*\(--lead-out (\S+) keeps them\)", cli("circular-test", *files).stderr)
    assert told
    out = cli("circular-test", *files, "--lead-out", told[1])
    assert out.returncode == 0 and "warning" not in out.stderr, out.stderr
    assert json.loads(out.stdout)["G_cw"] == pytest.approx(iso_G(cw[:N]), abs=1e-6)


def test_trim_api_keeps_the_end_unless_asked():
    cw, cw_ok = run(-1, 1)
    kept, rep = trim(cw, (0.0, 0.0))
    assert len(kept) == N and rep["overrun_at"] == "end" and rep["passes"]["steady"] == "end"
    kept, rep = trim(cw, (0.0, 0.0), overrun="auto")
    assert np.array_equal(kept, cw_ok) and rep["overrun_at"] == "start"


def test_two_revolutions_are_two_tests_not_overrun(tmp_path):
    """Two complete tests one after the other: refused in one line, not 360 deg of 'overrun' dropped; the options it
    names give either test."""
    a, _ = run(-1, 9, transient_at=None)
    b, _ = run(-1, 10, transient_at=None)
    c, _ = run(1, 11, transient_at=None)
    d, _ = run(1, 12, transient_at=None)
    b[:, 0] += 4e-3 * np.cos(2 * np.arctan2(b[:, 1], b[:, 0]))
    cw = write(tmp_path / "cw.csv", np.vstack([a[:N], b[:N]]))   # a blank line between: the reader refuses
    ccw = write(tmp_path / "ccw.csv", np.vstack([c[:N], d[:N]]))
    out = cli("circular-test", cw, ccw, "--nominal-radius", R, "--nominal-center", 0, 0)
    assert out.returncode == 2 and out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "CW run: recorded 719.0°: it goes round twice (samples 1-360 and 361-720)" in lines[0]
    lead_out = re.search(r"--lead-out (\S+) keeps the first, --lead-in (\S+) the second", lines[0])
    assert lead_out, lines[0]
    first = cli("circular-test", cw, ccw, "--nominal-radius", R, "--nominal-center", 0, 0, "--lead-out",
                lead_out[1], "--json")
    second = cli("circular-test", cw, ccw, "--nominal-radius", R, "--nominal-center", 0, 0, "--lead-in", lead_out[2],
                 "--json")
    assert json.loads(first.stdout)["G_cw"] == pytest.approx(iso_G(a[:N]), abs=1e-6)
    assert json.loads(second.stdout)["G_cw"] == pytest.approx(iso_G(b[:N]), abs=1e-6)


def test_two_tests_in_one_ballbar_export(tmp_path):
    """The ballbar layout (direction, angle, deviation) with a second CW/CCW test after a blank line."""
    ang = np.arange(N) * 360.0 / N
    rows = []
    for test, lobes in ((1, 0.0), (2, 4.0)):
        for word, a in (("Clockwise", 360.0 - ang), ("Counter-clockwise", ang)):
            dev = 1.0 + lobes * np.cos(2 * np.radians(a)) + 0.3 * np.sin(np.radians(a) + test)
            rows += [f"{word}\t{x:.3f}\t{v:.4f}" for x, v in zip(a, dev)]
        rows.append("")
    p = tmp_path / "bb.txt"
    p.write_text("Direction\tAngle [deg]\tDeviation [µm]\n" + "\n".join(rows))
    out = cli("circular-test", p, "--nominal-radius", 150)
    assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1, out.stderr
    assert "goes round twice" in out.stderr and "a file of its own" in out.stderr
