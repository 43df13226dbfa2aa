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
