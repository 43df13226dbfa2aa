"""Roundness of an uncentred part given as angle + radial deviation without --nominal-radius: the deviations are
evaluated alone (the limaçon approximation, ISO 12181-1), which drops the e²/(2R) term of an eccentricity e on a part
of radius R. A part 117 µm off the spindle axis had RONt 17-23 % too high, exit 0, no word; and with unequal angle
steps a false 'is the file in nm? (--unit nm)' hint, which would divide every figure by 1000. Checked here against
NumPy: the first harmonic of the deviations (e), the limaçon residuals (linear least squares on 1, cos, sin) and the
exact least-squares circle of the x, y profile. ``fitbench fit`` of the same file without --nominal-radius (whose
form error is wrong by up to e²/(2R) the same way) warns of it too: it said nothing."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from cli_calls import cli

R = 5.0            # mm
LOBES = ((3, 1.5e-3, 0.4), (2, 0.6e-3, 1.0), (15, 0.4e-3, 2.0))     # (UPR, amplitude mm, phase rad)


def instrument_file(path, eccentricity_mm, uniform=True, n=720, seed=7):
    """What a roundness instrument records of a part of radius R with LOBES, set up ``eccentricity_mm`` off the
    spindle axis: the radius from the axis at each spindle angle, minus R, in µm (``uniform``: equal angle steps;
    else the polar angles of points equally spaced on the part). Returns (angles rad, deviations mm)."""
    rng = np.random.default_rng(seed)
    phi = np.radians(-31.0)
    c = eccentricity_mm * np.array([np.cos(phi), np.sin(phi)])
    psi = np.linspace(0.0, 2 * np.pi, 100_001)[:-1]
    form = sum(a * np.cos(k * psi + p) for k, a, p in LOBES) + rng.normal(0, 2e-5, psi.size)
    x, y = c[0] + (R + form) * np.cos(psi), c[1] + (R + form) * np.sin(psi)
    ang, rad = np.arctan2(y, x) % (2 * np.pi), np.hypot(x, y)
    o = np.argsort(ang)
    ang, rad = ang[o], rad[o]
    th = np.arange(n) * 2 * np.pi / n if uniform else np.sort(ang[:: psi.size // n][:n])
    r = np.interp(th, ang, rad, period=2 * np.pi)
    path.write_text("Angle (deg)\tRadius deviation (um)\n" +
                    "".join(f"{np.degrees(a):.6f}\t{(ri - R) * 1e3:.5f}\n" for a, ri in zip(th, r)), encoding="utf-8")
    return th, np.round((r - R) * 1e3, 5) * 1e-3


def lsci_ront_exact(th, dev):
    """RONt (mm) about the least-squares circle of the x, y profile on the radius R (Gauss-Newton in NumPy)."""
    x, y = (R + dev) * np.cos(th), (R + dev) * np.sin(th)
    p = np.array([0.0, 0.0, R])
    for _ in range(50):
        d = np.hypot(x - p[0], y - p[1])
        J = np.column_stack([-(x - p[0]) / d, -(y - p[1]) / d, -np.ones_like(d)])
        p = p - np.linalg.lstsq(J, d - p[2], rcond=None)[0]
    return float(np.ptp(np.hypot(x - p[0], y - p[1]) - p[2]))


def limacon(th, dev):
    """(eccentricity mm, RONt mm about the limaçon LSCI): linear least squares of the deviations on 1, cos, sin."""
    A = np.column_stack([np.ones_like(th), np.cos(th), np.sin(th)])
    coef, *_ = np.linalg.lstsq(A, dev, rcond=None)
    return float(np.hypot(coef[1], coef[2])), float(np.ptp(dev - A @ coef))


@pytest.mark.parametrize("uniform", [True, False], ids=["equal-steps", "unequal-steps"])
def test_an_uncentred_part_without_its_radius_is_warned_about(tmp_path, uniform):
    th, dev = instrument_file(tmp_path / "p.txt", 0.117, uniform=uniform)
    e, ront_limacon = limacon(th, dev)
    exact = lsci_ront_exact(th, dev)
    out = cli("roundness", tmp_path / "p.txt", "--cutoff", "none", "--reference", "lsci", "--json")
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    ront = got["references"]["lsci"]["RONt"]
    # the evaluation is the limaçon's (NumPy's linear fit), and that is off the exact figure by less than e²/(2R)
    assert ront == pytest.approx(ront_limacon, abs=2e-6)
    assert 0.05 * exact < abs(ront - exact) <= e ** 2 / (2 * R)
    # the warning says so, with NumPy's eccentricity, and what to give; no unit hint (the deviations span 0.24 mm)
    assert "--unit nm" not in out.stderr and "implausible" not in out.stderr, out.stderr
    m = re.search(r"warning: the profile is (\S+) µm off centre.*for R below (\S+) mm; give --nominal-radius",
                  out.stderr)
    assert m and out.stderr.count("\n") == 1, out.stderr
    assert float(m.group(1)) == pytest.approx(e * 1e3, abs=0.1)
    assert float(m.group(2)) == pytest.approx(e ** 2 / (2 * 0.05 * ront), rel=1e-3)
    assert any("off centre" in w for w in got["warnings"])
    # with the radius the figures are the exact ones and nothing is warned
    given = cli("roundness", tmp_path / "p.txt", "--cutoff", "none", "--reference", "lsci", "--nominal-radius", R,
                "--json")
    assert given.returncode == 0 and given.stderr == "", given.stderr
    assert json.loads(given.stdout)["references"]["lsci"]["RONt"] == pytest.approx(exact, abs=2e-7)


def test_a_centred_part_is_not_warned_about(tmp_path):
    th, dev = instrument_file(tmp_path / "p.txt", 0.003)
    out = cli("roundness", tmp_path / "p.txt", "--cutoff", "none", "--reference", "lsci")
    assert out.returncode == 0 and "warning" not in out.stderr, out.stderr
    assert "off centre" not in out.stdout


def test_the_unit_hint_still_names_nm_for_nanometres(tmp_path):
    """The hint now measures the deviations' own span: the uncentred part's file in nm read as µm still gets it."""
    th, dev = instrument_file(tmp_path / "p.txt", 0.117, uniform=False)
    text = (tmp_path / "p.txt").read_text().splitlines()
    rows = [f"{a}\t{float(v) * 1e3:.2f}" for a, v in (l.split("\t") for l in text[1:])]
    (tmp_path / "nm.txt").write_text("Angle (deg)\tRadius deviation\n" + "\n".join(rows) + "\n", encoding="utf-8")
    out = cli("roundness", tmp_path / "nm.txt", "--cutoff", "none", "--reference", "lsci", "--unit", "um")
    assert out.returncode == 0 and "is the file in nm? (--unit nm)" in out.stderr, out.stderr


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
