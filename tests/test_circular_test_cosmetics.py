"""What ``fitbench circular-test`` prints and draws (ISO 230-4): a servo mismatch's uncertainty in ms is never
printed as 0.000 (a 2 ms servo mismatch read '+2.000 +- 0.000 ms'), the polar plot's ring at the nominal radius reads '0 µm' (it read
'+0 µm'), and an angle + radial deviation file is told its plane by --plane (it was refused: "no column 'z'", and a
ZX test was printed with X-Y diagnostics)."""
import json
import re

import numpy as np
import pytest

from fitbench.cli.commands import main as cli_main

R = 50.0


def servo_runs(lag_s=0.002, feed=2000.0, seed=31):
    """A circle of radius R about (0, 0) whose X lags Y by ``lag_s`` at ``feed`` mm/min, 0.05 µm noise: CW, CCW."""
    rng = np.random.default_rng(seed)
    phi = (feed / 60.0) / R * lag_s
    out = []
    for s in (-1, 1):
        th = s * np.radians(np.arange(0, 360, 0.25) + 0.1)
        pts = np.column_stack([R * np.cos(th - s * phi), R * np.sin(th)])
        out.append(pts + rng.normal(0, 5e-5, pts.shape))
    return out


def write_xy(path, pts):
    np.savetxt(path, pts, delimiter=",", header="x,y", comments="", fmt="%.7f")
    return str(path)


def test_a_small_servo_mismatch_uncertainty_is_printed_to_its_first_significant_digit(tmp_path, capsys):
    cw, ccw = servo_runs()
    files = [write_xy(tmp_path / "cw.csv", cw), write_xy(tmp_path / "ccw.csv", ccw)]
    opts = ["--nominal-radius", str(R), "--nominal-center", "0", "0", "--feed", "2000"]
    assert cli_main(["circular-test", *files, *opts, "--json"]) == 0
    item = json.loads(capsys.readouterr().out)["diagnostics"]["servo_mismatch"]
    u_ms = item["u"] * 1e3
    assert 0 < u_ms < 0.0005                                      # what printed as 0.000 ms
    assert cli_main(["circular-test", *files, *opts]) == 0
    line = next(ln for ln in capsys.readouterr().out.splitlines() if "servo mismatch" in ln)
    m = re.search(r"([+-]\d+\.(\d+)) \+- (\d+\.(\d+)) ms", line)
    assert m, line
    digits = len(m.group(4))
    assert len(m.group(2)) == digits                             # the value to the uncertainty's decimal
    assert float(m.group(3)) > 0 and float(m.group(3)) == pytest.approx(u_ms, abs=0.5 * 10 ** -digits)
    assert float(m.group(1)) == pytest.approx(item["value"] * 1e3, abs=0.5 * 10 ** -digits)
    assert float(m.group(1)) == pytest.approx(2.0, abs=0.01)
    assert float(m.group(3)) >= 10 ** -digits                    # its first significant digit is printed


def test_the_nominal_circle_s_ring_reads_0_um():
    from fitbench.plots.circular_test import polar_plot
    from methods.circular_test import evaluate
    cw, ccw = servo_runs()
    ev = evaluate(cw, ccw, R, (0.0, 0.0))
    labels = []

    def keep(fig, path):
        labels.extend(t.get_text() for t in fig.axes[0].get_yticklabels())
    polar_plot(cw, ccw, ev, "unused.png", save=keep)
    assert "0 µm" in labels, labels
    assert not [t for t in labels if re.fullmatch(r"[+-]0(\.0*)? µm", t)], labels
    assert all(re.fullmatch(r"[+-]\d+(\.\d+)? µm", t) for t in labels if t != "0 µm"), labels


def write_polar(path, cw, ccw):
    """One file as a ballbar lists it: Direction; Angle (deg); Radial deviation (µm), about (0, 0) on R."""
    rows = []
    for name, pts in (("CW", cw), ("CCW", ccw)):
        ang = np.degrees(np.arctan2(pts[:, 1], pts[:, 0]))
        dev = (np.hypot(pts[:, 0], pts[:, 1]) - R) * 1e3
        rows += [f"{name};{a:.4f};{d:.4f}" for a, d in zip(ang, dev)]
    path.write_text("Direction;Angle (deg);Radial deviation (µm)\n" + "\n".join(rows) + "\n", encoding="utf-8")
    return str(path)


def test_an_angle_and_deviation_file_is_told_its_plane(tmp_path, capsys):
    cw, ccw = servo_runs()
    f = write_polar(tmp_path / "zx.csv", cw, ccw)
    opts = ["--nominal-radius", str(R), "--feed", "2000"]
    assert cli_main(["circular-test", f, *opts, "--json"]) == 0
    xy = json.loads(capsys.readouterr().out)
    assert cli_main(["circular-test", f, *opts, "--plane", "zx", "--json"]) == 0
    zx = json.loads(capsys.readouterr().out)
    assert zx["details"]["conditions"]["plane"] == "zx" and xy["details"]["conditions"]["plane"] == "xy"
    # the same numbers, the plane's axis names: Z is the first axis, X the second
    assert zx["diagnostics"]["servo_mismatch"]["value"] == pytest.approx(xy["diagnostics"]["servo_mismatch"]["value"])
    assert "Z lags behind X" in zx["diagnostics"]["servo_mismatch"]["sign"]
    assert cli_main(["circular-test", f, *opts, "--plane", "zx"]) == 0
    text = capsys.readouterr().out
    assert "servo mismatch Z-X" in text and "Z lags behind X" in text and "X-Y" not in text
    # fitbench fit reads such a profile with --plane too: its note and its coordinates name the plane's axes
    one = tmp_path / "one.csv"
    one.write_text("\n".join(ln.split(";", 1)[1] for ln in (tmp_path / "zx.csv").read_text().splitlines()
                             if not ln.startswith("CCW")) + "\n", encoding="utf-8")
    assert cli_main(["fit", "circle.gauss_newton", str(one), "--plane", "zx", "--nominal-radius", str(R)]) == 0
    out = capsys.readouterr().out
    assert "note: angle + radial deviation in the ZX plane (--plane zx): the angle turns from +Z towards +X" in out
    assert re.search(r"^center z ", out, re.M) and re.search(r"^center x ", out, re.M), out
