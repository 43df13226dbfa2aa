"""``meta.json`` is written by ``experiments.jsontext.json_text`` (a text "NaN" as "\\NaN", an infinite number as
"Infinity"), so every reader reads it back with ``json_value``: a study whose config holds the text "NaN",
"Infinity" or "-Infinity" (a label) is compared with its previous run (before: read raw, its recorded inputs never
equalled the run's, and the rerun said "not compared: ... of another config or data")."""
import json

from experiments import compare
from experiments import config as configs
from experiments import run as runner
from experiments.jsontext import json_text

DATASET = ('[[datasets]]\nsource = "circle"\nlabel = "{}"\n'
           'params = {{ center = [1.0, 2.0], radius = 5.0, noise = 0.01, n = 12 }}\n')
STUDY = ('name = "lab"\ntitle = "lab"\nseed = 3\nrepetitions = 2\n'
         + "".join(DATASET.format(label) for label in ("NaN", "Infinity", "-Infinity")) + '[[methods]]\nid = "circle.kasa"\n')


def test_a_study_labelled_nan_is_compared_with_its_previous_run(tmp_path, capsys):
    toml = tmp_path / "lab.toml"
    toml.write_text(STUDY, encoding="utf-8")
    out = tmp_path / "out"
    for _ in range(2):
        assert runner.main([str(toml), "--out", str(out), "--jobs", "1", "--no-report", "--force"]) == 0
    printed = capsys.readouterr().out
    assert "lab: reproduces the previous results" in printed, printed
    assert "not compared" not in printed, printed
    meta = (out / "lab" / "meta.json").read_text(encoding="utf-8")
    assert '"\\\\NaN"' in meta   # the escaped text the readers must undo


def test_the_recorded_inputs_of_a_text_nan_equal_the_run_s(tmp_path):
    """The reference of a rerun: the recorded inputs (as json_text wrote them) are the run's inputs."""
    toml = tmp_path / "lab.toml"
    toml.write_text(STUDY, encoding="utf-8")
    cfg = configs.load(str(toml))
    folder = tmp_path / "out" / "lab"
    folder.mkdir(parents=True)
    (folder / "results.csv").write_text("study,status\nlab,ok\n", encoding="utf-8")
    (folder / "meta.json").write_text(json_text({"quick": False, "inputs": compare.inputs(cfg)}), encoding="utf-8")
    refs = compare.reference_snapshot(tmp_path / "out", ["lab"], False, tmp_path / "ref",
                                      {"lab": compare.inputs(cfg)})
    assert "other" not in refs["lab"] and refs["lab"]["folder"] == tmp_path / "ref", refs
    assert json.loads((tmp_path / "ref" / "lab" / "meta.json").read_text(encoding="utf-8"))["quick"] is False
