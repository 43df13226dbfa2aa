"""The row store refuses what is not a stored row: a row that is valid JSON but not an object (``[]``, ``1``, a text,
``null``) is a corrupt store, moved aside and recomputed in one line, as a row that is not JSON is."""
from __future__ import annotations

import sqlite3

import pandas as pd
import pytest

from experiments.store import RowStore
from results_csv import non_timing
from test_run_faults import run_here, study


@pytest.mark.parametrize("text", ["[]", "1", '"ok"', "null", " [1, 2]", "\n{}", "NaN", "[NaN]"])
def test_a_row_that_is_not_a_json_object_moves_the_store_aside(tmp_path, text):
    path = tmp_path / "rows.sqlite"
    store = RowStore(path)
    store.put_many(["a", "b"], [{"status": "ok", "radius": 1.0}, {"status": "ok", "radius": 2.0}])
    store.close()
    with sqlite3.connect(path) as db:
        db.execute("UPDATE rows SET row = ? WHERE key = 'b'", (text,))
    said = []
    store = RowStore(path, log=said.append)
    moved = list(tmp_path.glob("rows.sqlite.corrupt-*"))
    if text.strip().startswith("{"):  # an object: a row the store keeps
        assert not said and not moved and store.done(["a", "b"]) == {"a": "ok", "b": "ok"}
    else:
        assert len(said) == 1 and "moved aside" in said[0] and "not a JSON object" in said[0], said
        assert moved and store.empty()
    store.close()


def test_a_run_over_a_store_with_a_list_row_recomputes_it(tmp_path, monkeypatch, capsys):
    """The review's case: ``update rows set row = '[]'`` gave a traceback on every rerun."""
    cfg = study(tmp_path, reps=1)
    out = tmp_path / "out"
    assert run_here([cfg, "--jobs", "1", "--out", out, "--no-report"], tmp_path, monkeypatch, capsys).returncode == 0
    expected = non_timing(out / "faults" / "results.csv")
    with sqlite3.connect(out / "faults" / "rows.sqlite") as db:
        db.execute("UPDATE rows SET row = '[]'")
    for attempt in range(2):  # moved aside and recomputed once; the next run serves the recomputed rows
        again = run_here([cfg, "--jobs", "1", "--out", out, "--no-report"], tmp_path, monkeypatch, capsys)
        assert again.returncode == 0 and "Traceback" not in again.stderr, again.stderr
        said = [ln for ln in again.stdout.splitlines() if "moved aside" in ln]
        assert len(said) == (1 - attempt) and all("not a JSON object" in ln for ln in said), again.stdout
        pd.testing.assert_frame_equal(non_timing(out / "faults" / "results.csv"), expected)
    aside = [p for p in (out / "faults").glob("rows.sqlite.corrupt-*") if not p.name.endswith(("-wal", "-shm"))]
    assert len(aside) == 1


def test_a_new_store_has_large_pages_and_an_old_one_keeps_its_own(tmp_path):
    """New stores use PAGE_BYTES pages; a store made with SQLite's default pages opens with its rows and pages."""
    from experiments.store import PAGE_BYTES
    new = RowStore(tmp_path / "new.sqlite")
    new.put_many(["k"], [{"status": "ok", "x": 1.5}])
    assert new.db.execute("PRAGMA page_size").fetchone()[0] == PAGE_BYTES
    new.close()
    old_path = tmp_path / "old.sqlite"
    db = sqlite3.connect(old_path)
    db.execute("PRAGMA page_size=4096")
    db.execute("PRAGMA journal_mode=WAL")
    db.execute("CREATE TABLE rows (key TEXT PRIMARY KEY, status TEXT, row TEXT)")
    db.execute("INSERT INTO rows VALUES ('k', 'ok', '{\"status\": \"ok\", \"x\": 2.5}')")
    db.commit()
    db.close()
    old = RowStore(old_path)
    assert old.db.execute("PRAGMA page_size").fetchone()[0] == 4096
    assert old.get(["k"]) == [{"status": "ok", "x": 2.5}]
    old.close()
