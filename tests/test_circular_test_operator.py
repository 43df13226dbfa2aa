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
