"""The runner: configs validate, the published study writes its table and provenance."""
import json

import pandas as pd
import pytest

from experiments import config as configs
from experiments.run import main, run_study


def test_list_and_default_studies(capsys):
    assert main(["--list"]) == 0
    out = capsys.readouterr().out
    assert "published_circle" in out and "default" in out and "nist_circle" in out


def test_unknown_study_is_one_line_exit_2(capsys):
    assert main(["no_such_study"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown study" in err[0]


def test_config_validation_names_the_problem(tmp_path, monkeypatch):
    bad = tmp_path / "broken.toml"
    bad.write_text('name = "broken"\ntitle = "t"\nkind = "published_circle"\ndatasets = ["roundness_set2"]\n'
                   'methods = ["circle.gauss_newtn"]\n')
    monkeypatch.setattr(configs, "CONFIG_DIR", tmp_path)
    with pytest.raises(configs.ConfigError, match="broken.toml: unknown method id 'circle.gauss_newtn'"):
        configs.load("broken")
    bad.write_text('name = "broken"\ntitle = "t"\nkind = "published_circle"\ndatasets = ["roundness_set9"]\nmethods = []\n')
    with pytest.raises(configs.ConfigError, match="unknown data set 'roundness_set9'"):
        configs.load("broken")


def test_published_study_writes_results_and_provenance(tmp_path, monkeypatch):
    real_load = configs.load

    def small(name):  # the same study with a small Monte Carlo, for speed
        cfg = real_load(name)
        cfg["rounding"] = {**cfg.get("rounding", {}), "samples": 40}
        cfg["timing"] = {"min_time_s": 0.001, "rounds": 3}
        return cfg

    monkeypatch.setattr(configs, "load", small)
    target = run_study("published_circle", tmp_path, log=lambda *a: None)
    rows = pd.read_csv(target / "results.csv")
    meta = json.loads((target / "meta.json").read_text())
    assert set(rows["status"]) == {"ok"}
    assert {"roundness_set1", "roundness_set2", "roundness_set3"} <= set(rows["dataset"])
    assert all(c in rows for c in ("form_error", "center_x", "radius", "time_median_s", "time_iqr_s"))
    gn = rows[(rows.dataset == "roundness_set2") & (rows.method == "circle.gauss_newton")]
    assert round(float(gn.form_error.iloc[0]), 4) == 1.7487
    found = {(f["dataset"], f["column"]): f for f in meta["findings"]["published_vs_reproduced"]}
    assert found[("roundness_set2", "MIC")]["reproduced"] and found[("roundness_set2", "MCC")]["reproduced"]
    assert found[("roundness_set2", "Voronoi (minimum zone)")]["reproduced"]
    assert not found[("roundness_set1", "LSQ (paper's Gauss-Newton)")]["reproduced"]
    for key in ("git_commit", "git_dirty", "versions", "blas", "cpu", "date", "config", "config_hash"):
        assert key in meta
    assert not list(target.glob(".*.tmp"))  # atomic writes leave no temporaries
