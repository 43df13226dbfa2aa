"""``python -m experiments.report --results DIR`` on a folder holding no study (empty, or a typo'd folder such as
``results/quick/paper``) is one line and exit 2, with nothing built (it built a report of nothing, exit 0); the
report's sentence of how to reproduce a user's study reads as written (a space before the parenthesis, ``meta.json``
as code, not ``\\`meta.json\\```), and a folder of unfinished studies has no empty command ("reproduce them with .")."""
import json

import pytest

from experiments import report


@pytest.mark.parametrize("layout", ["empty", "a paper build only", "files only"])
def test_a_folder_without_a_study_is_one_line_and_exit_2(tmp_path, capsys, layout):
    results = tmp_path / "results"
    results.mkdir()
    if layout == "a paper build only":   # --results results/quick/paper, the report's own folder
        (results / "tables").mkdir()
        (results / "report.md").write_text("# fitbench: comparison report\n")
    elif layout == "files only":
        (results / "meta.json").write_text("{}")
    out = tmp_path / "paper"
    assert report.main(["--results", str(results), "--out", str(out)]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"experiments.report: error: no study in {results} "), captured.err
    assert "experiments.run" in lines[0] and captured.out == ""
    assert not out.exists()


def test_a_folder_of_unfinished_studies_names_no_empty_command(tmp_path):
    results = tmp_path / "results"
    (results / "half").mkdir(parents=True)
    (results / "half" / "rows.sqlite").write_bytes(b"")
    assert report.main(["--results", str(results), "--out", str(tmp_path / "paper")]) == 0
    md = (tmp_path / "paper" / "report.md").read_text(encoding="utf-8")
    assert " with ." not in md and "so none can be reproduced from it" in md


def test_the_command_of_a_user_s_study_reads_as_written(tmp_path, monkeypatch):
    from experiments.run import main as run_main
    monkeypatch.chdir(tmp_path)
    cfg = tmp_path / "my_study.toml"
    cfg.write_text('name = "my_study"\ntitle = "a user study"\nseed = 1\nrepetitions = 1\n[[datasets]]\n'
                   'source = "circle"\nparams = { radius = 5.0, noise = 0.01, n = 12 }\n[[methods]]\n'
                   'id = "circle.kasa"\n', encoding="utf-8")
    assert run_main([str(cfg), "--jobs", "1", "--out", "out"]) == 0
    md = (tmp_path / "out" / "paper" / "report.md").read_text(encoding="utf-8")
    line = next(x for x in md.splitlines() if "reproduce it with" in x)
    assert "`python -m experiments.run my_study.toml --out out` (my_study.toml: the study's TOML file" in line, line
    assert "recorded in its `meta.json`)" in line and "\\`" not in line, line
    json.loads((tmp_path / "out" / "my_study" / "meta.json").read_text())
