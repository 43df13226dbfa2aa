"""``--columns x z`` puts X right and Z up: the ZX plane seen from -Y, where a G02 (clockwise seen from +Y, the
ISO 6983-1 convention for G18) turns counter-clockwise. The runs were called the wrong way round, a warning blamed
the user's file order, and the diagnostics named Z "Y". The pair is now read in the plane's own order."""
from __future__ import annotations

import json

import numpy as np

from cli_calls import cli

R, ZC, XC = 150.0, 500.0, -300.0


def g18_file(path, clockwise, lobes_um, seed):
    """A G18 circle about (Z 500, X -300) in the ZX plane: clockwise seen from +Y is Z right, X up, angle decreasing;
    a 3-lobe error of ``lobes_um`` tells the runs apart; Y stays 0."""
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False) * (-1 if clockwise else 1)
    r = R + 1e-3 * lobes_um * np.cos(3 * t) + np.random.default_rng(seed).normal(0, 1e-5, t.size)
    z, x = ZC + r * np.cos(t), XC + r * np.sin(t)
    path.write_text("X [mm],Y [mm],Z [mm]\n" + "\n".join(f"{a:.6f},0.000000,{c:.6f}" for a, c in zip(x, z)) + "\n")
    return path


def test_columns_x_z_follows_the_planes_orientation(tmp_path):
    g02, g03 = g18_file(tmp_path / "g02.csv", True, 2.0, 1), g18_file(tmp_path / "g03.csv", False, 5.0, 2)
    plane = cli("circular-test", g02, g03, "--plane", "zx", "--nominal-radius", R, "--nominal-center", ZC, XC, "--json")
    mirrored = cli("circular-test", g02, g03, "--columns", "x", "z", "--nominal-radius", R, "--nominal-center", XC, ZC,
                   "--json")
    assert plane.returncode == 0 and mirrored.returncode == 0, (plane.stderr, mirrored.stderr)
    assert "wrong order" not in mirrored.stderr and "wrong order" not in plane.stderr
    a, b = json.loads(plane.stdout), json.loads(mirrored.stdout)
    # G02 is the CW run: its 2 um lobes give G about 4 um, the G03 run's 5 um lobes about 10 um
    assert 3.5 < a["G_cw"] * 1e3 < 4.5 and 9.5 < a["G_ccw"] * 1e3 < 10.5
    for k in ("G_cw", "G_ccw", "G_b", "H"):
        assert b[k] == a[k], k
    assert b["details"]["conditions"]["plane"] == "zx"
    assert np.allclose(b["center"], [ZC, XC], atol=1e-3)       # in the plane's order (z, x), as the note says
    assert any("views the ZX plane from -Y" in n for n in b["notes"])
    assert b["diagnostics"] == a["diagnostics"]               # labelled Z and X, not X and "Y"
    text = cli("circular-test", g02, g03, "--columns", "x", "z", "--nominal-radius", R, "--nominal-center", XC, ZC)
    assert "scale mismatch Z-X" in text.stdout and "X-Y" not in text.stdout
