"""The report of a user's own studies suggests commands that work: a study that is not one of the project's is named
by its TOML file (``meta.json`` records it: ``config_file``), and ``python -m experiments.verify --results OUT`` checks
such a study by running that TOML (before: "unknown study 'my_study'", exit 2, for both commands the report gave)."""
import json
import re
import shlex

import pytest

from experiments import report, verify
from experiments import run as runner
from experiments.verdict import recorded_config

STUDY = ('name = "{name}"\ntitle = "a personal study"\nseed = 1\nrepetitions = 1\n[[datasets]]\nsource = "circle"\n'
         'params = {{ radius = 5.0, noise = 0.01, n = 12 }}\n[[methods]]\nid = "circle.kasa"\n')


def _run(*args):
    assert runner.main([*args, "--jobs", "1", "--no-report"]) == 0


@pytest.mark.slow
def test_the_commands_of_a_user_study_s_report_run(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "studies").mkdir()
    for name in ("my_study", "plug"):
        (tmp_path / "studies" / f"{name}.toml").write_text(STUDY.format(name=name), encoding="utf-8")
    _run("studies/my_study.toml", "--out", "out")
    _run("studies/plug.toml", "--out", "out")
    assert recorded_config(tmp_path / "out" / "my_study") == (tmp_path / "studies" / "my_study.toml").resolve()
    report.build(tmp_path / "out", tmp_path / "out" / "paper", log=lambda *a: None)
    text = (tmp_path / "out" / "paper" / "report.md").read_text(encoding="utf-8")
    rerun = re.search(r"rerun it with (python -m experiments\.run [^\n]*?)\.(?:\n|$)", text)
    assert rerun and rerun.group(1) == "python -m experiments.run studies/my_study.toml --out out", text
    check = re.search(r"No current reproducibility verdict: run `([^`]*)`", text)
    assert check and check.group(1) == "python -m experiments.verify --results out --write-verdict", text
    capsys.readouterr()
    assert runner.main([*shlex.split(rerun.group(1))[3:], "--jobs", "1", "--no-report"]) == 0
    assert verify.main(shlex.split(check.group(1))[3:]) == 0, capsys.readouterr()
    verdict = json.loads((tmp_path / "out" / "verify.json").read_text(encoding="utf-8"))
    assert verdict["agree"] is True and sorted(s["study"] for s in verdict["studies"]) == ["my_study", "plug"]


def test_a_user_study_whose_toml_is_gone_is_one_line(tmp_path, capsys):
    """verify cannot rerun a user's study whose recorded TOML is not there: one line saying so and what to give."""
    folder = tmp_path / "out" / "gone"
    folder.mkdir(parents=True)
    (folder / "results.csv").write_text("study,status\ngone,ok\n", encoding="utf-8")
    (folder / "meta.json").write_text(json.dumps({"quick": False, "config_file": str(tmp_path / "gone.toml")}),
                                      encoding="utf-8")
    assert verify.main(["gone", "--results", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "which is not there" in err[0] and "PATH/gone.toml --results" in err[0], err
