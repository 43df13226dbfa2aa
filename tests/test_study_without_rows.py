"""A TOML study whose methods run on no data set (an ``on`` label that names none, a ``max_n`` below every data set's
n) is refused in one line before any row; it ran 0 rows and crashed in the analysis (KeyError 'status'). The analysis
of an empty frame does not crash either."""
import pandas as pd
import pytest

from experiments import analysis
from experiments import study as contract
from experiments import config as configs
from experiments.run import main as run_main, run_study
from experiments.study import ConfigError

STUDY = ('name = "zero"\ntitle = "z"\nseed = 1\nrepetitions = 2\n[[datasets]]\nsource = "circle"\n'
         'params = {{ radius = 5.0, noise = 0.01, n = 30 }}\n[[methods]]\nid = "circle.kasa"\n{extra}\n')


@pytest.mark.parametrize("extra, words", [
    ('on = ["nothere"]', ["methods[0]: on = [...] names 'nothere', no data set's label", "the labels are: 'circle'"]),
    ('on = ["circel"]', ["names 'circel'", "did you mean 'circle'?"]),
    ('max_n = 5', ["the grid has 0 rows", "circle (n = 30)", "circle.kasa max_n = 5"]),
    ('on = ["circle"]\nmax_n = 29', ["the grid has 0 rows", 'circle.kasa on = ["circle"] max_n = 29']),
])
def test_a_study_whose_methods_run_on_nothing_is_refused_before_any_row(tmp_path, capsys, extra, words):
    cfg = tmp_path / "zero.toml"
    cfg.write_text(STUDY.format(extra=extra), encoding="utf-8")
    out = tmp_path / "out"
    assert run_main([str(cfg), "--jobs", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and all(w in err[0] for w in words) and "Traceback" not in err[0], err
    assert not (out / "zero").exists()


def test_run_study_refuses_it_too(tmp_path):
    cfg = tmp_path / "zero.toml"
    cfg.write_text(STUDY.format(extra="max_n = 5"), encoding="utf-8")
    with pytest.raises(ConfigError, match="the grid has 0 rows"):
        run_study(str(cfg), tmp_path / "out", jobs=1, log=lambda *a: None)
    assert not (tmp_path / "out" / "zero" / "rows.sqlite").exists()


def test_a_label_of_another_data_set_is_kept(tmp_path, capsys):
    cfg = tmp_path / "zero.toml"
    cfg.write_text(STUDY.format(extra='on = ["ring"]\nmax_n = 12\n[[datasets]]\nsource = "circle"\nlabel = "ring"\n'
                                      'params = { radius = 1.0, n = 12 }'), encoding="utf-8")
    assert run_main([str(cfg), "--jobs", "1", "--out", str(tmp_path / "out"), "--no-report"]) == 0, \
        capsys.readouterr().err
    rows = pd.read_csv(tmp_path / "out" / "zero" / "results.csv")
    assert list(rows["dataset"].unique()) == ["ring"] and list(rows["status"]) == ["ok"] * 2


def test_the_analysis_of_no_rows_does_not_crash(tmp_path):
    cfg = tmp_path / "zero.toml"
    cfg.write_text(STUDY.format(extra=""), encoding="utf-8")
    loaded = configs.load(str(cfg))
    values, result = analysis.analyse(contract.study_of(loaded["kind"]), pd.DataFrame(), loaded, tmp_path, print)
    assert values == {"n_rows": 0, "n_ok": 0} and not result.tables and not result.figures
