"""A user's study is known by the TOML its ``meta.json`` records, not by its name: one named like a project study
(``noise.toml``) is rerun and verified from that TOML (before: ``experiments.verify --results OUT`` ran the project's
28,800-row noise study, and the report said ``python -m experiments.run noise``); the TOML is recorded relative to
the results folder when it lies beside it (no folder of the author's machine in a committed meta.json), and found
again after both are moved. The report's commands are code spans shown literally: a folder named ``R&D #1 [a] ~{b}!``
is not Markdown-escaped inside them (before: ``'R\\&D...'``, a path that does not exist).

The commands that report suggests for a user's own studies work: such a study is named by its TOML file
(``meta.json`` records it: ``config_file``), and ``python -m experiments.verify --results OUT`` checks it by running
that TOML (before: "unknown study 'my_study'", exit 2, for both commands the report gave)."""
import html
import json
import re
import shlex
import shutil

import pytest

from experiments import config as configs
from experiments import report, verify
from experiments import run as runner
from experiments.verdict import is_project_study, recorded_config

STUDY = ('name = "{name}"\ntitle = "a personal study"\nseed = 1\nrepetitions = 1\n[[datasets]]\nsource = "circle"\n'
         'label = "mine"\nparams = {{ radius = 5.0, noise = 0.01, n = 12 }}\n[[methods]]\nid = "circle.kasa"\n')
UNLABELLED = STUDY.replace('label = "mine"\n', "")   # its data set named by its source


def _run(*args):
    assert runner.main([*args, "--jobs", "1", "--no-report"]) == 0


def test_a_user_study_named_like_a_project_study_is_rerun_from_its_toml(tmp_path, monkeypatch, capsys):
    assert "noise" in configs.available()
    project = tmp_path / "project"
    project.mkdir()
    (project / "noise.toml").write_text(STUDY.format(name="noise"), encoding="utf-8")
    monkeypatch.chdir(project)
    _run("noise.toml", "--out", "res")
    known = configs.available()
    assert verify.config_of("noise", project / "res", known) == str((project / "noise.toml").resolve())
    assert report.study_command_names(project / "res", ["noise"], known) == {"noise": "noise.toml"}
    assert not is_project_study(project / "res" / "noise", known)
    report.build(project / "res", project / "res" / "paper", log=lambda *a: None)
    text = (project / "res" / "paper" / "report.md").read_text(encoding="utf-8")
    assert "reproduce it with `python -m experiments.run noise.toml --out res`" in text, text
    meta_text = (project / "res" / "noise" / "meta.json").read_text(encoding="utf-8")
    meta = json.loads(meta_text)
    assert (meta["config_file"], meta["config_file_relative_to"]) == ("../noise.toml", "results folder")
    assert str(tmp_path) not in meta_text
    # moved with its results folder (a clone of the user's repository elsewhere): still found, relative to it
    monkeypatch.chdir(tmp_path)
    shutil.move(project, tmp_path / "moved")
    assert recorded_config(tmp_path / "moved" / "res" / "noise") == (tmp_path / "moved" / "noise.toml").resolve()
    assert verify.config_of("noise", tmp_path / "moved" / "res", known) == str((tmp_path / "moved" / "noise.toml").resolve())


def test_the_project_s_own_record_and_an_older_meta_json_are_the_project_study(tmp_path):
    known = configs.available()
    for record in ({"config_file": "experiments/configs/noise.toml", "config_file_relative_to": "checkout"},
                   {"config_file": "experiments/configs/noise.toml"}, {}):
        folder = tmp_path / "res" / "noise"
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "meta.json").write_text(json.dumps({"quick": False, **record}), encoding="utf-8")
        assert is_project_study(folder, known), record
        assert verify.config_of("noise", tmp_path / "res", known) == "noise"


def test_a_toml_outside_the_current_and_the_results_folder_s_is_recorded_whole(tmp_path, monkeypatch):
    (tmp_path / "studies").mkdir()
    (tmp_path / "work").mkdir()
    (tmp_path / "studies" / "mine.toml").write_text(STUDY.format(name="mine"), encoding="utf-8")
    monkeypatch.chdir(tmp_path / "work")
    cfg = configs.load(str(tmp_path / "studies" / "mine.toml"))
    assert runner.config_file(cfg, tmp_path / "work" / "res") == {"config_file": str((tmp_path / "studies" / "mine.toml").resolve())}
    assert runner.config_file(cfg, tmp_path / "res") == {"config_file": "../studies/mine.toml",
                                                         "config_file_relative_to": "results folder"}
    monkeypatch.chdir(tmp_path)
    assert runner.config_file(cfg, tmp_path / "work" / "res") == {"config_file": "../../studies/mine.toml",
                                                                  "config_file_relative_to": "results folder"}


def test_the_report_s_commands_are_shown_literally(tmp_path, monkeypatch):
    folder = tmp_path / "R&D #1 [a] ~{b}!"
    folder.mkdir()
    (folder / "plain.toml").write_text(STUDY.format(name="plain"), encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    out = f"{folder.name}/res"
    _run(f"{folder.name}/plain.toml", "--out", out)
    report.build(tmp_path / out, tmp_path / out / "paper", log=lambda *a: None)
    md = (tmp_path / out / "paper" / "report.md").read_text(encoding="utf-8")
    page = (tmp_path / out / "paper" / "report.html").read_text(encoding="utf-8")
    spans = {"md": re.findall(r"(?:reproduce it with|reproducibility verdict: run) (`+) ?(.*?) ?\1", md),
             "html": [(None, html.unescape(c)) for c in re.findall(
                 r"(?:reproduce it with|reproducibility verdict: run) <code>(.*?)</code>", page)]}
    for kind, found in spans.items():
        commands = [shlex.split(c) for _, c in found]
        assert [c[:3] for c in commands] == [["python", "-m", "experiments.run"], ["python", "-m", "experiments.verify"]], (kind, found)
        assert commands[0][3:] == [f"{folder.name}/plain.toml", "--out", out], (kind, found)
        assert commands[1][3:] == ["--results", out, "--write-verdict"], (kind, found)
        assert (tmp_path / commands[0][3]).is_file()


def test_a_code_span_shows_any_text_as_it_is():
    """Backticks in the text: a longer fence, padded where the text starts or ends with one (CommonMark 6.1)."""
    from experiments.render.markdown import md_code
    from experiments.render.page import prose_html
    for text in ("a`b", "`x", "x``", " lead", "R&D #1 [a] ~{b}! <i> \\ *x* _y_ |", "my  data/plain.toml"):
        shown = re.fullmatch(r"<p><code>(.*)</code></p>", str(prose_html(md_code(text))).strip())
        assert shown and html.unescape(shown.group(1)) == text, (text, md_code(text))


def test_a_rerun_from_a_moved_toml_records_where_it_now_is(tmp_path, monkeypatch):
    """A study run again, up to date, from its TOML moved elsewhere: its rows come from the store, and meta.json
    names the TOML the run loaded (it kept naming the old place, which the report and verify then ran)."""
    import json

    from experiments import run
    monkeypatch.chdir(tmp_path)
    toml = tmp_path / "mine.toml"
    toml.write_text('name = "mine"\ntitle = "Mine"\nkind = "grid"\nseed = 3\nrepetitions = 2\n[[datasets]]\n'
                    'source = "circle"\nparams = { radius = 5.0, noise = 0.01, n = 12 }\n[[methods]]\nid = "circle.kasa"\n')
    assert run.main([str(toml), "--out", "res", "--jobs", "1", "--no-report"]) == 0
    (tmp_path / "sub").mkdir()
    moved = toml.rename(tmp_path / "sub" / "mine.toml")
    assert run.main([str(moved), "--out", "res", "--jobs", "1", "--no-report"]) == 0
    meta = json.loads((tmp_path / "res" / "mine" / "meta.json").read_text())
    assert meta["config_file"] == "../sub/mine.toml" and meta["config_file_relative_to"] == "results folder"


def test_a_symlinked_toml_of_another_name_is_recorded_as_the_link_given(tmp_path, monkeypatch):
    """``proj/noise.toml`` a link to ``drafts/noise-v3.toml`` beside an older ``drafts/noise.toml``: meta.json
    records the file the run was given (the link), and verify and the report's command run it again (they named the
    link's target folder plus the study's name, the older draft, which verify then reran)."""
    (tmp_path / "drafts").mkdir()
    (tmp_path / "proj").mkdir()
    (tmp_path / "drafts" / "noise-v3.toml").write_text(STUDY.format(name="noise").replace('"mine"', '"v3"'),
                                                       encoding="utf-8")
    (tmp_path / "drafts" / "noise.toml").write_text(STUDY.format(name="noise").replace('"mine"', '"old"'),
                                                    encoding="utf-8")
    (tmp_path / "proj" / "noise.toml").symlink_to(tmp_path / "drafts" / "noise-v3.toml")
    monkeypatch.chdir(tmp_path / "proj")
    _run("noise.toml", "--out", "res")
    meta = json.loads((tmp_path / "proj" / "res" / "noise" / "meta.json").read_text(encoding="utf-8"))
    assert (meta["config_file"], meta["config_file_relative_to"]) == ("../noise.toml", "results folder")
    known = configs.available()
    rerun = verify.config_of("noise", tmp_path / "proj" / "res", known)
    assert rerun == str(tmp_path.resolve() / "proj" / "noise.toml")
    assert configs.load(rerun)["datasets"][0]["label"] == "v3"
    assert report.study_command_names(tmp_path / "proj" / "res", ["noise"], known) == {"noise": "noise.toml"}
    # the link given by its absolute path, run from elsewhere: recorded whole, still the link
    monkeypatch.chdir(tmp_path / "drafts")
    cfg = configs.load(str(tmp_path / "proj" / "noise.toml"))
    assert runner.config_file(cfg, tmp_path / "elsewhere" / "res") == {
        "config_file": str(tmp_path.resolve() / "proj" / "noise.toml")}


@pytest.mark.slow
def test_the_commands_of_a_user_study_s_report_run(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "studies").mkdir()
    for name in ("my_study", "plug"):
        (tmp_path / "studies" / f"{name}.toml").write_text(UNLABELLED.format(name=name), encoding="utf-8")
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
