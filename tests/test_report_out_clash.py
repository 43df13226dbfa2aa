"""``python -m experiments.report --results OTHER --out paper`` in the checkout replaced the committed report with a
user's study (paper/ rewritten, the committed figures deleted), exit 0. A report of other results into the ``paper/``
of the repository or of the current folder is one line and exit 2, nothing written; the report of ``results/`` into
``paper/`` beside it is still built."""
import pytest

from experiments import report


def study_folder(results):
    """A results folder holding one (unfinished) study: enough for a report."""
    (results / "half").mkdir(parents=True)
    (results / "half" / "rows.sqlite").write_bytes(b"")
    return results


@pytest.mark.parametrize("results", ["mine", "results/quick"])
@pytest.mark.parametrize("where", ["checkout", "current folder"])
def test_a_report_of_other_results_into_paper_is_refused(tmp_path, monkeypatch, capsys, results, where):
    repo = tmp_path / "repo"
    repo.mkdir()
    monkeypatch.setattr(report, "REPO", repo)
    monkeypatch.chdir(repo if where == "checkout" else tmp_path)
    base = repo if where == "checkout" else tmp_path
    study_folder(base / results)
    for out in ("paper", str(base / "paper"), "paper/sub"):
        assert report.main(["--results", results, "--out", out]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"experiments.report: error: --out {out} writes into paper/"), err
        assert f"not the report of --results {results}" in err[0] and f"{results}/paper/" in err[0], err
        assert not (base / "paper").exists()


def test_the_report_of_results_into_paper_beside_it_is_built(tmp_path, monkeypatch):
    monkeypatch.setattr(report, "REPO", tmp_path)
    monkeypatch.chdir(tmp_path)
    study_folder(tmp_path / "results")
    assert report.main(["--results", "results", "--out", "paper"]) == 0
    assert (tmp_path / "paper" / "report.md").is_file()
    study_folder(tmp_path / "mine")
    assert report.main(["--results", "mine", "--out", str(tmp_path / "elsewhere")]) == 0
    assert report.main(["--results", "mine"]) == 0 and (tmp_path / "mine" / "paper" / "report.md").is_file()


def _refused(argv, *words):
    """``experiments.report`` refuses ``argv`` in one line holding ``words`` (exit 2) and writes nothing."""
    from cli_calls import call
    called = call(report.main, *argv)
    assert called.returncode == 2 and called.stdout == "", called
    err = called.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("experiments.report: error: --out ") and "Traceback" not in called.stderr
    for w in words:
        assert w in err[0], err
    return err[0]


def snapshot(root):
    return sorted((p.relative_to(root).as_posix(), p.read_bytes() if p.is_file() else None)
                  for p in root.rglob("*"))


def test_out_onto_results_or_a_study_is_refused_before_anything_is_written(tmp_path, monkeypatch):
    """`--out` the results folder read, a folder inside it (other than its report folder, RESULTS/paper), a study
    folder (of these or other results) or another results folder, also through a symlink: one line, exit 2, no file
    written anywhere. Each was built into, exit 0: the report's tables/, figures/ and pages among the studies."""
    repo = tmp_path / "repo"
    repo.mkdir()
    monkeypatch.setattr(report, "REPO", repo)
    monkeypatch.chdir(tmp_path)
    study_folder(tmp_path / "mine")
    study_folder(tmp_path / "theirs")
    (tmp_path / "link").symlink_to(tmp_path / "mine")
    before = snapshot(tmp_path)
    cases = {"mine": "is the results folder read (--results mine)",
             "link": "is the results folder read (--results mine)",
             "mine/sub": "lies inside the results folder read",
             "mine/paper/sub": "lies inside the results folder read",
             "mine/half": "is a study folder",
             "link/half": "is a study folder (mine/half)",
             "mine/half/tables": "lies in the study folder mine/half",
             "theirs/half": "is a study folder",
             "theirs": "is the results folder of other studies",
             "theirs/paper": "lies in theirs, the results folder of other studies",
             str(tmp_path / "theirs" / "new"): "lies in theirs, the results folder of other studies"}
    for out, words in cases.items():
        _refused(["--results", "mine", "--out", out], f"--out {out} {words}", "leave --out out (the report then "
                 "goes to mine/paper/)")
        assert snapshot(tmp_path) == before, out
    assert report.main(["--results", "mine", "--out", "mine/paper"]) == 0       # its own report folder (the default)
    assert (tmp_path / "mine" / "paper" / "report.md").is_file()


def test_out_that_is_a_file_is_refused(tmp_path, monkeypatch):
    """`--out report.md` (a file), or a folder under a file: one line, exit 2, the file untouched (a traceback,
    FileExistsError / NotADirectoryError, exit 1)."""
    monkeypatch.chdir(tmp_path)
    study_folder(tmp_path / "mine")
    (tmp_path / "report.md").write_text("mine\n")
    _refused(["--results", "mine", "--out", "report.md"], "--out report.md is a file: the report is a folder")
    _refused(["--results", "mine", "--out", "report.md/x"], "--out report.md/x is no folder (report.md is a file)")
    assert (tmp_path / "report.md").read_text() == "mine\n"


def test_out_into_the_paper_of_another_checkout_is_refused(tmp_path, monkeypatch):
    """The paper/ of a folder with a results/ beside it (another checkout, a folder `experiments.run` filled) is the
    report of those results: a report of other results into it (or below it) is refused; the report of those
    results into it is built."""
    monkeypatch.chdir(tmp_path)
    other = tmp_path / "other"
    study_folder(other / "results")
    (other / "paper").mkdir()
    (other / "paper" / "report.md").write_text("their report\n")
    study_folder(tmp_path / "mine")
    for out in (other / "paper", other / "paper" / "sub"):
        _refused(["--results", "mine", "--out", str(out)], "writes into paper/, the report of other/results/ beside "
                 "it, not the report of --results mine")
    assert (other / "paper" / "report.md").read_text() == "their report\n" and not (other / "paper" / "sub").exists()
    assert report.main(["--results", str(other / "results"), "--out", str(other / "paper")]) == 0


def test_fitbench_report_of_other_results_goes_beside_them(tmp_path, monkeypatch):
    """`fitbench report --results mine` builds mine/paper, as `python -m experiments.report --results mine`; the
    command added `--out paper` and the report was refused as one into paper/ (exit 2), or, before that refusal,
    replaced the report of results/ in paper/."""
    from cli_calls import cli
    monkeypatch.setattr(report, "REPO", tmp_path / "repo")
    monkeypatch.chdir(tmp_path)
    study_folder(tmp_path / "mine")
    got = cli("report", "--results", "mine")
    assert got.returncode == 0, got.stderr
    assert (tmp_path / "mine" / "paper" / "report.md").is_file() and not (tmp_path / "paper").exists()
