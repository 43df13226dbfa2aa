"""A row's text that UTF-8 cannot encode (a method's message with a lone surrogate, from bytes decoded with
errors="surrogateescape" or a C extension) is made writable where the row is made: it crashed every run of the study
with a UnicodeEncodeError in results.csv, after the row was stored ``ok`` (so every rerun crashed too). A row stored
with such text by an older run is read and made writable as well."""
import json
import sqlite3
import textwrap

import numpy as np
import pandas as pd
import pytest

import methods
from experiments.run import main as run_main
from methods import results
from plugin_methods import registered

WEIRD = "ok\x00nul\r\n\"q\",c\u2028\ud800end é"
WRITTEN = "ok\x00nul\r\n\"q\",c\u2028\\ud800end é"   # the surrogate as its backslash escape, the rest as it was


def _weird(points):
    """Kåsa's fit with a message holding a lone surrogate."""
    res = methods.get("circle.kasa").func(points)
    return results.circle_result(points, np.asarray(res.center), float(res.radius), converged=True, message=WEIRD)


def _raises(points):
    raise ValueError("cannot read \udcff\udcfe")   # a file name decoded with surrogateescape


@pytest.fixture
def weird_methods():
    """Methods registered for this test only (a plugin's: not built-in)."""
    methods.list_methods()
    with registered({"circle.test_weird_message": _weird, "circle.test_weird_error": _raises}, kind="closed form",
                    summary="t", reference="test"):
        yield


STUDY = textwrap.dedent('''
    name = "weird"
    title = "weird"
    seed = 1
    repetitions = 2
    [[datasets]]
    source = "circle"
    params = { radius = 5.0, noise = 0.01, n = 30 }
    [[methods]]
    id = "circle.kasa"
    [[methods]]
    id = "circle.test_weird_message"
    [[methods]]
    id = "circle.test_weird_error"
''')


def _messages(folder):
    df = pd.read_csv(folder / "weird" / "results.csv", keep_default_na=False, encoding="utf-8")
    return dict(zip(df["method"], df["message"])), dict(zip(df["method"], df["status"]))


def test_a_message_with_a_surrogate_is_written_and_rerun(tmp_path, weird_methods, capsys):
    cfg = tmp_path / "weird.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    out = tmp_path / "out"
    for _ in range(2):   # the second run serves the rows from the store
        assert run_main([str(cfg), "--jobs", "1", "--out", str(out), "--no-report"]) == 0, capsys.readouterr().err
        messages, statuses = _messages(out)
        assert statuses == {"circle.kasa": "ok", "circle.test_weird_message": "ok", "circle.test_weird_error": "error"}
        assert messages["circle.test_weird_message"] == WRITTEN
        assert "cannot read \\udcff\\udcfe" in messages["circle.test_weird_error"]
        assert "Traceback" not in capsys.readouterr().err
    assert (out / "weird" / "meta.json").is_file()


def test_a_row_an_older_run_stored_with_a_surrogate_is_written(tmp_path, weird_methods, capsys):
    cfg = tmp_path / "weird.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    out = tmp_path / "out"
    assert run_main([str(cfg), "--jobs", "1", "--out", str(out), "--no-report"]) == 0, capsys.readouterr().err
    capsys.readouterr()
    with sqlite3.connect(out / "weird" / "rows.sqlite") as db:   # as an older run stored it (json.dumps escapes it)
        stored = db.execute("SELECT key, row FROM rows").fetchall()
        for key, text in stored:
            row = json.loads(text)
            if row["method"] == "circle.test_weird_message":
                row["message"] = WEIRD
                db.execute("UPDATE rows SET row = ? WHERE key = ?", (json.dumps(row), key))
    (out / "weird" / "results.csv").unlink()   # the outputs are made again from the stored rows
    assert run_main([str(cfg), "--jobs", "1", "--out", str(out), "--no-report"]) == 0, capsys.readouterr().err
    assert "6 rows: 4 already stored, 2 to run" in capsys.readouterr().out   # (the error rows are retried)
    assert _messages(out)[0]["circle.test_weird_message"] == WRITTEN


def test_the_text_helpers():
    from experiments.rows import bounded_message, row_from_json, writable_text
    assert writable_text(WEIRD) == WRITTEN and writable_text("plain é") == "plain é"
    assert bounded_message(WEIRD) == WRITTEN and bounded_message(None) is None
    assert bounded_message("\ud800" * 3000).endswith("[message cut: 18,000 characters in all]")
    assert row_from_json(json.dumps({"message": WEIRD, "radius": float("nan")})) == {"message": WRITTEN,
                                                                                      "radius": pytest.approx(np.nan,
                                                                                                              nan_ok=True)}
    WRITTEN.encode("utf-8")
