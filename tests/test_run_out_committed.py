"""``--out`` never writes into the committed report ``paper/`` or results ``results/``: the report of ``--out DIR``
goes to ``DIR/paper``, so ``--out .`` in the checkout would replace ``paper/`` with a report of the run's study, and
``--out paper`` (or a folder inside ``paper/`` or ``results/``) would write into the committed folders. A personal
study keeps ``results/user/``; a project study keeps ``results/``."""
from pathlib import Path

import pytest

from experiments import config as configs
from experiments import report
from experiments.run import main as run_main, output_folder
from methods import InvalidInputError

STUDY = ('name = "mine"\ntitle = "a personal study"\nseed = 1\nrepetitions = 1\n[[datasets]]\nsource = "circle"\n'
         'params = { radius = 5.0, noise = 0.01, n = 12 }\n[[methods]]\nid = "circle.kasa"\n')


@pytest.fixture
def checkout(tmp_path, monkeypatch):
    """A stand-in for the repository (its committed paper/ and results/), a personal study outside it."""
    repo = tmp_path / "checkout"
    (repo / "paper").mkdir(parents=True)
    (repo / "results" / "noise").mkdir(parents=True)
    (repo / "paper" / "report.md").write_text("the committed report\n", encoding="utf-8")
    monkeypatch.setattr(report, "REPO", repo)
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    (tmp_path / "mine.toml").write_text(STUDY, encoding="utf-8")
    return repo, tmp_path / "mine.toml"


def _snapshot(repo: Path) -> list:
    return sorted((p.relative_to(repo).as_posix(), p.is_file() and p.read_bytes()) for p in repo.rglob("*"))


@pytest.mark.parametrize("out, words", [(".", "would put the run's report into paper/"),
                                        ("paper", "lies inside paper/"), ("paper/mine", "lies inside paper/"),
                                        ("results/noise", "lies inside results/")])
def test_a_personal_study_stays_out_of_the_committed_folders(checkout, monkeypatch, capsys, out, words):
    repo, cfg = checkout
    before = _snapshot(repo)
    for where, given in ((repo, out), (repo.parent / "elsewhere", str(repo / out))):   # relative and absolute
        monkeypatch.chdir(where)
        assert run_main([str(cfg), "--jobs", "1", "--out", given]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and words in err[0] and "Traceback" not in err[0], err
        assert f"--out {given} " in err[0] and "results/user" in err[0], err
        assert _snapshot(repo) == before   # nothing written


def test_the_user_folder_and_other_folders_stay_open(checkout):
    repo, cfg = checkout
    mine = configs.load(str(cfg))
    for out in (repo / "results" / "user", repo / "results" / "user" / "x", repo.parent / "other", repo / "mine"):
        assert output_folder(str(out), [mine], False) == (out, None)


def test_a_project_study_keeps_results_but_not_paper(checkout):
    repo, _ = checkout
    project = configs.load("ellipse_angle")
    assert output_folder(str(repo / "results"), [project], False) == (repo / "results", None)
    assert output_folder(str(repo / "results" / "quick"), [project], True) == (repo / "results" / "quick", None)
    for out in (repo, repo / "paper"):
        with pytest.raises(InvalidInputError, match="paper/"):
            output_folder(str(out), [project], False)


def test_outside_the_checkout_the_words_say_reserved_not_committed(tmp_path, monkeypatch):
    """The current folder's paper/ and results/ are where a run without --out writes there: refused alike, not called
    committed."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.toml").write_text(STUDY, encoding="utf-8")
    mine = configs.load(str(tmp_path / "mine.toml"))
    for out, words in ((".", "the report of results/ of the current folder"), ("paper", "lies inside paper/"),
                       ("results/x", "reserved for the project's studies")):
        with pytest.raises(InvalidInputError) as info:
            output_folder(out, [mine], False)
        assert words in str(info.value) and "committed" not in str(info.value), str(info.value)
