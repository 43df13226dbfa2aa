"""Where ``python -m experiments.run`` writes: an empty --out (an unset $OUT) is refused, and a study that is not one
of the project's never joins the committed results/ and paper/ unasked."""
from pathlib import Path

import pytest

from experiments import config as configs
from experiments.run import main as run_main, output_folder

STUDY = ('name = "mine"\ntitle = "a personal study"\nseed = 1\nrepetitions = 1\n[[datasets]]\nsource = "circle"\n'
         'params = { radius = 5.0, noise = 0.01, n = 12 }\n[[methods]]\nid = "circle.kasa"\n')


@pytest.fixture
def personal(tmp_path, monkeypatch):
    """A checkout-like folder with a committed results/ and paper/, and a personal study beside it."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "results").mkdir()
    (tmp_path / "paper").mkdir()
    (tmp_path / "paper" / "report.md").write_text("the committed report\n", encoding="utf-8")
    cfg = tmp_path / "mine.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    return tmp_path, cfg


@pytest.mark.parametrize("out", ["", "  "])
def test_an_empty_out_is_refused(personal, capsys, out):
    root, cfg = personal
    assert run_main([str(cfg), "--jobs", "1", "--out", out]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--out is empty" in err[0] and "Traceback" not in err[0], err
    assert (root / "paper" / "report.md").read_text(encoding="utf-8") == "the committed report\n"
    assert sorted(p.name for p in root.iterdir()) == ["mine.toml", "paper", "results"]   # nothing written


def test_a_personal_study_without_out_goes_to_results_user(personal, capsys):
    root, cfg = personal
    assert run_main([str(cfg), "--jobs", "1"]) == 0
    captured = capsys.readouterr()
    notes = [ln for ln in captured.err.splitlines() if "not one of the project's studies" in ln]
    assert len(notes) == 1 and "results/user/" in notes[0] and "results/user/paper/" in notes[0], captured.err
    assert (root / "results" / "user" / "mine" / "results.csv").is_file()
    assert (root / "results" / "user" / "paper" / "report.md").is_file()
    assert not (root / "results" / "mine").exists()
    assert (root / "paper" / "report.md").read_text(encoding="utf-8") == "the committed report\n"
    assert sorted(p.name for p in (root / "paper").iterdir()) == ["report.md"]


@pytest.mark.parametrize("out", ["results", "results/quick"])
def test_the_committed_results_folder_is_refused_for_a_personal_study(personal, capsys, out):
    root, cfg = personal
    assert run_main([str(cfg), "--jobs", "1", "--out", out]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not one of the project's studies" in err[0] and "mine.toml" in err[0], err
    assert not (root / out / "mine").exists() and not (root / "results" / "paper").exists()


def test_the_project_studies_keep_results_and_paper():
    cfg = configs.load("ellipse_angle")
    assert output_folder(None, [cfg], False) == (Path("results"), None)
    assert output_folder(None, [cfg], True) == (Path("results") / "quick", None)
    assert output_folder("elsewhere", [cfg], False) == (Path("elsewhere"), None)
    assert output_folder("results", [cfg], False) == (Path("results"), None)
