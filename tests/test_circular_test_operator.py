"""What an operator reads from ``fitbench circular-test``: repeated samples (a dwell, a logger writing each sample
twice) are reported and dropped, never counted as independent points."""
import json

import numpy as np
import pytest

from datasets.circular_test import MachineErrors, TestConditions, circular_test
from fitbench.cli.commands import main as cli_main
from methods import InvalidInputError
from methods.circular_test import diagnose, evaluate
from methods.circular_test.runs import REPEAT_FRACTION, drop_repeated

COND = TestConditions(nominal_radius=150.0, nominal_center=(300.0, 200.0), feed_mm_min=2000.0, sampling_hz=20.0,
                      start_angle_deg=17.0)
ERR = MachineErrors(squareness=40e-6, scale_x=20e-6, backlash_y=0.003, noise=0.0005)


@pytest.fixture(scope="module")
def runs():
    cw, ccw, _ = circular_test(COND, ERR, seed=11)
    return cw, ccw


def write(path, pts):
    np.savetxt(path, pts, delimiter=",", header="x,y", comments="", fmt="%.9f")
    return str(path)


def cli_json(capsys, cw_path, ccw_path):
    code = cli_main(["circular-test", cw_path, ccw_path, "--nominal-radius", "150", "--nominal-center", "300", "200",
                     "--feed", "2000", "--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    return json.loads(out.out), out.err


def test_the_api_refuses_repeated_samples(runs):
    """Each sample twice divided every diagnostic u by sqrt 2 (sigma^2 = RSS / (N - rank) with N counting the
    copies), and a dwell pulled the least-squares centres: the API refuses such runs, naming where."""
    cw, ccw = runs
    twice = np.repeat(cw, 2, axis=0)
    with pytest.raises(InvalidInputError, match=r"CW run: %d sample\(s\) repeat the one before them \(samples 1-2, "
                                                r"3-4, 5-6 and %d more groups" % (len(cw), len(cw) - 3)):
        diagnose(twice, ccw, 150.0, (300.0, 200.0))
    dwell = np.vstack([np.repeat(ccw[:1], 40, axis=0), ccw])
    with pytest.raises(InvalidInputError, match=r"CCW run: 40 sample\(s\) repeat the one before them \(samples 1-41 "
                                                r"are one position"):
        evaluate(cw, dwell, 150.0, (300.0, 200.0))


def test_drop_repeated_finds_a_noisy_dwell_and_keeps_the_motion(runs):
    """A dwell whose samples scatter by less than REPEAT_FRACTION of a sampling step is found whole; the first
    sample of it (the position the machine stood at) is kept, and the moving samples are untouched."""
    cw, _ = runs
    step = float(np.median(np.hypot(*np.diff(cw, axis=0).T)))
    jitter = np.random.default_rng(5).normal(scale=0.1 * REPEAT_FRACTION * step / 2, size=(30, 2))
    pts = np.vstack([cw[:1] + np.vstack([[0.0, 0.0], jitter]), cw[1:]])
    kept, report, said = drop_repeated(pts, (300.0, 200.0), "CW")
    np.testing.assert_array_equal(kept, cw)
    assert report["repeated_samples_dropped"] == 30
    assert report["repeated_groups"] == [[1, 31, pytest.approx(17.0, abs=0.5)]]
    assert said.startswith("CW run: 30 repeated sample(s) dropped: samples 1-31 are one position, at 17.0°")
    assert drop_repeated(cw, (300.0, 200.0))[1] == {"repeated_samples_dropped": 0, "repeated_groups": []}


def test_cli_drops_repeated_samples_says_where_and_counts_independent_points(runs, tmp_path, capsys):
    """The reviewer's files: every line twice (the diagnostics' u were 1/sqrt 2 of the clean file's) and a
    60-sample dwell at the start (G and G(b) moved by 0.3 um). Both now give the clean file's figures and u, with a
    warning naming how many samples were dropped and where, and the drop recorded in the JSON."""
    cw, ccw = runs
    clean, err = cli_json(capsys, write(tmp_path / "cw.csv", cw), write(tmp_path / "ccw.csv", ccw))
    assert "repeated" not in err
    twice, err2 = cli_json(capsys, write(tmp_path / "cw2.csv", np.repeat(cw, 2, axis=0)),
                           write(tmp_path / "ccw2.csv", np.repeat(ccw, 2, axis=0)))
    for run, n in (("CW", len(cw)), ("CCW", len(ccw))):
        assert f"warning: {run} run: {n} repeated sample(s) dropped: samples 1-2, 3-4, 5-6 and {n - 3} more" in err2
    dwell_cw = np.vstack([np.repeat(cw[:1], 60, axis=0), cw])
    dwell, err3 = cli_json(capsys, write(tmp_path / "cw3.csv", dwell_cw), write(tmp_path / "ccw3.csv", ccw))
    assert "warning: CW run: 60 repeated sample(s) dropped: samples 1-61 are one position, at 17.0° (a dwell at " \
           "the start" in err3 and "CCW run" not in err3
    assert dwell["details"]["conditions"]["trimming"]["cw"]["repeated_samples_dropped"] == 60
    assert dwell["details"]["conditions"]["trimming"]["cw"]["repeated_groups"][0][:2] == [1, 61]
    assert any("60 repeated sample(s)" in n for n in dwell["notes"])
    for got in (twice, dwell):
        for key in ("G_cw", "G_ccw", "G_b", "H", "F_max", "F_min"):
            assert got[key] == clean[key], key
        for name, item in clean["diagnostics"].items():
            assert got["diagnostics"][name] == item, name
        assert got["details"]["diagnostics_model"]["points"] == len(cw) + len(ccw)


# ------------------------------------------------------------------------------------------------ signs
def hand_built_runs(n=1440, R=150.0, centre=(400.0, 250.0), feed=1000.0, squareness=50e-6, scale_x=20e-6,
                    lag_x=0.002, backlash_x=0.005, spike_y=0.004, spike_decay_deg=1.0, offset=(0.003, -0.002)):
    """CW and CCW runs of a machine built from the documented geometric meaning of each sign, not from the
    diagnostics' model: the Y axis moves along (sin a, cos a) (the angle between +X and +Y is 90 deg - a); X travels
    (1 + scale_x) mm per mm commanded; X follows its command lag_x s late; X falls short of its command by
    backlash_x / 2 in its direction of travel; Y sticks at its reversals (it stays behind its new direction of
    travel by spike_y, decaying over spike_decay_deg of arc); the path's centre is offset from the nominal one."""
    omega = feed / 60.0 / R                                   # rad/s
    out = {}
    for name, d in (("cw", -1.0), ("ccw", 1.0)):
        theta = np.radians(10.1) + d * np.arange(n) * 2 * np.pi / n
        theta_x = theta - d * omega * lag_x                   # where X was commanded lag_x ago
        x = R * np.cos(theta_x) * (1 + scale_x) + 0.5 * backlash_x * d * np.sign(np.sin(theta))  # short of -sign(xdot)
        ydot_sign = d * np.sign(np.cos(theta))
        since = np.mod(d * (theta - np.pi / 2), np.pi)        # arc travelled since the last Y reversal (90, 270 deg)
        y = R * np.sin(theta) - spike_y * ydot_sign * np.exp(-since / np.radians(spike_decay_deg))
        pts = np.column_stack([x + y * np.sin(squareness), y * np.cos(squareness)])
        out[name] = pts + np.asarray(centre) + np.asarray(offset)
    return out["cw"], out["ccw"]


def test_signs_follow_their_documented_geometric_meaning(tmp_path, capsys):
    """+50 µrad of squareness built as 'the angle between +X and +Y is 90 deg - 50 µrad' gives +50 µrad; likewise
    X travelling further (+20 µm/m), X lagging behind Y (+2 ms), X's lost motion (+5 µm), Y sticking at its reversals
    (+4 µm, outward) and the centre offset (+3, -2 µm); the JSON says what each sign means and the text names the
    meaning of each resolved sign."""
    cw, ccw = hand_built_runs()
    dg = diagnose(cw, ccw, 150.0, (400.0, 250.0), feed_mm_min=1000.0)
    assert dg["squareness"]["value"] == pytest.approx(50.0, abs=0.05)
    assert dg["scale_mismatch"]["value"] == pytest.approx(20.0, abs=0.05)
    assert dg["servo_mismatch"]["value"] == pytest.approx(2.0, abs=0.01)
    assert dg["backlash_x"]["value"] == pytest.approx(5.0, abs=0.01)
    assert dg["reversal_spike_y"]["value"] == pytest.approx(4.0, abs=0.05)
    assert dg["_model"]["centre_offset_um"] == pytest.approx([3.0, -2.0], abs=0.01)
    code = cli_main(["circular-test", write(tmp_path / "cw.csv", cw), write(tmp_path / "ccw.csv", ccw),
                     "--nominal-radius", "150", "--nominal-center", "400", "250", "--feed", "1000", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert code == 0
    assert d["diagnostics"]["squareness"]["sign"].startswith("positive: the angle between the +X and +Y axes is less "
                                                              "than 90° by the value")
    assert d["diagnostics"]["scale_mismatch"]["sign"].startswith("X scale error minus Y's: positive: X travels further")
    assert "positive: X lags behind Y" in d["diagnostics"]["servo_mismatch"]["sign"]
    assert d["diagnostics"]["backlash_x"]["sign"].startswith("positive: lost motion")
    assert d["diagnostics"]["reversal_spike_y"]["sign"].startswith("positive: Y sticks at its reversals (90° and 270°)")
    assert "minus the nominal centre" in d["details"]["diagnostics_model"]["signs"]["centre_offset"]
    assert cli_main(["circular-test", str(tmp_path / "cw.csv"), str(tmp_path / "ccw.csv"), "--nominal-radius", "150",
                     "--nominal-center", "400", "250", "--feed", "1000"]) == 0
    lines = {ln.split("  ")[1].strip(): ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("  ")}
    for label, words in (("squareness", "angle X-Y below 90°"), ("scale mismatch X-Y", "X travels further"),
                         ("servo mismatch X-Y", "X lags behind Y"), ("backlash X", "lost motion"),
                         ("reversal spike Y", "outward spike")):
        assert lines[label].endswith(words), lines[label]
    # the opposite machine gives the opposite signs and words
    cw, ccw = hand_built_runs(squareness=-50e-6, scale_x=-20e-6, backlash_x=-0.005, spike_y=-0.004)
    dg = diagnose(cw, ccw, 150.0, (400.0, 250.0), feed_mm_min=1000.0)
    for name, value in (("squareness", -50.0), ("scale_mismatch", -20.0), ("backlash_x", -5.0),
                        ("reversal_spike_y", -4.0)):
        assert dg[name]["value"] == pytest.approx(value, abs=0.05), name


def test_the_words_follow_the_plane():
    from fitbench.plots.circular_test import SIGNS, for_plane, meaning
    assert meaning("squareness", 50.0, 0.1, "zx") == "angle Z-X below 90°"
    assert meaning("servo_mismatch", -1.0, 0.1, "yz") == "Z lags behind Y"
    assert meaning("backlash_x", 0.1, 0.1) == ""                       # within 2 u: the sign is not resolved
    assert for_plane(SIGNS["squareness"], "zx").startswith("positive: the angle between the +Z and +X axes")


def test_the_json_model_is_in_the_json_units(tmp_path, capsys):
    """``details.diagnostics_model`` is in the units the JSON declares (mm, rad), as docs/circular-test.md says: it
    held centre_offset_um, radius_offset_um, spike_decay_deg and residual_rms_um beside units {length: mm}."""
    files = [write(tmp_path / f"{n}.csv", pts) for n, pts in zip(("cw", "ccw"), hand_built_runs())]
    cw, ccw = (np.loadtxt(f, delimiter=",", skiprows=1) for f in files)   # the points the CLI reads
    m = diagnose(cw, ccw, 150.0, (400.0, 250.0), feed_mm_min=1000.0)["_model"]
    code = cli_main(["circular-test", *files, "--nominal-radius", "150", "--nominal-center", "400", "250", "--feed",
                     "1000", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert code == 0 and d["units"]["length"] == "mm" and d["units"]["angle"] == "rad"
    got = d["details"]["diagnostics_model"]
    assert not [k for k in got if k.endswith(("_um", "_deg"))], sorted(got)
    assert got["centre_offset"] == pytest.approx([v * 1e-3 for v in m["centre_offset_um"]], rel=1e-6)
    assert got["centre_offset"] == pytest.approx([0.003, -0.002], abs=1e-5)
    assert got["radius_offset"] == pytest.approx({k: v * 1e-3 for k, v in m["radius_offset_um"].items()}, rel=1e-6)
    assert got["spike_decay"] == pytest.approx(np.radians(m["spike_decay_deg"]), rel=1e-9)
    assert got["spike_decay"] == pytest.approx(np.radians(1.0), rel=0.05)
    assert got["residual_rms"] == pytest.approx(m["residual_rms_um"] * 1e-3, rel=1e-9)
    assert got["points"] == len(cw) + len(ccw) and got["converged"] is True


def write_polar(path, runs, R):
    """A ballbar-style file: direction, angle (deg), radial deviation written as µm numbers without a unit."""
    rows = ["dir,angle (deg),dr"]
    for tag, pts in zip(("G02", "G03"), runs):
        q = pts - (400.0, 250.0)
        ang, dr = np.degrees(np.arctan2(q[:, 1], q[:, 0])), (np.hypot(*q.T) - R) * 1e3
        rows += [f"{tag},{a:.6f},{d:.5f}" for a, d in zip(ang, dr)]
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def test_polar_deviations_in_um_read_as_mm_name_the_unit(tmp_path, capsys):
    """docs/cli.md promised that a circular test far from its nominal radius warns naming the likely unit; a ballbar
    file whose deviations (µm) were read as mm got warnings about the centre and the radius only."""
    small = hand_built_runs(squareness=10e-6, scale_x=5e-6, lag_x=0.0, backlash_x=0.002, spike_y=0.0, offset=(0, 0))
    path = write_polar(tmp_path / "small.csv", small, 150.0)
    assert cli_main(["circular-test", path, "--nominal-radius", "150"]) == 0
    err = capsys.readouterr().err
    assert "warning: radial deviations up to" in err and "are implausible for a circular test" in err
    assert "is the deviation column in µm? (--unit um)" in err
    assert cli_main(["circular-test", path, "--nominal-radius", "150", "--unit", "um"]) == 0
    assert "implausible" not in capsys.readouterr().err
    big = write_polar(tmp_path / "big.csv", hand_built_runs(), 150.0)     # deviations beyond 5 % of R as mm: refused
    assert cli_main(["circular-test", big, "--nominal-radius", "150"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "error: radial deviations up to" in err[0] and "(--unit um)" in err[0]


def test_repeated_samples_of_a_file_without_direction_labels_name_the_run_by_its_order(runs, tmp_path, capsys):
    """One file with a run column 1, 2 (no CW/CCW): the warning names the run by its place, not a guessed label."""
    cw, ccw = runs
    dwell = np.vstack([np.repeat(cw[:1], 5, axis=0), cw])
    path = tmp_path / "both.csv"
    path.write_text("run,x,y\n" + "".join(f"{k},{x:.9f},{y:.9f}\n" for k, pts in ((1, dwell), (2, ccw)) for x, y in pts))
    assert cli_main(["circular-test", str(path), "--nominal-radius", "150", "--nominal-center", "300", "200"]) == 0
    assert "warning: first run: 5 repeated sample(s) dropped: samples 1-6" in capsys.readouterr().err
