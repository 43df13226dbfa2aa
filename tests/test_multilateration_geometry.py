"""Degenerate station geometry is refused (InvalidInputError, CLI exit 2), and a solution
left undetermined by rounding is reported converged=False with the condition number, never 'converged'."""

import numpy as np
import pytest

import methods
from cli_calls import cli, one_error_line
from datasets.multilateration import simulate

ALL = ["case_a_distance", "case_a_squared", "joint", "case_b_linear", "case_b_taylor", "case_b_centred"]


def degenerate_campaign(shape):
    """Consistent lengths (no machine errors, no noise) from stations on one line or in one plane."""
    data, truth = simulate(stations=6, errors=None, noise=0.0)
    S = truth["stations"].copy()
    t = np.linspace(0, 1, 6)
    if shape == "line":
        S[:, :3] = np.outer(t, [1000.0, 200.0, 50.0]) + [-100.0, 0.0, -500.0]
    else:  # the plane z = -500, stations spread in x and y
        S[:, :3] = np.column_stack([800 * np.cos(2 * np.pi * t), 600 * np.sin(2 * np.pi * t), np.full(6, -500.0)])
    d = np.linalg.norm(data.points[:, None] - S[None, :, :3], axis=2)
    return type(data)(data.stations, data.points, d - S[:, 3]), S


@pytest.mark.parametrize("method", ALL)
def test_collinear_known_stations_are_refused(method):
    data, S = degenerate_campaign("line")
    with pytest.raises(methods.InvalidInputError, match="one straight line|one line"):
        methods.fit(f"multilateration.{method}", data.with_stations(S))


@pytest.mark.parametrize("method", ALL)
def test_collinear_located_stations_are_refused_or_not_converged(method):
    """Step 1 locates each station from the (3-D) nominal points; the located stations are collinear to
    rounding (refused) or, from the unscaled Case B, only close to it: then the point system's condition
    number (2e22 here before) exceeds 1e-2/eps and the result says it is not determined."""
    data, _ = degenerate_campaign("line")
    try:
        res = methods.fit(f"multilateration.{method}", data)
    except methods.InvalidInputError as exc:
        assert "line" in str(exc) or "singular" in str(exc) or "rank deficient" in str(exc)
        return
    assert not res.converged and "not determined" in res.message


@pytest.mark.parametrize("method", ["case_b_linear", "case_b_taylor", "case_b_centred"])
def test_coplanar_stations_are_refused_by_the_linear_case_b(method):
    data, S = degenerate_campaign("plane")
    with pytest.raises(methods.InvalidInputError, match="one plane"):
        methods.fit(f"multilateration.{method}", data.with_stations(S))


@pytest.mark.parametrize("method", ["case_a_distance", "joint"])
def test_coplanar_stations_still_locate_points_off_their_plane(method):
    """Stations in one plane determine every point off it (up to the mirror image, excluded by the start):
    not refused, and exact lengths give the exact points."""
    data, S = degenerate_campaign("plane")
    res = methods.fit(f"multilateration.{method}", data.with_stations(S))
    assert res.converged, res.message
    assert np.abs(res.volumetric_errors).max() < 1e-6


def test_general_position_is_unchanged():
    data, _ = simulate(stations=6)
    for method in ALL:
        res = methods.fit(f"multilateration.{method}", data)
        assert res.converged, (method, res.message)
        assert max(float(np.max(c["svd"])) for c in res.condition_numbers.values()) < 1e12


def test_cli_exit_2_for_collinear_stations(tmp_path):
    data, S = degenerate_campaign("line")
    meas, st = tmp_path / "m.csv", tmp_path / "s.csv"
    data.to_frame().to_csv(meas, index=False, float_format="%.9f")
    data.with_stations(S).stations_frame().to_csv(st, index=False, float_format="%.9f")
    one_error_line(cli("multilaterate", meas, "--stations", st), "straight line")


@pytest.mark.parametrize("max_iter", [100, 1])
def test_the_result_states_its_frame_converged_or_not(max_iter):
    """The joint scheme's located solution is defined up to a rigid motion and reported aligned to the nominal
    points, converged or not: ``frame == "nominal"`` says so (the study reads the field, never the message),
    and the alignment holds: the least-squares rigid motion from its points to the nominal ones is the identity."""
    from methods.multilateration.solvers import kabsch
    data, _ = simulate(stations=6)
    res = methods.fit("multilateration.joint", data, max_iter=max_iter)
    assert res.frame == "nominal" and res.converged == (max_iter == 100)
    R, t = kabsch(res.points, data.points)
    assert np.abs(R - np.eye(3)).max() < 1e-9 and np.abs(t).max() < 1e-6
    assert methods.fit("multilateration.case_a_distance", data).frame == "measurement"
