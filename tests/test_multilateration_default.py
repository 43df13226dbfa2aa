"""``fitbench multilaterate`` without ``--stations`` must not default to a scheme that the machine's own errors bias:
on exact lengths from a machine with errors, the default recovers the true volumetric errors (up to the rigid
motion self-located stations cannot observe); a two-step scheme chosen explicitly is warned about."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli
from datasets.multilateration import simulate
from methods.multilateration.solvers import kabsch


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """Exact lengths (noise 0) of the simulated MCV 754 with its errors (largest volumetric error 66 µm)."""
    folder = tmp_path_factory.mktemp("ml")
    data, truth = simulate(stations=6, grid=(3, 3, 3), noise=0.0)
    meas, st = folder / "meas.csv", folder / "stations.csv"
    data.to_frame().to_csv(meas, index=False, float_format="%.12f")
    data.with_stations(truth["stations"]).stations_frame().to_csv(st, index=False, float_format="%.12f")
    return meas, st, truth


def aligned_error_um(d, truth) -> float:
    """Largest distance (µm) between the actual points found and the true ones after the best rigid motion."""
    got = np.asarray(d["nominal_points"]) + np.asarray(d["volumetric_errors"])
    R, t = kabsch(got, truth["actual"])
    return float(np.max(np.linalg.norm(got @ R.T + t - truth["actual"], axis=1)) * 1e3)


def test_default_without_stations_is_unbiased_on_exact_lengths(campaign):
    meas, _, truth = campaign
    code, out, err = cli("multilaterate", meas, "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["method"] == "multilateration.joint" and not d["stations_given"]
    assert "rigid-body motion" in " ".join(d["notes"])
    assert aligned_error_um(d, truth) < 1e-3          # the two-step default was off by several µm here
    # the paper's two-step scheme on the same file: biased, and now said so
    code, out, err = cli("multilaterate", meas, "--method", "case_a_distance", "--json")
    assert aligned_error_um(json.loads(out), truth) > 1.0
    assert "warning: multilateration.case_a_distance locates the stations" in err and "--method joint" in err
    code, out, err = cli("multilaterate", meas)
    assert code == 0 and "method       multilateration.joint" in out and "note: stations located" in out
    assert "warning" not in err


def test_default_with_known_stations_is_case_a_and_exact(campaign):
    meas, st, truth = campaign
    code, out, err = cli("multilaterate", meas, "--stations", st, "--json")
    assert code == 0 and "warning" not in err, err
    d = json.loads(out)
    assert d["method"] == "multilateration.case_a_distance" and d["stations_given"]
    np.testing.assert_allclose(d["volumetric_errors"], truth["volumetric_errors"], atol=1e-6)
