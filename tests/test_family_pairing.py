"""A method of one family on data of another family's shape (a circle fit on a square outline, a square fit on
circles) is refused before any row, as a method that cannot take a source's data is, unless the study asks for it
(`any_family = true`); and no row ever gets errors against the truth of another family (they were `ok` rows with
a circle's centre error against a square's centre, pooled into the tables)."""
import numpy as np
import pandas as pd
import pytest

from datasets import sources
from experiments import config as configs
from experiments import run as runner
from experiments.study import ConfigError
from experiments.rows import fit_row

STUDY = """name = "study"
title = "t"
seed = 1
repetitions = 2
[[datasets]]
source = "{source}"
{params}
[[methods]]
id = "{method}"
{extra}
"""


def write(tmp_path, source="circle", method="circle.kasa", params="params = { radius = 5.0, noise = 0.01, n = 30 }",
          extra=""):
    path = tmp_path / "study.toml"
    path.write_text(STUDY.format(source=source, method=method, params=params, extra=extra), encoding="utf-8")
    return path


def test_a_method_of_another_family_is_refused_in_one_line_before_any_row(tmp_path, capsys):
    path = write(tmp_path, method="ellipse.halir_flusser")
    code = runner.main([str(path), "--out", str(tmp_path / "out"), "--jobs", "1", "--no-report"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "Traceback" not in err, err
    assert ("study.toml: methods[0]: ellipse.halir_flusser (family 'ellipse') would fit datasets[0] (source 'circle'), "
            "whose points and truth are of family 'circle'; remove the method, name the data sets it fits in its "
            "on = [...], or set any_family = true") in err, err
    assert not (tmp_path / "out" / "study" / "rows.sqlite").exists()
    ellipse = 'params = { semi_axes = [5.0, 3.0], noise = 0.01, n = 30 }'
    with pytest.raises(ConfigError, match=r"methods\[0\] \(circle\.\*\): circle\.\w+ \(family 'circle'\) would fit "
                                          r"datasets\[0\] \(source 'ellipse'\), whose points and truth are of family "
                                          r"'ellipse'"):
        configs.load(str(write(tmp_path, source="ellipse", method="circle.*", params=ellipse)))
    configs.load(str(write(tmp_path, source="ellipse", method="circle.*", params=ellipse, extra="any_family = true")))
    configs.load(str(write(tmp_path, source="ellipse", method="ellipse.halir_flusser", params=ellipse)))


def test_a_plugin_source_and_a_file_declare_their_family(tmp_path):
    """The check reads the source's declaration (``register_source(family=...)``) and a file's truth table; a source
    that declares none is not checked before the run (its rows get no errors against another family's truth)."""
    def squares(rng, *, n: int = 40):
        t = rng.uniform(-1, 1, n)
        return np.c_[t, np.sign(rng.uniform(-1, 1, n))], {"family": "square", "center": (0.0, 0.0), "side": 2.0}
    try:
        sources.register_source("test_squares", random=True, summary="t", gives=np.ndarray, family="square")(squares)
        sources.register_source("test_squares_undeclared", random=True, summary="t", gives=np.ndarray)(squares)
        with pytest.raises(ConfigError, match=r"circle.kasa \(family 'circle'\) would fit datasets\[0\] \(source "
                                              r"'test_squares'\), whose points and truth are of family 'square'"):
            configs.load(str(write(tmp_path, source="test_squares", params="")))
        configs.load(str(write(tmp_path, source="test_squares", params="", extra='on = ["circle"]\n[[datasets]]\nsource = "circle"')))
        configs.load(str(write(tmp_path, source="test_squares_undeclared", params="")))
        with pytest.raises(ValueError, match="family must be a family name"):
            sources.register_source("test_bad_family", random=False, summary="t", family=3)
    finally:
        for name in ("test_squares", "test_squares_undeclared"):
            sources._REGISTRY.pop(name, None)
    (tmp_path / "pts.csv").write_text("x,y\n1,0\n0,1\n-1,0\n0,-1\n0.7071,0.7071\n", encoding="utf-8")
    text = ('[[datasets]]\nfile = "pts.csv"\ntruth = { family = "ellipse", center = [0.0, 0.0], '
            'semi_axes = [1.0, 1.0], angle = 0.0 }\n[[methods]]\nid = "circle.kasa"\n')
    path = tmp_path / "file.toml"
    path.write_text('name = "file"\ntitle = "t"\nseed = 1\n' + text, encoding="utf-8")
    with pytest.raises(ConfigError, match=r"circle.kasa \(family 'circle'\) would fit datasets\[0\] \(source 'file'\)"):
        configs.load(str(path))


def test_no_row_gets_errors_against_another_family_s_truth():
    rng = np.random.default_rng(3)
    t = rng.uniform(0, 2 * np.pi, 50)
    points = np.c_[np.cos(t), np.sin(t)] + rng.normal(0, 1e-3, (50, 2))
    task = {"study": "s", "dataset": {"label": "d", "params": {}}, "repetition": 0, "seed": 1, "stream": [0, 0, 0],
            "method": "circle.kasa", "params": {}}
    same = fit_row(task, points, {"family": "circle", "center": (0.0, 0.0), "radius": 1.0})
    assert same["status"] == "ok" and same["center_error"] < 1e-3 and "radius_error" in same
    other = fit_row(task, points, {"family": "square", "center": (0.0, 0.0), "side": 2.0})
    assert other["status"] == "ok" and other["radius"] == same["radius"]
    assert not {"center_error", "radius_error"} & set(other), other
    assert other["message"].endswith("no errors against the truth: the data are of family 'square', circle.kasa of "
                                     "'circle'")
    unnamed = fit_row(task, points, {"center": (0.0, 0.0), "radius": 1.0})   # a truth naming no family: as before
    assert unnamed["center_error"] == same["center_error"] and unnamed["message"] == same["message"]


def test_a_study_that_asks_for_another_family_gets_rows_without_truth_errors(tmp_path):
    ellipse = 'params = { semi_axes = [5.0, 4.9], noise = 0.01, n = 30 }'
    path = write(tmp_path, source="ellipse", method="circle.kasa", params=ellipse, extra="any_family = true")
    assert runner.main([str(path), "--out", str(tmp_path / "out"), "--jobs", "1", "--no-report"]) == 0
    rows = pd.read_csv(tmp_path / "out" / "study" / "results.csv")
    assert len(rows) == 2 and (rows["status"] == "ok").all() and rows["form_error"].notna().all()
    assert "center_error" not in rows or rows["center_error"].isna().all()
    assert rows["message"].str.contains("the data are of family 'ellipse', circle.kasa of 'circle'").all()
