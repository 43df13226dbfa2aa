"""Multilateration (Holub et al., Machines 2022, 10, 833): every scheme against the simulator's truth, an
independent solver (scipy's trust-region-reflective least_squares), and the identification of the 21 errors."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import least_squares

import methods
from datasets.multilateration import TOOL_OFFSETS, mcv754_errors, simulate, write_example
from methods import InvalidInputError
from fitbench.cli.commands import main
from datasets.io import read_multilateration as read_csv
from methods.multilateration import from_frame
from methods.multilateration.kinematics import (ErrorModel, design_matrix, identify, parameter_names,
                                                volumetric_errors)
from methods.multilateration.solvers import cond_svd, cond_theorem1, kabsch

ALL = ["case_a_distance", "case_a_squared", "case_b_linear", "case_b_taylor", "case_b_centred", "joint"]
CASE_A = ["case_a_distance", "case_a_squared", "joint"]


def fit(name, data, **kw):
    return methods.fit(f"multilateration.{name}", data, **kw)


@pytest.mark.parametrize("stations", [4, 6])
@pytest.mark.parametrize("name", ALL)
def test_exact_lengths_perfect_machine_recover_stations_and_points(name, stations):
    data, truth = simulate(stations=stations, errors=None, noise=0.0)
    res = fit(name, data)
    assert res.converged
    assert np.abs(res.stations - truth["stations"]).max() < 1e-6
    assert np.abs(res.points - truth["actual"]).max() < 1e-6
    assert np.abs(res.volumetric_errors).max() < 1e-6


@pytest.mark.parametrize("name", ALL)
def test_exact_lengths_known_stations_recover_actual_points(name):
    data, truth = simulate(stations=6, noise=0.0)
    res = fit(name, data.with_stations(truth["stations"]))
    assert np.abs(res.points - truth["actual"]).max() < 1e-6
    assert np.abs(res.volumetric_errors - truth["volumetric_errors"]).max() < 1e-6
    assert np.abs(res.stations - truth["stations"]).max() == 0.0       # given stations are kept


@pytest.mark.parametrize("stations", [4, 6])
def test_joint_adjustment_recovers_machine_errors_up_to_a_rigid_motion(stations):
    data, truth = simulate(stations=stations, noise=0.0)
    res = fit("joint", data)
    assert res.converged
    R, t = kabsch(truth["actual"], data.points)                  # the truth in the reported gauge
    actual = truth["actual"] @ R.T + t
    st = truth["stations"][:, :3] @ R.T + t
    assert np.abs(res.points - actual).max() < 1e-6
    assert np.abs(res.stations[:, :3] - st).max() < 1e-6
    assert np.abs(res.stations[:, 3] - truth["stations"][:, 3]).max() < 1e-6
    # the paper's two-step scheme cannot: its stations absorb the machine's errors
    two_step = fit("case_a_distance", data)
    assert np.abs(two_step.stations - truth["stations"]).max() > 1e-3


def _predicted_covariance(stations, points, sigma):
    """Covariance of the unweighted least-squares point: (J^T J)^-1 J^T S J (J^T J)^-1."""
    d = points[:, None, :] - stations[None, :, :3]
    J = d / np.linalg.norm(d, axis=2)[..., None]
    Hinv = np.linalg.inv(np.einsum("nki,nkj->nij", J, J))
    middle = np.einsum("nki,nk,nkj->nij", J, sigma ** 2, J)
    return Hinv @ middle @ Hinv


def test_instrument_noise_known_stations_points_at_the_instruments_level():
    data, truth = simulate(stations=6, noise=1.0, rng=np.random.default_rng(7))
    res = fit("case_a_distance", data.with_stations(truth["stations"]))
    err = res.points - truth["actual"]
    C = _predicted_covariance(truth["stations"], truth["actual"], truth["sigma"])
    chi2 = np.einsum("ni,nij,nj->n", err, np.linalg.inv(C), err)
    assert 2.4 < chi2.mean() < 3.6                     # errors as predicted by the instrument's uncertainty
    rms = np.sqrt(np.mean(np.sum(err ** 2, axis=1)))
    assert 0.05e-3 < rms < 5e-3                        # micrometre level (not exact, not tens of um)


def test_case_a_distance_agrees_with_scipy_trust_region_reflective():
    data, truth = simulate(stations=6, noise=1.0, rng=np.random.default_rng(3))
    res = fit("case_a_distance", data)
    P = data.lengths
    for k in range(len(data.stations)):
        def r(th, k=k):
            return np.linalg.norm(data.points - th[:3], axis=1) - (th[3] + P[:, k])
        ref = least_squares(r, truth["stations"][k] + 0.5, method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15)
        assert np.abs(ref.x - res.stations[k]).max() < 1e-7
    for i in (0, 17, 101, 239):
        def rp(x, i=i):
            return np.linalg.norm(x - res.stations[:, :3], axis=1) - (res.stations[:, 3] + P[i])
        ref = least_squares(rp, data.points[i] + 0.3, method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15)
        assert np.abs(ref.x - res.points[i]).max() < 1e-7          # 0.1 nm; scipy stops on xtol first


def test_case_a_squared_minimises_eq_8():
    data, _ = simulate(stations=6, noise=1.0, rng=np.random.default_rng(4))
    res = fit("case_a_squared", data)
    P = data.lengths
    for k in range(len(data.stations)):
        def r(th, k=k):
            return np.sum((data.points - th[:3]) ** 2, axis=1) - (th[3] + P[:, k]) ** 2
        ref = least_squares(r, res.stations[k] + 0.2, method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15)
        assert np.abs(ref.x - res.stations[k]).max() < 1e-6


def test_case_b_solves_its_published_system_and_equals_the_centred_estimator():
    """Same estimator, two numerical routes: the unscaled normal equations (eq. 11) and QR of the centred,
    scaled design; they agree to what kappa ~ 1e8 leaves of double precision."""
    data, _ = simulate(stations=6, noise=1.0, rng=np.random.default_rng(5))
    b = fit("case_b_linear", data)
    c = fit("case_b_centred", data)
    assert np.abs(b.stations - c.stations).max() < 1e-5
    assert np.abs(b.points - c.points).max() < 1e-5
    # and the algebraic residual of eq. 9 is what lstsq minimises
    P = data.lengths[:, 0]
    M = np.column_stack([2 * data.points, 2 * P, -np.ones(len(P))])
    g = np.sum(data.points ** 2, axis=1) - P ** 2
    ref = np.linalg.lstsq(M, g, rcond=None)[0]
    assert np.abs(ref[:4] - b.stations[0]).max() < 1e-5


def test_taylor_correction_lowers_the_distance_residuals_of_case_b():
    data, _ = simulate(stations=4, noise=1.0, rng=np.random.default_rng(6))
    b, t = fit("case_b_linear", data), fit("case_b_taylor", data)
    assert np.nansum(t.residuals ** 2) < np.nansum(b.residuals ** 2)


def test_case_b_as_published_is_ill_conditioned_and_centring_fixes_it():
    data, _ = simulate(stations=6, noise=1.0, rng=np.random.default_rng(8))
    a, b, c = fit("case_a_distance", data), fit("case_b_linear", data), fit("case_b_centred", data)
    kb = np.min(b.condition_numbers["stations"]["svd"])
    assert kb > 1e7 and kb > 1e4 * np.max(a.condition_numbers["stations"]["svd"])
    assert np.min(b.condition_numbers["stations"]["theorem1"]) > 1e3        # the paper's "at least 10^3"
    assert np.max(c.condition_numbers["stations"]["svd"]) < 1e3
    assert np.max(c.condition_numbers["points"]["svd"]) < 1e3
    for res in (a, b, c):                                                    # Theorem 1 is a lower bound
        for cn in res.condition_numbers.values():
            assert np.all(cn["theorem1"] <= cn["svd"] * (1 + 1e-9))


def test_theorem1_is_a_lower_bound_of_the_condition_number():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((500, 5, 5)) * np.logspace(0, 6, 5)
    assert np.all(cond_theorem1(A) <= cond_svd(A) * (1 + 1e-12))
    assert cond_theorem1(np.diag([1e4, 1.0, 1.0]))[()] == pytest.approx(1e4)


def test_near_coplanar_stations_make_the_point_step_ill_posed():
    """LT1-LT4 of table 5 lie within 1.3 mm of a plane: the point systems' conditioning shows it."""
    data4, truth = simulate(stations=(1, 2, 3, 4), noise=0.0)
    good, _ = simulate(stations=4, noise=0.0)
    bad = fit("case_b_centred", data4.with_stations(truth["stations"]))
    ok = fit("case_b_centred", good.with_stations(simulate(stations=4)[1]["stations"]))
    assert np.median(bad.condition_numbers["points"]["svd"]) > 1e3 * np.median(ok.condition_numbers["points"]["svd"])


def test_missing_lengths_are_allowed():
    data, truth = simulate(stations=6, errors=None, noise=0.0)
    lengths = data.lengths.copy()
    rng = np.random.default_rng(1)
    drop = rng.random(lengths.shape) < 0.15
    drop[np.isfinite(lengths).sum(axis=1) - drop.sum(axis=1) < 4] = False
    lengths[drop] = np.nan
    gappy = type(data)(data.stations, data.points, lengths)
    errors = {}
    for name in ALL:
        res = fit(name, gappy)
        errors[name] = np.abs(res.points - truth["actual"]).max()
        assert np.isnan(res.residuals[drop]).all()
    # exact data: only rounding is left. Points seen by 4 stations make the published Case B point system
    # kappa ~ 1e9-1e12, and its rounding error reaches micrometres' thousandths; centred, it is gone.
    assert max(errors[n] for n in ALL if n != "case_b_linear") < 1e-7, errors
    assert errors["case_b_linear"] < 1e-4, errors


# ---------------------------------------------------------------- identification of the 21 errors

def test_identification_gives_back_the_21_errors_to_1e9_relative():
    _, truth = simulate(stations=6, noise=0.0)
    model = truth["model"]
    for rigid in (False, True):
        ident = identify(truth["axes"], truth["offsets"], truth["volumetric_errors"], degree=model.degree, rigid=rigid)
        ref = model.vector(rigid=rigid)
        assert np.max(np.abs(ident.vector - ref)) <= 1e-9 * np.max(np.abs(ref[:-6] if rigid else ref))
        for name in ("EXX", "EBY", "ECZ", "EYX"):       # per component function, relative to its own size
            coef, true = ident.model.coefficients[name], model.coefficients[name]
            assert np.max(np.abs(coef - true)) <= 1e-9 * np.max(np.abs(true))
        for name in ("C0Y", "B0Z", "A0Z"):
            assert ident.model.squareness[name] == pytest.approx(model.squareness[name], rel=1e-9)


def test_identification_absorbs_a_rigid_motion():
    _, truth = simulate(stations=6, noise=0.0)
    model = truth["model"]
    moved = ErrorModel(degree=model.degree, coefficients=model.coefficients, squareness=model.squareness,
                       rigid=np.array([0.01, -0.02, 0.005, 3e-5, -2e-5, 4e-5]))
    vol = volumetric_errors(moved, truth["axes"], truth["offsets"])
    ident = identify(truth["axes"], truth["offsets"], vol, degree=model.degree, rigid=True)
    assert np.max(np.abs(ident.vector - moved.vector(rigid=True))) < 1e-12


def test_identification_uncertainties_cover_the_truth():
    data, truth = simulate(stations=6, noise=1.0, rng=np.random.default_rng(11))
    res = fit("case_a_distance", data.with_stations(truth["stations"]))
    ident = identify(truth["axes"], truth["offsets"], res.volumetric_errors, degree=3, rigid=False)
    z = (ident.vector - truth["model"].vector()) / ident.std
    assert np.mean(np.abs(z) < 2) > 0.8 and np.max(np.abs(z)) < 6


def test_identification_without_tool_offsets_says_what_is_confounded():
    _, truth = simulate(stations=6, noise=0.0, offsets=((0.0, 0.0, 0.0),))
    with pytest.raises(InvalidInputError, match="not identifiable.*tool offsets"):
        identify(truth["axes"], truth["offsets"], truth["volumetric_errors"], degree=3)


def test_kinematic_chain_signs_follow_small_rotations():
    """EAX (roll of X) rotates everything the X carriage carries: a point at height z moves by -z * EAX in y
    and y * EAX in z (eq. 3-4)."""
    m = ErrorModel(degree=1, coefficients={"EAX": np.array([1e-5])})
    axes = np.array([[750.0, 200.0, -300.0]])
    d = volumetric_errors(m, axes, (0.0, 0.0, 0.0))[0]
    eps = 1e-5 * 1.0                                         # u = x / travel = 1
    assert d == pytest.approx([0.0, 300.0 * eps, 200.0 * eps])
    G = design_matrix(axes, TOOL_OFFSETS[1], 3)
    assert G.shape == (3, len(parameter_names(3)))
    assert len(parameter_names(3)) == 9 + 12 + 27 + 3       # 18 functions + 3 squareness


# ---------------------------------------------------------------- input, CLI

def test_csv_round_trip_and_order_of_first_appearance(tmp_path):
    meas, st = write_example(tmp_path, stations=4, noise=1.0)
    data = read_csv(meas, st)
    sim, truth = simulate(stations=4, noise=1.0, rng=np.random.default_rng(0))
    assert data.stations == sim.stations
    assert np.allclose(data.points, sim.points) and np.allclose(data.lengths, sim.lengths, atol=1e-9)
    assert np.allclose(data.known_stations, truth["stations"])
    df = pd.read_csv(meas).sample(frac=1.0, random_state=1)          # shuffled rows: first appearance decides
    shuffled = from_frame(df)
    first = df.drop_duplicates(["x", "y", "z"])[["x", "y", "z"]].to_numpy()
    assert np.allclose(shuffled.points, first)


def test_cli_json_keys(tmp_path, capsys):
    meas, st = write_example(tmp_path, stations=6, noise=0.0)
    assert main(["multilaterate", str(meas), "--method", "multilateration.case_a_distance", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    _, truth = simulate(stations=6, noise=0.0)
    assert np.shape(out["stations"]) == (6, 4)
    assert np.shape(out["points"]) == (240, 3) and np.shape(out["volumetric_errors"]) == (240, 3)
    assert set(out["condition_numbers"]) == {"stations", "points"}
    assert main(["multilaterate", str(meas), "--method", "joint", "--stations", str(st), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert np.abs(np.array(out["volumetric_errors"]) - truth["volumetric_errors"]).max() < 1e-6
    assert main(["multilaterate", str(meas), "--method", "case_b_taylor"]) == 0
    text = capsys.readouterr().out
    assert "Theorem 1" in text and "LT6" in text


@pytest.mark.parametrize("content,stations,match", [
    ("station,x,y,length\nA,0,0,1\n", None, "missing column"),
    ("station,x,y,z,length\nA,0,0,0,nan\n", None, "finite"),
    ("station,x,y,z,length\nA,0,0,0,1\nA,0,0,0,2\n", None, "twice"),
    ("station,x,y,z,length\n" + "".join(f"A,{i},{i * i},{i ** 3 % 7},{i}\n" for i in range(4)), None, "at least 5"),
    ("station,x,y,z,length\n" + "".join(f"A,{i},{2 * i},0,{i}\n" for i in range(6)), None, "coplanar"),
    ("station,x,y,z,length\nA,0,0,0,1\nB,0,0,0,1\nC,0,0,0,1\nA,1,0,0,1\n", "station,x,y,z,L\nA,0,0,0,0\nB,1,0,0,0\nC,0,1,0,0\n",
     "at least 3 stations"),
    ("station,x,y,z,length\nA,0,0,0,1\n", "station,x,y,z,L\nB,0,0,0,0\n", "no position for station"),
])
def test_bad_input_one_line_exit_2(tmp_path, capsys, content, stations, match):
    f = tmp_path / "m.csv"
    f.write_text(content)
    args = ["multilaterate", str(f)]
    if stations:
        s = tmp_path / "s.csv"
        s.write_text(stations)
        args += ["--stations", str(s)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and match in err and "Traceback" not in err


def test_unknown_and_foreign_method_ids(tmp_path, capsys):
    meas, _ = write_example(tmp_path)
    assert main(["multilaterate", str(meas), "--method", "case_c"]) == 2
    assert "unknown method" in capsys.readouterr().err
    assert main(["multilaterate", str(meas), "--method", "circle.kasa"]) == 2
    assert "not a multilateration method" in capsys.readouterr().err


def test_collinear_stations_are_rejected_by_the_joint_adjustment():
    data, truth = simulate(stations=6, errors=None, noise=0.0)
    S = truth["stations"].copy()
    S[:, :3] = np.outer(np.linspace(0, 1, 6), [1000.0, 200.0, 50.0]) + [-100.0, 0.0, -500.0]
    d = np.linalg.norm(data.points[:, None] - S[None, :, :3], axis=2)
    flat = type(data)(data.stations, data.points, d - S[:, 3])
    with pytest.raises(InvalidInputError, match="one line|degenerate|singular|determined"):
        fit("joint", flat)


def test_dataframe_input_and_parameters():
    data, _ = simulate(stations=4, noise=0.0)
    res = methods.fit("multilateration.case_a_distance", data.to_frame(), max_iter=50)
    assert res.params == {"max_iter": 50} and res.converged
    with pytest.raises(InvalidInputError, match="no parameter"):
        methods.fit("multilateration.case_b_linear", data, max_iter=3)
    assert mcv754_errors().degree == 3


# ---------------------------------------------------------------- the study

@pytest.fixture(scope="module")
def study(tmp_path_factory):
    from conftest import quick_study
    target = quick_study(tmp_path_factory, "multilateration")
    from experiments.jsontext import json_value
    return target, pd.read_csv(target / "results.csv"), json_value((target / "meta.json").read_text())


def test_study_rows_and_findings(study):
    target, rows, meta = study
    assert set(rows["status"]) == {"ok"} and rows["converged"].all()
    f = meta["findings"]
    acc = pd.DataFrame(f["accuracy"])
    exact = acc[acc["dataset"].str.contains("exact lengths")]
    # exact lengths: given stations -> every scheme exact; located -> only the joint adjustment is
    assert (exact[exact["stations"] == "known"]["volumetric_error_max_um"] < 1e-3).all()
    located = exact[exact["stations"] == "located"].set_index("method")
    assert located.loc["joint", "aligned_error_rms_um"] < 1e-3
    assert (located.drop(index="joint")["aligned_error_rms_um"] > 1.0).all()
    # the condition numbers the paper reports: Case B as published >> Case A; centring brings it down
    six = acc[acc["dataset"].str.startswith("6 stations (table 5)") & ~acc["dataset"].str.contains("exact")
              & (acc["stations"] == "located")].groupby("method").median(numeric_only=True)
    assert six.loc["case_b_linear", "kappa_stations"] > 1e4 * six.loc["case_a_distance", "kappa_stations"]
    assert six.loc["case_b_centred", "kappa_stations"] < 1e3
    assert six.loc["case_b_linear", "kappa_stations_theorem1"] > 1e3
    # the stations table (the paper's tables 5-9): six schemes x six stations, read from the rows
    report = json.loads((target / "report.json").read_text())
    stations = pd.read_csv(target / report["tables"][0]["file"])
    assert len(stations) == 6 * 6 and set(stations["method"]) >= {"joint", "case_b_linear"}
    for fig in report["figures"]:
        assert (target / fig["file"]).stat().st_size > 10_000
    assert {w["best"] for w in f["winners"] if "machine errors" in w["scenario"] and w["stations"] == "located"} == {"joint"}


def test_cli_identify_gives_back_the_21_errors(tmp_path, capsys):
    meas, st = write_example(tmp_path, stations=6, noise=0.0)
    assert main(["multilaterate", str(meas), "--stations", str(st), "--identify", "--json", "--no-residuals"]) == 0
    out = json.loads(capsys.readouterr().out)
    ge = out["geometric_errors"]
    got = {p["parameter"]: p["value"] for p in ge["parameters"]}
    model = mcv754_errors()
    travel = ge["travel"]                                  # from the data: the largest |axis position| per axis
    assert travel == [750.0, 500.0, 550.0]
    assert got["EXX^1"] == pytest.approx(model.coefficients["EXX"][0], rel=1e-6)
    assert got["EBY^2"] == pytest.approx(model.coefficients["EBY"][1], rel=1e-6)
    assert got["C0Y"] == pytest.approx(model.squareness["C0Y"], rel=1e-6)
    assert abs(got["TX"]) < 1e-8 and abs(got["RZ"]) < 1e-10          # the CSV holds 9 decimals
    assert main(["multilaterate", str(meas), "--stations", str(st), "--identify"]) == 0
    text = capsys.readouterr().out
    assert "C0Y" in text and "µrad" in text and "RZ" in text


def test_cli_identify_needs_tool_offsets(tmp_path, capsys):
    meas, _ = write_example(tmp_path)
    df = pd.read_csv(meas)
    df.drop(columns=["xp", "yp", "zp"]).to_csv(tmp_path / "bare.csv", index=False)
    assert main(["multilaterate", str(tmp_path / "bare.csv"), "--identify"]) == 2
    assert "xp, yp, zp" in capsys.readouterr().err
    df.drop(columns=["zp"]).to_csv(tmp_path / "partial.csv", index=False)
    assert main(["multilaterate", str(tmp_path / "partial.csv")]) == 2
    assert "all of xp, yp, zp or none" in capsys.readouterr().err
    clash = df.copy()
    clash.loc[7, "xp"] = 5.0                                # the same nominal point with another offset
    clash.to_csv(tmp_path / "clash.csv", index=False)
    assert main(["multilaterate", str(tmp_path / "clash.csv")]) == 2
    assert "two different tool offsets" in capsys.readouterr().err


# ---------------------------------------------------------------- the most accurate scheme: ties named

def _acc(values: dict, scenario="s", stations="known"):
    return pd.DataFrame([{"dataset": scenario, "stations": stations, "method": m, "aligned_error_rms_um": v}
                         for m, v in values.items()])


def _tol():
    from experiments.studies.multilateration import MultilaterationStudy
    return MultilaterationStudy.tolerances["aligned_error_rms_um"]


def test_winner_names_ties_whatever_the_row_order():
    """Medians identical to 9 digits (known stations: case_a_distance = joint, case_b_taylor 1e-7 above) are a
    tie, named by name; the row order decides nothing (it used to decide the 'winner')."""
    from experiments.studies.multilateration import winner
    vals = {"joint": 0.619022342, "case_a_squared": 0.807911323, "case_a_distance": 0.619022342,
            "case_b_taylor": 0.619022445, "case_b_linear": 1.09522023}
    outs = [winner(_acc(dict(order)), _tol()) for order in (vals.items(), reversed(vals.items()),
                                                            sorted(vals.items()))]
    for w in outs:
        pd.testing.assert_frame_equal(w, outs[0])
    w = outs[0].iloc[0]
    assert w["best"] == "case_a_distance, case_b_taylor, joint" and w["tied"] == 3
    assert w["runner_up"] == "case_a_squared" and w["best_rms_um"] == pytest.approx(0.619022342)


def test_winner_exact_lengths_are_a_tie_of_all():
    """On exact lengths every scheme is within rounding (1e-10 µm) of the truth: no scheme 'wins' by its last bits."""
    from experiments.studies.multilateration import winner, winner_text
    acc = _acc({"case_a_distance": 2.37842244e-10, "joint": 2.37842244e-10, "case_b_taylor": 2.27376024e-10,
                "case_b_linear": 3.42744944e-09})
    w = winner(acc, _tol())
    assert w.loc[0, "tied"] == 4 and w.loc[0, "runner_up"] == "" and np.isnan(w.loc[0, "runner_up_rms_um"])
    assert winner_text(w, 4) == "all 4 tied in 1"


def test_winner_claim_holds_for_every_machine_verify_calls_agreeing():
    """Move every median anywhere within verify's declared tolerance (atol + rtol |x|; the extremes included): the
    scheme most accurate there is always one of those named here, and a lone winner stays the lone winner."""
    from experiments.studies.multilateration import winner
    tol = _tol()
    vals = {"case_a_distance": 0.612594162, "case_a_squared": 0.795896556, "case_b_taylor": 0.617371871,
            "joint": 0.631038825, "case_b_linear": 1.09012674, "case_b_centred": 1.09012674}
    acc = _acc(vals)
    named = set(winner(acc, tol).loc[0, "best"].split(", "))
    lone = winner(_acc({"joint": 0.637595371, "case_a_distance": 14.179279, "case_b_taylor": 18.351342}), tol)
    assert lone.loc[0, "best"] == "joint"
    rng = np.random.default_rng(0)
    x = acc["aligned_error_rms_um"].to_numpy()
    band = tol.atol + tol.rtol * x
    for s in [*rng.uniform(-1, 1, (500, len(x))), *rng.choice([-1.0, 1.0], (500, len(x)))]:
        moved = acc.assign(aligned_error_rms_um=x + s * band)
        assert moved.loc[moved["aligned_error_rms_um"].idxmin(), "method"] in named
        y = lone.loc[0, "best_rms_um"]
        other = _acc({"joint": y + s[0] * (tol.atol + tol.rtol * y), "case_a_distance": 14.179279 * (1 - tol.rtol) - tol.atol})
        assert winner(other, tol).loc[0, "best"] == "joint"


def test_winner_text_counts_tie_sets():
    from experiments.studies.multilateration import winner, winner_text
    acc = pd.concat([_acc({"a": 1.0, "b": 1.0, "c": 2.0}, scenario="s1"), _acc({"a": 1.0, "b": 5.0, "c": 2.0}, scenario="s2"),
                     _acc({"a": 3.0, "b": 5.0, "c": 1.0}, scenario="s3"), _acc({"a": 1e-10, "b": 2e-10, "c": 3e-10}, scenario="s4")])
    text = winner_text(winner(acc, _tol()), 3)
    assert text == "a alone in 1, a = b (tied) in 1, all 3 tied in 1, c alone in 1"
    assert "; " not in text and ". " not in text          # the abstract keeps a finding up to its first '; ' or '. '
