"""What the positioning output says about its own numbers. Before: without --mpe / --instrument-u, U(P) was printed
(max U(P_i) = 0.653 µm for the example) with nothing but 'u(delta) = 0 µm' to say that it leaves the instrument's
error out (with --mpe 2um: 2.400 µm); and --standard vdi3441 printed ISO 230-2's R_i column (2s↑ + 2s↓ + |B_i|) under
the VDI/DGQ 3441 heading instead of VDI's per-position reversal span U_i and scatter Ps_i. The figures are recomputed
here from the file."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd

from cli_calls import cli

EXAMPLE = "docs/examples/positioning.csv"


def by_hand():
    d = pd.read_csv(EXAMPLE, sep=";")
    up, dn = d.iloc[:, 1::2].to_numpy(), d.iloc[:, 2::2].to_numpy()          # µm, runs in columns
    su, sd = up.std(1, ddof=1), dn.std(1, ddof=1)
    return np.abs(up.mean(1) - dn.mean(1)), 6 * np.sqrt((su ** 2 + sd ** 2) / 2)


def test_vdi3441_shows_its_own_per_position_figures():
    U_i, Ps_i = by_hand()
    out = cli("positioning", EXAMPLE, "--standard", "vdi3441")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.split()[:1] == ["target"])
    cols = lines[head].split()
    assert "R_i" not in cols and "B_i" not in cols and cols[-3:] == ["U_i", "Ps_i", "x̄_i"]
    rows = np.array([[float(v) for v in ln.split()] for ln in lines[head + 1:head + 12]])
    np.testing.assert_allclose(rows[:, -3], U_i, atol=5e-4)
    np.testing.assert_allclose(rows[:, -2], Ps_i, atol=5e-4)
    assert f"{Ps_i.max():.3f}" in out.stdout.split("per target")[0]          # Ps, the largest Ps_i
    per = json.loads(cli("positioning", EXAMPLE, "--standard", "vdi3441", "--json").stdout)["per_target"]
    assert "R_i" not in per and np.allclose(np.array(per["Ps_i"]) * 1e3, Ps_i, atol=1e-9)
    iso = cli("positioning", EXAMPLE).stdout                              # ISO 230-2 keeps B_i and R_i
    assert "     B_i      R_i" in iso and "U_i" not in iso


def test_u_of_p_without_the_instrument_error_says_so():
    bare = cli("positioning", EXAMPLE)
    assert bare.returncode == 0
    note = next(ln for ln in bare.stdout.splitlines() if ln.startswith("note: U(P) includes the scatter"))
    assert "not the instrument's error" in note and "--mpe" in note and "--instrument-u" in note
    assert "max U(P_i) = 0.653 µm (k = 2), without the instrument's error" in bare.stdout
    given = cli("positioning", EXAMPLE, "--mpe", "2um")
    assert "U(P) includes the scatter" not in given.stdout and "without the instrument's error" not in given.stdout
    # what the note says it would add: U(P)^2 + (2 u(delta))^2, u(delta) = MPE / sqrt(3), at every target
    j0 = json.loads(cli("positioning", EXAMPLE, "--json").stdout)
    j1 = json.loads(cli("positioning", EXAMPLE, "--mpe", "2um", "--json").stdout)
    for d in ("up", "down"):
        U0, U1 = (np.array(j["polynomial"][d]["U_at_targets"]) for j in (j0, j1))
        np.testing.assert_allclose(U1 ** 2 - U0 ** 2, (2 * 0.002 / np.sqrt(3)) ** 2, rtol=1e-9)
    assert any(n.startswith("U(P) includes the scatter") for n in j0["notes"])
