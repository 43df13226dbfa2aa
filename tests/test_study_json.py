"""report.json and meta.json are JSON that any strict parser reads (jq, JavaScript's JSON.parse): a study's value that
is infinite or not a number is written as the text "Infinity", "-Infinity" or "NaN" (which Python's float() and
JavaScript's Number() read back), never as the bare literals Python's json module writes by default."""
from __future__ import annotations

import json
import math

import numpy as np

from experiments.run import run_study
from experiments.study import Analysis, Study
from study_kinds import plant, small_study

TOML = small_study("nonfinite", "a study with infinite values", "nonfinite_values",
                   findings="the ratio is {ratio:.3f}, the spread {spread}")


def strict(text: str):
    def refuse(name):
        raise ValueError(f"not JSON: {name}")
    return json.loads(text, parse_constant=refuse)


class NonFinite(Study):
    values = ("ratio", "spread", "low", "f32", "series", "fine")

    def analyse(self, rows, cfg, target, log):
        return Analysis(values={"ratio": math.inf, "spread": float("nan"), "low": np.float64(-np.inf),
                                "f32": np.float32(np.nan), "series": [1.5, math.inf, {"x": -math.inf}],
                                "fine": 2.5})


def test_infinite_values_are_written_as_json_texts(tmp_path, monkeypatch):
    plant(monkeypatch, "nonfinite_values", NonFinite=NonFinite)
    path = tmp_path / "nonfinite.toml"
    path.write_text(TOML, encoding="utf-8")
    target = run_study(str(path), tmp_path / "out", jobs=1, log=lambda *a: None)
    report = strict((target / "report.json").read_text())
    meta = strict((target / "meta.json").read_text())
    for values in (report["values"], meta["findings"]):
        assert values["ratio"] == "Infinity" and values["spread"] == "NaN" and values["low"] == "-Infinity"
        assert values["f32"] == "NaN" and values["series"] == [1.5, "Infinity", {"x": "-Infinity"}]
        assert values["fine"] == 2.5 and values["n_rows"] == 2
        assert float(values["low"]) == -math.inf  # read back by float()
    assert report["findings"] == "the ratio is inf, the spread nan"


def test_json_value_reads_the_non_finite_texts_back_as_floats():
    import math

    from experiments.jsontext import json_text, json_value
    value = {"k": [1.5, math.inf, {"x": -math.inf}], "n": math.nan, "label": "Infinity war", "s": "x"}
    back = json_value(json_text(value))
    assert back["k"] == [1.5, math.inf, {"x": -math.inf}] and math.isnan(back["n"])
    assert back["label"] == "Infinity war" and back["s"] == "x"


def test_a_text_that_reads_as_a_number_stays_a_text():
    """Only what json_text wrote as a number that is not finite is read back as a float: a label, a message or a value
    that is the text "NaN", "Infinity" or "-Infinity" stays that text (it is written escaped: "\\NaN")."""
    from experiments.jsontext import json_text, json_value
    value = {"label": "NaN", "msg": ["Infinity", "-Infinity"], "n": math.nan, "esc": "\\NaN", "x": -math.inf,
             "nested": {"source": "NaN", "ratio": math.inf}}
    text = json_text(value)
    strict(text)  # still strict JSON
    back = json_value(text)
    assert back["label"] == "NaN" and back["msg"] == ["Infinity", "-Infinity"] and back["esc"] == "\\NaN"
    assert back["nested"]["source"] == "NaN" and back["nested"]["ratio"] == math.inf and back["x"] == -math.inf
    assert math.isnan(back["n"])


class TextValues(Study):
    values = ("label", "ratio")

    def analyse(self, rows, cfg, target, log):
        return Analysis(values={"label": "NaN", "ratio": math.inf})


def test_report_and_meta_keep_texts_that_read_as_numbers(tmp_path, monkeypatch):
    """report.json and meta.json as the report reads them: a study value "NaN" and a data set labelled "Infinity" are
    texts, an infinite value a float."""
    from experiments.report import _read_json
    plant(monkeypatch, "text_values", TextValues=TextValues)
    path = tmp_path / "textvalues.toml"
    text = TOML.replace('"nonfinite"', '"textvalues"').replace('"nonfinite_values"', '"text_values"')
    text = text.replace('source = "circle"', 'source = "circle"\nlabel = "Infinity"')
    path.write_text(text.replace("the ratio is {ratio:.3f}, the spread {spread}", "{label}"), encoding="utf-8")
    target = run_study(str(path), tmp_path / "out", jobs=1, log=lambda *a: None)
    report, meta = _read_json(target / "report.json"), _read_json(target / "meta.json")
    for values in (report["values"], meta["findings"]):
        assert values["label"] == "NaN" and values["ratio"] == math.inf
    assert meta["config"]["datasets"][0]["label"] == "Infinity" and report["findings"] == "NaN"
    strict((target / "meta.json").read_text())
