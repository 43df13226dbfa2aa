"""ISO 230-2's test of linear axes over 2000 mm: one approach in each direction to targets about 250 mm apart.
Before: refused ("target 0 has 1 run(s) in the up direction; at least two are needed"). E, M, B_i, B and B mean
are defined by one run per direction; s, R, A and the model's uncertainty (paper eq. 10) need repeats."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line


def long_axis(path, seed=7):
    """A 4000 mm axis, 17 targets 250 mm apart, one run each way (µm), as a wide export."""
    rng = np.random.default_rng(seed)
    T = np.arange(0.0, 4001.0, 250.0)
    base = 20 * np.sin(np.pi * T / 4000) - 8 * T / 1000
    up, down = (np.round(base + s * 1.8 + rng.normal(0, 0.5, T.size), 3) for s in (1, -1))
    path.write_text("Target (mm);Run 1 + (µm);Run 1 - (µm)\n"
                    + "\n".join(f"{t:.1f};{u:.3f};{d:.3f}" for t, u, d in zip(T, up, down)) + "\n")
    return T, up, down


def test_one_run_per_direction_gives_e_m_b_and_says_what_it_cannot(tmp_path):
    T, up, down = long_axis(tmp_path / "long.csv")
    out = cli("positioning", tmp_path / "long.csv", "--json")
    assert out.returncode == 0, out.stderr
    j = json.loads(out.stdout)
    xm = (up + down) / 2
    expect = {"E_up": np.ptp(up), "E_down": np.ptp(down), "E": max(up.max(), down.max()) - min(up.min(), down.min()),
              "M": np.ptp(xm), "B": np.max(np.abs(up - down)), "B_mean": np.mean(up - down)}
    for key, value in expect.items():
        assert j[key] * 1e3 == pytest.approx(value, abs=1e-9), key
    assert not {"A", "R", "A_up", "R_up"} & set(j) and j["polynomial"] is None
    assert j["iso230_2_conformity"]["meets_minimum"] and any("one run per direction" in n for n in j["notes"])
    text = cli("positioning", tmp_path / "long.csv", "--plot", tmp_path / "l.png").stdout
    assert "17 targets x 1 run," in text and "A and R need the estimator s" in text
    assert (tmp_path / "l.png").stat().st_size > 5000


def test_its_table_comes_from_the_measured_deviations(tmp_path):
    long_axis(tmp_path / "long.csv")
    table = tmp_path / "l.mpf"
    out = cli("positioning", tmp_path / "long.csv", "--axis", "X1", "--compensation", "siemens-eec", table)
    one_error_line(out, "needs repeated runs", "--compensation-from mean")
    assert not table.exists()
    out = cli("positioning", tmp_path / "long.csv", "--axis", "X1", "--compensation", "siemens-eec", table,
              "--compensation-from", "mean")
    assert out.returncode == 0 and "$AA_ENC_COMP[0,16,X1]" in table.read_text()


def test_a_single_run_among_repeated_runs_is_still_refused(tmp_path):
    p = tmp_path / "mixed.csv"
    p.write_text("target,direction,run,deviation\n" + "".join(
        f"{t},{d},{r},0.001\n" for t in (0, 100, 200) for d in "+-" for r in ((1, 2) if t else (1,))))
    one_error_line(cli("positioning", p), "target 0 has 1 run(s)", "at least two")
