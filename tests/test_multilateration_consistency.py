"""multilaterate with given stations that disagree with the lengths: the residual RMS (6 µm for a dead path 0.02 mm
off, 32 mm for every L + 50 mm, 212 mm for a stations file in m) was printed beside "converged yes", exit 0, with
volumetric errors off by 21 µm to 164 mm and no uncertainty on any point. Now the residuals are tested against the
lengths' standard uncertainty (a warning naming the station, or a refusal beyond a gross bound) and each point's
standard uncertainty is given; the latter is checked against the known truth of the simulated machine."""
from __future__ import annotations

import json

import numpy as np

from cli_calls import cli, one_error_line

S = np.array([[-200, -300, 200.], [800, -250, 150], [850, 650, -600], [-250, 700, -500], [300, 200, 300]])
L = np.array([150., 160, 170, 180, 190])


def write(tmp_path, noise_mm=2e-4, seed=11):
    """The review's LaserTRACER-like set: 36 points, 5 stations, the machine's errors up to 12 µm."""
    rng = np.random.default_rng(seed)
    g = np.array(np.meshgrid(np.linspace(0, 600, 4), np.linspace(0, 400, 3), np.linspace(-400, 0, 3),
                             indexing="ij")).reshape(3, -1).T
    x, y, z = g.T
    act = g + np.c_[12e-6 * x + 3e-6 * y, 20e-6 * x - 1e-8 * x ** 2, 5e-6 * z + 1e-8 * y * x / 10]
    rows = [f"LT{k + 1},{p[0]:.4f},{p[1]:.4f},{p[2]:.4f},{d:.7f}" for k, s in enumerate(S)
            for p, d in zip(g, np.linalg.norm(act - s, axis=1) - L[k] + rng.normal(0, noise_mm, len(g)))]
    (tmp_path / "ml.csv").write_text("station,x [mm],y [mm],z [mm],length [mm]\n" + "\n".join(rows) + "\n")

    def stations(name, s=S, dl=np.zeros(5), f=1.0):
        (tmp_path / name).write_text("station,x,y,z,L\n" + "\n".join(
            f"LT{k + 1},{a * f},{b * f},{c * f},{(L[k] + dl[k]) * f}" for k, (a, b, c) in enumerate(s)) + "\n")
        return tmp_path / name
    return tmp_path / "ml.csv", act, stations


def test_consistent_stations_give_point_uncertainties_that_cover_the_truth(tmp_path):
    ml, act, stations = write(tmp_path)
    out = cli("multilaterate", ml, "--stations", stations("st.csv"), "--json")
    assert out.returncode == 0 and "warning" not in out.stderr, out.stderr
    d = json.loads(out.stdout)
    assert d["length_check"]["consistent"] and d["length_check"]["ratio"] < 1
    u = np.asarray(d["point_uncertainty"])
    z = (np.asarray(d["points"]) - act) / u                     # against the simulated truth
    assert u.shape == (36, 3) and 0.5 < np.sqrt(np.mean(z ** 2)) < 1.6
    text = cli("multilaterate", ml, "--stations", stations("st.csv")).stdout
    assert "consistent" in text and "standard uncertainty from the residuals" in text


def test_a_wrong_dead_path_is_warned_about_naming_its_station(tmp_path):
    ml, _, stations = write(tmp_path)
    out = cli("multilaterate", ml, "--stations", stations("st_off2.csv", dl=np.r_[0.02, 0, 0, 0, 0]), "--json")
    assert out.returncode == 0
    d = json.loads(out.stdout)
    assert not d["length_check"]["consistent"] and d["length_check"]["worst_station"] == "LT1"
    assert "warning: the length residuals" in out.stderr and "station LT1" in out.stderr
    u = np.linalg.norm(np.asarray(d["point_uncertainty"]), axis=1)
    assert np.median(u) > 10 * 0.3e-3                             # the points are as uncertain as the lengths disagree
    text = cli("multilaterate", ml, "--stations", stations("st_off2.csv", dl=np.r_[0.02, 0, 0, 0, 0])).stdout
    assert "INCONSISTENT" in text


def test_grossly_wrong_stations_are_refused(tmp_path):
    ml, _, stations = write(tmp_path)
    for name, kw in (("st_off.csv", dict(dl=np.full(5, 50.0))), ("st_m.csv", dict(f=1e-3))):
        one_error_line(cli("multilaterate", ml, "--stations", stations(name, **kw)), "do not fit the given stations")
