"""The engine at scale and its isolation: keys computed once per run, rows in chunks with the same rows
whatever the chunking and the executor, a frame built a block at a time with the types of one frame, time
limits, crashes and exits labelled and never cached, environment failures stopped in one line, the row
store's I/O errors told from corruption, the --out lock, a long --out, limits before expansion, progress.

The hostile methods live in a plugin distribution built offline (:func:`conftest.install_plugin`), so that
worker processes (spawned: they import everything afresh) find them too."""
from __future__ import annotations

import fcntl
import json
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import install_plugin, subprocess_env
from experiments import codehash, codekeys, engine, executors, rows as row_code, run
from experiments.rowframe import MissingRows, RowFrame, part_of
from experiments.store import RowStore, StoreIOError
from methods import InvalidInputError

STUDY = '''name = "{name}"
title = "engine test study"
kind = "grid"
seed = 5
repetitions = {reps}
{extra}
[[datasets]]
source = "circle"
params = {{ center = [1.0, 2.0], radius = 5.0, noise = 0.01, n = 20 }}
grid = {{ arc_deg = [360.0, 90.0] }}
{methods}'''

KASA_GN = '[[methods]]\nid = "circle.kasa"\n[[methods]]\nid = "circle.gauss_newton"\n'


def write_study(folder: Path, name="eng", reps=3, methods=KASA_GN, extra="") -> Path:
    path = folder / f"{name}.toml"
    path.write_text(STUDY.format(name=name, reps=reps, methods=methods, extra=extra))
    return path


def non_timing(df: pd.DataFrame) -> pd.DataFrame:
    return df[[c for c in df.columns if not c.startswith("time_")]]


# ---------------------------------------------------------------- keys, chunks, columns, frames

def test_code_is_hashed_once_per_pair_not_per_row(tmp_path, monkeypatch):
    """A run of N rows hashes the code of each (method, data set) pair once (it hashed it for every row)."""
    cfg = run.configs.load(str(write_study(tmp_path, reps=200)))
    codekeys.reset_caches()
    calls = []
    original = codehash.code_hash

    def counting(*modules):
        calls.append(modules)
        return original(*modules)
    monkeypatch.setattr(codehash, "code_hash", counting)
    tasks = list(engine.iter_grid_tasks(cfg, cfg.where, keyed=True))
    assert len(tasks) == 2 * 200 * 2
    assert 0 < len(calls) <= 4 * 5  # 4 pairs x (method, source, metrics, rows, study) at most, whatever the rows
    # the fast keys are the keys of the general rule
    assert all(t["key"] == engine.task_key(t) for t in tasks[:50])
    assert len({t["key"] for t in tasks}) == len(tasks)


def test_kernel_backend_and_versions_are_in_the_key(tmp_path, monkeypatch):
    cfg = run.configs.load(str(write_study(tmp_path, reps=1)))
    task = next(engine.iter_grid_tasks(cfg, cfg.where))
    codekeys.reset_caches()
    compiled = engine.task_key(task)
    assert codekeys.environment()["kernels"] == "compiled" and codekeys.environment()["versions"]["numpy"]
    monkeypatch.setenv("FITBENCH_KERNELS", "numpy")
    codekeys.reset_caches()
    assert codekeys.environment()["kernels"] == "numpy"
    assert engine.task_key(task) != compiled
    monkeypatch.delenv("FITBENCH_KERNELS")
    codekeys.reset_caches()
    assert engine.task_key(task) == compiled


def test_rows_come_back_encoded_for_the_store(tmp_path):
    rows = [{"a": 1, "status": "ok", "c": None}, {"a": 2.5, "d": True, "status": "error"}]
    batch = row_code.encode_rows(rows)
    assert batch["status"] == ["ok", "error"]
    store = RowStore(tmp_path / "rows.sqlite", log=lambda *a: None)
    store.put_encoded(["k1", "k2"], batch["status"], batch["row"])
    assert store.get(["k1", "k2"]) == rows and store.done(["k1", "k2"]) == {"k1": "ok", "k2": "error"}
    store.close()


def _rows_of_every_kind():
    rng = np.random.default_rng(1)
    rows = []
    for i in range(60):
        failed = 20 <= i < 40
        rows.append({"status": "error" if failed else "ok", "radius": None if failed else float(rng.normal()),
                     "iterations": None if failed else int(i), "converged": None if failed else bool(i % 2),
                     **({} if i < 50 else {"extra": 0.1 * i}), **({"first": i} if i < 10 else {}),
                     "label": str(i % 3), "flag": None if i % 7 == 0 else True,
                     "mixed": "text" if i % 13 == 0 else 1.5 * i, "count": i if i < 30 else i + 0.5,
                     **({"only_ints": i} if i % 2 else {}), "task_index": i})
    return rows


@pytest.mark.parametrize("size", [1, 13, 60])
@pytest.mark.parametrize("order", ["in order", "reversed", "shuffled"])
def test_frame_of_parts_is_the_frame_of_all_rows(order, size):
    """Chunks of rows finish in any order (several workers, rows run again after a crash) and a block where every row
    failed holds None where others hold floats, ints or bools: the frame of the parts must equal the frame of all rows
    in task order (else results.csv writes a float column as ints, or puts the columns in another order)."""
    rows = _rows_of_every_kind()
    whole = pd.DataFrame([{k: v for k, v in r.items() if k != "task_index"} for r in rows])
    chunks = [rows[i:i + size] for i in range(0, 60, size)]
    if order == "reversed":
        chunks = chunks[::-1]
    elif order == "shuffled":
        chunks = [chunks[i] for i in np.random.default_rng(3).permutation(len(chunks))]
    frame = RowFrame(60)
    for chunk in chunks:
        frame.add(part_of(chunk))
    built = frame.frame()
    pd.testing.assert_frame_equal(whole, built)
    assert whole.to_csv(index=False, float_format="%.17g") == built.to_csv(index=False, float_format="%.17g")


@pytest.mark.parametrize("size", [1, 7, 40])
def test_chunks_of_rows_with_the_same_columns_make_the_frame_of_all_rows(size):
    """A chunk whose rows have the same columns in the same order (the rows of results) is transposed at once and its
    columns of one number type are made without pandas' inference: the frame still equals the frame of all rows."""
    rows = [{"ok": float(i) / 3, "i": i, "big": 2 ** 70 + i if i % 2 else i, "b": bool(i % 3), "s": f"t{i % 4}",
             "f_none": None if i % 5 == 0 else 0.5 * i, "s_none": None if i % 6 == 0 else "x", "ints_floats": i if i % 2
             else i + 0.25, "nan": float("nan") if i % 4 == 0 else -0.0, "none": None, "b_none": None if i < 20 else True,
             "task_index": i} for i in range(40)]
    whole = pd.DataFrame([{k: v for k, v in r.items() if k != "task_index"} for r in rows])
    frame = RowFrame(40)
    for i in range(0, 40, size):
        frame.add(part_of(rows[i:i + size]))
    built = frame.frame()
    pd.testing.assert_frame_equal(whole, built)
    assert whole.to_csv(index=False, float_format="%.17g") == built.to_csv(index=False, float_format="%.17g")
    assert part_of([{"a": 1.0, "task_index": 0}, {"a": [1], "task_index": 1}]) is None  # not plain: no part
    assert part_of([{"a": 1.0, "task_index": None}]) is None  # no task index: no place in a frame


def test_a_task_run_twice_keeps_its_last_row_and_a_missing_row_is_refused():
    rows = _rows_of_every_kind()
    frame = RowFrame(60)
    frame.add(part_of(rows[:30]))
    frame.add(part_of([{**rows[5], "status": "again", "radius": None}]))  # its radius is gone with its first row
    frame.add(part_of(rows[30:]))
    built = frame.frame()
    assert len(built) == 60 and built["status"][5] == "again" and np.isnan(built["radius"][5])
    assert built["radius"][6] == rows[6]["radius"] and built["radius"].dtype == np.float64
    short = RowFrame(60)
    short.add(part_of(rows[:59]))
    with pytest.raises(MissingRows, match="1 rows are missing"):
        short.frame()


def test_a_row_with_a_list_has_no_part_and_is_read_from_its_json():
    rows = [{"a": [1, 2], "task_index": 0}, {"a": 1.5, "task_index": 1}]
    assert part_of(rows) is None
    batch = row_code.encode_rows(rows)
    frame = RowFrame(2)
    frame.add_rows([row_code.row_from_json(text) for text in batch["row"]])
    assert frame.frame()["a"].tolist() == [[1, 2], 1.5]


def test_single_row_parts_keep_no_piece_and_equal_texts_are_one_object():
    """A slow study sends its rows one chunk of one row at a time, and every row's message is its own string: the frame
    holds each column in one array of all rows (no Series per chunk) and each distinct text once (a 160,000-row study
    held 80,000 copies of a few thousand certificate messages, about a third of its peak memory)."""
    frame = RowFrame(12_000)
    for i in range(12_000):
        frame.add(part_of([{"a": float(i), "b": "".join(["message ", str(i % 7)]), "c": f"label {i}",
                            **({"late": 1.0} if i >= 6000 else {}), "task_index": i}]))
    assert set(frame.numbers) == {"a", "late"} and set(frame.objects) == {"b", "c"}
    assert all(len(values) == 12_000 for values, _ in [*frame.numbers.values(), *frame.objects.values()])
    assert frame.shared["c"] is None  # mostly distinct texts: no table of them is kept
    built = frame.frame()
    assert len(built) == 12_000 and built["late"].isna().sum() == 6000 and list(built.columns) == ["a", "b", "c", "late"]
    assert built["a"].dtype == np.float64 and built["a"].tolist() == [float(i) for i in range(12_000)]
    assert built["b"].tolist() == [f"message {i % 7}" for i in range(12_000)]
    assert len({id(text) for text in built["b"].to_numpy(dtype=object)}) == 7
    assert built["c"].tolist() == [f"label {i}" for i in range(12_000)]


def test_the_last_chunks_shrink_so_that_no_worker_waits_long_for_another():
    chunks = executors.Chunks(iter(range(100_000)), workers=2, total=100_000)
    chunks.measured(10, 10 * 20e-6)  # 20 us a row: chunks of max_rows
    sizes = []
    while (chunk := chunks.next()) is not None:
        sizes.append(len(chunk))
    assert sum(sizes) == 100_000 and sizes[0] == executors.Chunks.max_rows
    left = 100_000
    for size in sizes:  # never more than a quarter of what was left (half of it per worker, two workers)
        assert size <= max(1, -(-left // 4))
        left -= size
    assert sizes[-1] == 1 and len(sizes) < 60
    one = executors.Chunks(iter(range(1000)), workers=1, total=1000)  # one worker: nothing to balance
    one.measured(10, 10 * 20e-6)
    assert len(one.next()) == 1000


def test_chunk_size_follows_the_measured_cost_of_a_row():
    chunks = executors.Chunks(iter(range(100_000)))
    sizes = [len(chunks.next()) for _ in range(3)]
    assert sizes == [4, 8, 16]  # growing until a cost is measured
    chunks.measured(10, 10 * 20e-6)  # 20 us a row
    assert chunks.size == executors.Chunks.max_rows
    chunks.measured(2, 2 * 2.0)  # slow rows: one at a time
    assert chunks.size == 1
    declared = executors.Chunks(iter(range(100)), declared=7)
    declared.measured(7, 7 * 1e-6)
    assert len(declared.next()) == 7
    declared.again([1, 2])
    assert declared.next() == [1] and declared.next() == [2]


def test_progress_reports_rows_per_second_and_eta(monkeypatch):
    lines = []
    now = [100.0]
    monkeypatch.setattr(executors.time, "monotonic", lambda: now[0])
    bar = executors.Progress(10_000, "big", log=lines.append)
    bar.bar.disable = True
    now[0] += 11.0
    bar.update(2_200)
    bar.close()
    assert len(lines) == 1
    assert "2,200/10,000 rows (22%)" in lines[0] and "200 rows/s" in lines[0] and "ETA 39 s" in lines[0]


@pytest.mark.parametrize("done, seconds, rate", [(3, 11.0, "3.7 s/row"), (3, 200.0, "67 s/row"), (12, 11.0, "1.1 rows/s"),
                                                 (50, 11.0, "4.5 rows/s"), (9, 36.0, "4.0 s/row")])
def test_progress_of_slow_rows_reads_as_seconds_per_row(monkeypatch, done, seconds, rate):
    """Under 10 rows/s the rate keeps its digits (was '0 rows/s' and '1 rows/s'); under 1 row/s it is seconds a row."""
    lines = []
    now = [100.0]
    monkeypatch.setattr(executors.time, "monotonic", lambda: now[0])
    bar = executors.Progress(100, "slow", log=lines.append)
    bar.bar.disable = True
    now[0] += seconds
    bar.update(done)
    bar.close()
    assert lines == [f"   slow: {done}/100 rows ({done}%), {rate}, ETA {executors._duration((100 - done) * seconds / done)}"]


def test_generic_chunks_give_the_rows_of_single_rows(tmp_path):
    """In-process chunks of any size give the same rows as one row at a time."""
    cfg = run.configs.load(str(write_study(tmp_path, reps=5)))
    make = run.task_source(cfg, run.contract.study_of("grid"), 10**6)
    frames = []
    for size, folder in ((1, "a"), (7, "b")):
        store = RowStore(tmp_path / folder / "rows.sqlite", log=lambda *a: None)
        df, counts = engine.run(make, store, force=False, jobs=1, executor="local", scheduler=None, desc="t",
                                log=lambda *a: None, chunk_rows=size)
        store.close()
        assert counts["to_run"] == 20 and len(df) == 20
        frames.append(df)
    pd.testing.assert_frame_equal(frames[0], frames[1])


# ---------------------------------------------------------------- a re-run of a study that is up to date

def _stamps(folder: Path) -> dict:
    return {p.name: p.stat().st_mtime_ns for p in folder.rglob("*") if p.is_file() and "rows.sqlite" not in p.name}


def test_a_rerun_of_an_unchanged_study_rewrites_nothing_and_any_change_runs_it_again(tmp_path):
    """All rows stored under the same keys and the outputs those of the same code: the re-run rewrites nothing. A
    missing table, a row another program changed in the store, --force: the study is analysed again."""
    study = str(write_study(tmp_path, reps=3))
    out = tmp_path / "out"
    target = out / "eng"
    logs: list[str] = []
    run.run_study(study, out, log=logs.append)
    assert "up to date" not in "\n".join(logs)
    first = _stamps(target)
    logs.clear()
    run.run_study(study, out, log=logs.append)
    assert any("12 rows: 12 already stored, 0 to run; results.csv, tables and figures up to date" in line
               for line in logs), logs
    assert _stamps(target) == first  # nothing rewritten
    (target / "summary.md").unlink()
    logs.clear()
    run.run_study(study, out, log=logs.append)
    assert not any("up to date" in line for line in logs) and (target / "summary.md").is_file()
    assert engine.up_to_date(run.configs.load(study), run.task_source(run.configs.load(study),
                             run.contract.study_of("grid"), 10**6), target) == 12
    with sqlite3.connect(target / "rows.sqlite") as con:  # another program adds a row to the store
        con.execute("INSERT INTO rows VALUES ('other', 'ok', '{}')")
    logs.clear()
    run.run_study(study, out, log=logs.append)
    assert any("12 rows: 12 already stored, 0 to run" in line and "up to date" not in line for line in logs), logs
    logs.clear()
    run.run_study(study, out, log=logs.append)
    assert any("up to date" in line for line in logs), logs
    logs.clear()
    run.run_study(study, out, force=True, log=logs.append)
    assert any("12 rows: 0 already stored, 12 to run" in line for line in logs), logs
    (target / "rows.sqlite").write_bytes(b"not a database")  # a store that is not one: moved aside, said, recomputed
    for extra in ("-wal", "-shm"):
        (target / f"rows.sqlite{extra}").unlink(missing_ok=True)
    logs.clear()
    run.run_study(study, out, log=logs.append)
    assert any("not a readable row store" in line for line in logs) and any("0 already stored" in line for line in logs)


def test_a_study_with_rows_to_run_again_or_another_config_is_not_up_to_date(tmp_path):
    study = write_study(tmp_path, reps=2)
    out = tmp_path / "out"
    run.run_study(str(study), out, log=lambda *a: None)
    cfg = run.configs.load(str(study))
    make = run.task_source(cfg, run.contract.study_of("grid"), 10**6)
    assert engine.up_to_date(cfg, make, out / "eng") == 8
    meta = json.loads((out / "eng" / "meta.json").read_text())
    (out / "eng" / "meta.json").write_text(json.dumps({**meta, "status_counts": {"ok": 7, "error": 1}}))
    assert engine.up_to_date(cfg, make, out / "eng") is None  # an error row is retried on every run
    (out / "eng" / "meta.json").write_text(json.dumps(meta))
    assert engine.up_to_date(cfg, make, out / "eng") == 8
    study.write_text(study.read_text().replace('title = "engine test study"', 'title = "another title"'))
    cfg = run.configs.load(str(study))
    assert engine.up_to_date(cfg, make, out / "eng") is None  # the same rows, but outputs of another config


def test_an_installed_plugins_code_is_part_of_a_studys_outputs(tmp_path, monkeypatch):
    """A plugin may register plots the analysis draws: installing one, or editing its code, makes a study's outputs
    out of date."""
    cfg = run.configs.load(str(write_study(tmp_path)))
    codekeys.reset_caches()
    without = engine.outputs_code(cfg)
    site = install_plugin(tmp_path, "fitbench-outputs-probe", {"fitbench_outputs_probe": "X = 1\n"},
                          {"fitbench.methods": {"probe": "fitbench_outputs_probe"}})
    monkeypatch.syspath_prepend(str(site))
    codekeys.reset_caches()
    installed = engine.outputs_code(cfg)
    (site / "fitbench_outputs_probe.py").write_text("X = 2\n")
    codekeys.reset_caches()
    edited = engine.outputs_code(cfg)
    codekeys.reset_caches()
    assert len({without, installed, edited}) == 3


def test_the_row_store_forgets_a_complete_study_when_any_program_changes_its_rows(tmp_path):
    store = RowStore(tmp_path / "rows.sqlite", log=lambda *a: None)
    store.put_encoded(["a", "b"], ["ok", "ok"], ["{}", "{}"])
    changes = ["INSERT INTO rows VALUES ('c', 'ok', '{}')", "INSERT OR REPLACE INTO rows VALUES ('a', 'ok', '{}')",
               "UPDATE rows SET status = 'error' WHERE key = 'b'", "DELETE FROM rows WHERE key = 'a'"]
    for sql in changes:
        store.mark_complete("fp", 2)
        assert store.complete("fp") == 2 and store.complete("other") is None
        with sqlite3.connect(tmp_path / "rows.sqlite") as con:
            con.execute(sql)
        assert store.complete("fp") is None, sql
    store.mark_complete("fp", 2)
    store.put_encoded(["d"], ["ok"], ["{}"])
    assert store.complete("fp") is None
    store.close()


def test_the_import_scan_cache_gives_the_closure_of_a_fresh_parse(tmp_path, monkeypatch):
    """The code hashes' import closure from cached scans (by the module's name and bytes) is that of parsing every
    file; a cached run parses nothing; a file whose bytes changed is parsed again."""
    monkeypatch.setattr(codehash, "SCAN_CACHE", tmp_path / "cache" / "import-scan.json")

    def fresh():
        codehash._SCANNED.clear()
        codehash._SCAN_STATE.update(loaded=False, new=0)
        codehash.module_closure.cache_clear()
        codehash.code_hash.cache_clear()
    fresh()
    parsed = codehash.files_of("experiments.run"), codehash.code_hash("experiments.run")
    assert (tmp_path / "cache" / "import-scan.json").is_file()
    fresh()
    calls = []
    real_parse = codehash.ast.parse
    monkeypatch.setattr(codehash.ast, "parse", lambda *a, **k: calls.append(a) or real_parse(*a, **k))
    assert (codehash.files_of("experiments.run"), codehash.code_hash("experiments.run")) == parsed
    assert calls == []
    module = tmp_path / "scanned_mod.py"
    module.write_text("import json\n")
    assert codehash._scan(module, "scanned_mod")[0] == ["json"]
    module.write_text("import csv\n")
    assert codehash._scan(module, "scanned_mod")[0] == ["csv"] and len(calls) == 2
    fresh()


# ---------------------------------------------------------------- limits before expansion, --out

def test_a_huge_study_is_refused_before_it_is_expanded(tmp_path, capsys):
    """start_directions = 20,000,000 in the convergence study: refused from the grid sizes at once (it built
    1.4e9 tasks first); one line, exit 2."""
    src = (run.configs.CONFIG_DIR / "convergence.toml").read_text()
    big = tmp_path / "conv_big.toml"
    big.write_text(src.replace('name = "convergence"', 'name = "conv_big"')
                   .replace("start_directions = 8", "start_directions = 20000000"))
    assert "20000000" in big.read_text()
    assert run.main([str(big), "--out", str(tmp_path / "out"), "--no-report"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "more than the limit" in err[0]
    assert not (tmp_path / "out" / "conv_big").exists()


def test_lazy_task_lists_are_counted_while_made(tmp_path):
    cfg = run.configs.StudyConfig({}, where="x.toml", folder=tmp_path)
    with pytest.raises(run.configs.ConfigError, match="more than 5"):
        list(run._limited(iter(range(10**12)), cfg, 5))


def test_a_busy_out_folder_is_one_line(tmp_path, capsys):
    study = write_study(tmp_path, reps=1)
    out = tmp_path / "out"
    out.mkdir()
    with open(out / run.LOCK_NAME, "a+") as fh:  # another run holds the folder
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        fh.write("pid 4242")
        fh.flush()
        assert run.main([str(study), "--out", str(out), "--jobs", "1", "--no-report"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "in use by another experiments.run" in err[0] and "pid 4242" in err[0]
    assert not (out / "eng").exists()


def test_a_300_character_out_is_one_line(tmp_path, capsys):
    study = write_study(tmp_path, reps=1)
    assert run.main([str(study), "--out", str(tmp_path / ("o" * 300)), "--jobs", "1", "--no-report"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "characters) cannot be written (File name too long)" in err[0]


# ---------------------------------------------------------------- the row store: I/O errors are not corruption

def test_an_io_error_does_not_move_a_healthy_store_aside(tmp_path, monkeypatch):
    path = tmp_path / "rows.sqlite"
    store = RowStore(path, log=lambda *a: None)
    store.put_many(["k1", "k2"], [{"status": "ok", "x": 1}, {"status": "ok", "x": 2}])
    store.close()

    def failing(p):
        raise sqlite3.OperationalError("disk I/O error")
    monkeypatch.setattr(RowStore, "_open", staticmethod(failing))
    with pytest.raises(StoreIOError, match="I/O error.*kept"):
        RowStore(path, log=lambda *a: None)
    monkeypatch.undo()
    assert not list(tmp_path.glob("*.corrupt-*"))
    assert RowStore(path).get(["k1", "k2"]) == [{"status": "ok", "x": 1}, {"status": "ok", "x": 2}]


def test_a_full_disk_is_one_line_and_a_real_corruption_still_moves_aside(tmp_path):
    path = tmp_path / "rows.sqlite"
    store = RowStore(path, log=lambda *a: None)

    class Full:
        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def executemany(self, *a):
            raise sqlite3.OperationalError("database or disk is full")
    store.db, real = Full(), store.db
    with pytest.raises(StoreIOError, match="the disk is full"):
        store.put_many(["k"], [{"status": "ok"}])
    real.close()
    path.write_bytes(b"this is not a database" * 100)
    for suffix in ("-wal", "-shm"):
        Path(str(path) + suffix).unlink(missing_ok=True)
    said = []
    RowStore(path, log=said.append).close()
    assert len(list(tmp_path.glob("rows.sqlite.corrupt-*"))) == 1 and "moved aside" in said[0]


# ---------------------------------------------------------------- isolation: hostile methods

HOSTILE = '''
"""Methods that misbehave on purpose (engine isolation tests)."""
import os
import signal
import threading
import time

from methods import register
from methods.results import circle_result


@register("circle.hostile", kind="closed form", summary="misbehaves on purpose", reference="fitbench tests")
def hostile(points, *, what="ok"):
    """Return the centroid circle, or hang, exit, raise SystemExit / KeyboardInterrupt, as asked."""
    if what == "hang":
        while True:
            time.sleep(0.01)
    if what == "slow":
        time.sleep(2.5)
    if what == "hang_in_c":  # a row that neither the alarm nor an exception raised in its thread can end
        if threading.current_thread() is threading.main_thread():  # a Dask worker runs rows in a thread
            signal.signal(signal.SIGALRM, signal.SIG_IGN)
        time.sleep(600)
    if what == "exit":
        os._exit(3)
    if what == "kill_worker":  # SIGKILL to the process two up: on Dask, the worker above the row process that forked
        with open(f"/proc/{os.getppid()}/stat") as fh:  # this row (a plugin acting on other processes: not protected)
            os.kill(int(fh.read().rsplit(")", 1)[1].split()[1]), 9)
        time.sleep(60)
    if what == "sysexit":
        raise SystemExit(4)
    if what == "kbint":
        raise KeyboardInterrupt
    if what == "no_kernel":
        from methods._compiled import KernelsNotBuiltError
        raise KernelsNotBuiltError("fitbench's compiled kernel methods.circle._ckernels is not built (test)")
    c = points.mean(axis=0)
    return circle_result(points, c, float(((points - c) ** 2).sum(axis=1).mean() ** 0.5), converged=True,
                         message="centroid")
'''


@pytest.fixture(scope="module")
def hostile_site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("hostile"), "fitbench-hostile", {"fitbench_hostile": HOSTILE},
                          {"fitbench.methods": {"hostile": "fitbench_hostile"}})


def cli(args, cwd, site, timeout=600):
    return subprocess.run([sys.executable, "-m", "experiments.run", *map(str, args), "--no-report"], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout,
                          env=subprocess_env(site, OPENBLAS_NUM_THREADS="1"))


def hostile_methods(*whats):
    return KASA_GN + "".join(f'[[methods]]\nid = "circle.hostile"\nparams = {{ what = "{w}" }}\n' for w in whats)


@pytest.mark.system  # ~15-30 s each: every hostile row waits for its time limit (twice with --jobs 2: run and rerun)
@pytest.mark.parametrize("jobs", ["1", "2"])
def test_hangs_exits_and_interrupts_are_labelled_and_the_study_goes_on(tmp_path, hostile_site, jobs):
    """A method that hangs is ``timeout``; one that os._exit()s, raises SystemExit or KeyboardInterrupt is
    ``crashed``; the other rows are ok, results.csv is written, exit 0. A rerun (once, with --jobs 2: what is
    rerun is decided before any row runs, whatever the jobs) recomputes exactly the labelled rows (never served
    from the cache)."""
    study = write_study(tmp_path, reps=1, methods=hostile_methods("hang", "hang_in_c", "exit", "sysexit", "kbint"))
    # one data set (a full circle): each hostile row waits for its limit, and a second data set only doubled the wait
    study.write_text(study.read_text().replace("arc_deg = [360.0, 90.0]", "arc_deg = [360.0]"))
    out = tmp_path / "out"
    jobs = ["--jobs", jobs]
    res = cli([study, *jobs, "--row-timeout", "1", "--out", out], tmp_path, hostile_site)
    assert res.returncode == 0, res.stderr
    df = pd.read_csv(out / "eng" / "results.csv")
    what = df["param_what"].fillna("")
    status = dict(zip(zip(what, df.index), df["status"]))
    assert set(df.loc[what == "", "status"]) == {"ok"}
    assert set(df.loc[what.isin(["hang", "hang_in_c"]), "status"]) == {"timeout"}
    assert set(df.loc[what.isin(["exit", "sysexit", "kbint"]), "status"]) == {"crashed"}, status
    assert set(df.loc[what == "exit", "message"]) == {"the process running this row ended (exit code 3)"}  # the same words on Dask (test_dask_executor)
    assert set(df.loc[what == "hang_in_c", "message"]) == {"the row ran longer than its limit of 1 s (the process running it was ended)"}
    assert df.loc[what == "sysexit", "message"].str.contains("SystemExit").all()
    meta = json.loads((out / "eng" / "meta.json").read_text())
    assert meta["row_timeout_s"] == 1 and meta["environment"]["kernels"] == "compiled"
    if jobs[1] == "1":
        return
    again = cli([study, *jobs, "--row-timeout", "1", "--out", out], tmp_path, hostile_site)
    assert again.returncode == 0, again.stderr
    assert f"{len(df) - (what == '').sum()} to run" in again.stdout


@pytest.mark.slow
def test_a_row_running_long_without_a_time_limit_is_named_once(tmp_path, hostile_site):
    """A method that hangs froze the progress line with no word when no time limit was set: the run names each row
    that has been running for STUCK_NOTICE_S seconds (60 s; 1 s here, the rows take 2.5 s), once, and says what would
    end it."""
    study = write_study(tmp_path, name="eng4", reps=1, methods=hostile_methods("slow"))
    code = ("import sys; import experiments.executors as e; e.STUCK_NOTICE_S = 1.0; from experiments import run; "
            "sys.exit(run.main(sys.argv[1:]))")
    res = subprocess.run([sys.executable, "-c", code, str(study), "--jobs", "2", "--out", str(tmp_path / "o"),
                          "--no-report"], cwd=tmp_path, capture_output=True, text=True, timeout=600,
                         env=subprocess_env(hostile_site, OPENBLAS_NUM_THREADS="1"))
    assert res.returncode == 0, res.stderr
    named = [line for line in res.stdout.splitlines() if "a row has been running for" in line]
    assert len(named) == 2, res.stdout  # the study's two slow rows (one per data set), each named once
    assert "circle.hostile on " in named[0] and "--row-timeout SECONDS" in named[0]


@pytest.mark.slow
def test_a_study_default_time_limit_and_sysexit_in_process(tmp_path, hostile_site):
    """``row_timeout`` in the TOML isolates --jobs 1 in a child; without a limit --jobs 1 runs in this process,
    where SystemExit and KeyboardInterrupt of a method are still ``crashed``."""
    study = write_study(tmp_path, name="eng2", reps=1, methods=hostile_methods("hang", "sysexit", "kbint"),
                        extra="row_timeout = 1\n")
    res = cli([study, "--jobs", "1", "--out", tmp_path / "a"], tmp_path, hostile_site)
    assert res.returncode == 0, res.stderr
    df = pd.read_csv(tmp_path / "a" / "eng2" / "results.csv")
    assert sorted(df["status"].unique()) == ["crashed", "ok", "timeout"]
    plain = write_study(tmp_path, name="eng3", reps=1, methods=hostile_methods("sysexit", "kbint"))
    res = cli([plain, "--jobs", "1", "--out", tmp_path / "b"], tmp_path, hostile_site)
    assert res.returncode == 0, res.stderr
    df = pd.read_csv(tmp_path / "b" / "eng3" / "results.csv")
    assert (df.loc[df["param_what"].notna(), "status"] == "crashed").all()


@pytest.mark.slow
def test_all_rows_failing_for_the_environment_stop_in_one_line_and_are_not_cached(tmp_path, hostile_site):
    """Every row says a kernel is not built: one line naming it, exit 2, no results.csv; the rows are kept in
    the store but recomputed by the next run (they were served from the cache as results)."""
    study = write_study(tmp_path, name="env", reps=2,
                        methods='[[methods]]\nid = "circle.hostile"\nparams = { what = "no_kernel" }\n')
    res = cli([study, "--jobs", "1", "--out", tmp_path / "out"], tmp_path, hostile_site)
    assert res.returncode == 2
    err = res.stderr.strip().splitlines()
    assert len(err) == 1 and "environment" in err[0] and "is not built" in err[0] and "(4 rows)" in err[0]
    assert not (tmp_path / "out" / "env" / "results.csv").exists()
    again = cli([study, "--jobs", "1", "--out", tmp_path / "out"], tmp_path, hostile_site)
    assert again.returncode == 2 and "0 already stored, 4 to run" in again.stdout


@pytest.mark.slow
def test_jobs_1_jobs_2_and_dask_give_identical_rows(tmp_path):
    """The same non-timing rows whatever the executor (local processes, a Dask LocalCluster of 2 worker processes,
    with rows in the workers' threads or in their row processes), the number of jobs and the chunking."""
    study = write_study(tmp_path, reps=30)
    frames = {}
    for name, extra in (("j1", ["--jobs", "1"]), ("j2", ["--jobs", "2"]),
                        ("dask", ["--jobs", "2", "--executor", "dask"]),
                        ("dask_rows_in_processes", ["--jobs", "2", "--executor", "dask", "--row-timeout", "600"])):
        res = subprocess.run([sys.executable, "-m", "experiments.run", str(study), "--out", str(tmp_path / name),
                              "--no-report", *extra], cwd=tmp_path, capture_output=True, text=True, timeout=600,
                             env=subprocess_env(OPENBLAS_NUM_THREADS="1"))
        assert res.returncode == 0, res.stderr
        frames[name] = non_timing(pd.read_csv(tmp_path / name / "eng" / "results.csv"))
    assert len(frames["j1"]) == 120
    pd.testing.assert_frame_equal(frames["j1"], frames["j2"])
    pd.testing.assert_frame_equal(frames["j1"], frames["dask"])
    pd.testing.assert_frame_equal(frames["j1"], frames["dask_rows_in_processes"])


@pytest.mark.slow
def test_an_exceeded_file_size_limit_keeps_the_store(tmp_path):
    """ulimit -f while the store grows: one line, exit 2, the store is not moved aside as corrupt and a later
    run uses its rows."""
    import resource
    study = write_study(tmp_path, reps=2)
    out = tmp_path / "out"
    env = subprocess_env(OPENBLAS_NUM_THREADS="1")
    first = subprocess.run([sys.executable, "-m", "experiments.run", str(study), "--out", str(out), "--jobs", "1",
                            "--no-report"], cwd=tmp_path, capture_output=True, text=True, env=env, timeout=300)
    assert first.returncode == 0, first.stderr
    size = max(p.stat().st_size for p in (out / "eng").glob("rows.sqlite*"))

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
    (tmp_path / "big").mkdir()
    big = write_study(tmp_path / "big", reps=400)
    res = subprocess.run([sys.executable, "-m", "experiments.run", str(big), "--out", str(out), "--jobs", "1",
                          "--no-report"], cwd=tmp_path, capture_output=True, text=True, env=env, timeout=300,
                         preexec_fn=limit)
    assert res.returncode == 2, res.stderr
    err = res.stderr.strip().splitlines()
    assert len(err) == 1 and ("row store" in err[0] or "cannot write" in err[0]), err
    assert not list((out / "eng").glob("*.corrupt-*"))
    again = subprocess.run([sys.executable, "-m", "experiments.run", str(study), "--out", str(out), "--jobs", "1",
                            "--no-report"], cwd=tmp_path, capture_output=True, text=True, env=env, timeout=300)
    assert again.returncode == 0, again.stderr
    assert "8 rows: 8 already stored, 0 to run" in again.stdout


@pytest.mark.slow
def test_workers_that_cannot_start_stop_the_run_in_one_line(tmp_path):
    """Every worker dies before its first row (here a sitecustomize ends each worker process as it starts: a copy
    forked from the run, or a process spawned later): the run stops after three such deaths with one line (it used to
    label every row crashed, starting a worker per row)."""
    study = write_study(tmp_path, reps=2)
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text("import os, sys\n"
                                           "if '--multiprocessing-fork' in sys.argv:\n    os._exit(7)\n"
                                           "os.register_at_fork(after_in_child=lambda: os._exit(7))\n")
    res = subprocess.run([sys.executable, "-m", "experiments.run", str(study), "--jobs", "2", "--no-report",
                          "--out", str(tmp_path / "o")], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                         env=subprocess_env(site, OPENBLAS_NUM_THREADS="1"))
    assert res.returncode == 2, res.stderr
    assert "worker processes end before running a row (exit code 7" in res.stderr.strip().splitlines()[-1]


@pytest.mark.slow
def test_a_script_without_the_main_guard_runs_on_several_workers(tmp_path):
    """Workers do not import the script that started the run, so a script without the ``if __name__ ==
    "__main__"`` guard that multiprocessing usually asks for runs its study on several workers."""
    study = write_study(tmp_path, reps=2)
    script = tmp_path / "unguarded.py"
    script.write_text(f"import sys\nfrom experiments import run\n"
                      f"sys.exit(run.main([{str(study)!r}, '--jobs', '2', '--no-report', '--out', {str(tmp_path / 'o')!r}]))\n")
    res = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                         env=subprocess_env(OPENBLAS_NUM_THREADS="1"))
    assert res.returncode == 0, res.stderr
    assert set(pd.read_csv(tmp_path / "o" / "eng" / "results.csv")["status"]) == {"ok"}


def _shortest_json_text(value: float) -> str:
    """The reference for results.csv's floats, from Python's shortest round-trip ``repr`` (not from orjson): the same
    digits in orjson's style: positional from 1e-5 on (``0.00001234``), a negative exponent without a leading zero, a
    whole number without ``.0``."""
    text = repr(float(value))
    if "e" not in text:
        return text[:-2] if text.endswith(".0") else text  # a whole number as an integer
    mantissa, exponent = text.split("e")
    if int(exponent) == -5:  # Python writes 1e-05 to 1e-04 with an exponent, JSON's shortest text positionally
        sign, digits = ("-", mantissa[1:]) if mantissa.startswith("-") else ("", mantissa)
        return f"{sign}0.0000{digits.replace('.', '')}"
    return f"{mantissa}e{exponent[0]}{int(exponent[1:])}"


def test_results_csv_text_is_pandas_to_csv_byte_for_byte():
    """The column-by-column CSV writer gives the bytes of DataFrame.to_csv(index=False) with each float as the shortest
    text that reads back as the same double (the reference above, from Python's repr): floats of every magnitude, NaN,
    infinities, -0.0, ints, bools, text needing quotes, missing text, object columns mixing types, and a dtype it
    leaves to pandas."""
    import io

    from experiments.csvtext import write_csv
    rng = np.random.default_rng(0)
    n = 3000
    df = pd.DataFrame({
        "f": np.where(rng.random(n) < 0.1, np.nan, rng.normal(size=n) * 10.0 ** rng.integers(-300, 300, n)),
        "g": rng.normal(size=n) * 10.0 ** rng.integers(-7, 18, n),  # around the two ends of positional text
        "bits": rng.integers(0, 2**63, n, dtype=np.uint64).view(np.float64),  # any double (NaN among them)
        "special": np.resize([0.0, -0.0, np.inf, -np.inf, 5e-324, 1.7976931348623157e308, 0.1, 1e-5, 1e-4, 1e16,
                              9999999999999998.0, -1.2345e-5], n),
        "i": rng.integers(-10**12, 10**12, n), "b": rng.random(n) < 0.5,
        "s": pd.Series(rng.choice(["a,b", 'q"uote', "new\nline", "cr\rhere", None, "", " sp ", "plain", "é ü", '"'], n),
                       dtype="str"),
        "o": pd.Series(rng.choice(np.array([0.1, "x", None, True, 3, np.nan, 1e-320, "y,z"], dtype=object), n),
                       dtype=object),
        # equal but not the same: 0.0 and -0.0 among missing values, False, 0 and 0.0 in one object column
        "z": np.resize([0.0, -0.0, np.nan, 1.0, -np.nan], n),
        "e": pd.Series(np.resize(np.array([False, 0, 0.0, "0", None, 1, True], dtype=object), n), dtype=object),
        "t": pd.Series(np.resize(["a", None, "a,b", "", "a"], n), dtype=object)})
    odd_names = df.rename(columns={"f": "a,b", "i": 'q"n'})
    for frame in (df, df.iloc[:0], df[["s"]], df[["s", "o"]], odd_names, df.iloc[::-7],
                  df.assign(cat=pd.Categorical(rng.choice(["u", "v"], n)))):
        for header in (True, False):
            ours = io.StringIO()
            write_csv(frame, ours, header=header)
            assert ours.getvalue() == frame.to_csv(index=False, header=header, float_format=_shortest_json_text)
    back = pd.read_csv(io.StringIO(write_csv_text(df[["f", "g", "bits", "special"]])), engine="python")
    for c in ("f", "g", "bits", "special"):  # every double reads back as itself
        assert np.array_equal(back[c].to_numpy().view(np.int64)[df[c].notna()], df[c].to_numpy().view(np.int64)[df[c].notna()])


def write_csv_text(frame) -> str:
    import io

    from experiments.csvtext import write_csv
    out = io.StringIO()
    write_csv(frame, out)
    return out.getvalue()


# ---------------------------------------------------------------- a file data set read with the reader's options

def _export_with_preamble(folder: Path) -> Path:
    angles = np.linspace(0.0, 2.0 * np.pi, 40, endpoint=False)
    lines = ["Instrument XYZ export", "Date: 2026-11-25", "Operator: A", "t,X (um),Y (um)"]
    lines += [f"{i},{5000.0 * np.cos(a):.3f},{5000.0 * np.sin(a):.3f}" for i, a in enumerate(angles)]
    path = folder / "export.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


def _file_study(folder: Path, reading: str) -> Path:
    path = folder / "fromfile.toml"
    path.write_text(f'name = "fromfile"\ntitle = "t"\nkind = "grid"\nseed = 1\n[[datasets]]\nfile = "export.csv"\n'
                    f'{reading}\n[[methods]]\nid = "circle.kasa"\n')
    return path


def test_a_file_data_set_takes_the_reader_s_options(tmp_path):
    """An instrument export (a preamble, a header with units, a third column) is read as the CLI reads it: a file
    data set takes columns, plane, unit and skip_rows (it took none, so the reader's advice could not be followed)."""
    _export_with_preamble(tmp_path)
    study = _file_study(tmp_path, 'skip_rows = 3\ncolumns = ["X", "Y"]')
    assert run.main([str(study), "--out", str(tmp_path / "o"), "--no-report", "--jobs", "1"]) == 0
    df = pd.read_csv(tmp_path / "o" / "fromfile" / "results.csv")
    assert df["status"].tolist() == ["ok"]
    assert df["radius"][0] == pytest.approx(5.0, rel=1e-6)  # micrometres in the header: read as 5 mm


def test_a_second_run_in_one_process_reads_an_edited_data_file_anew(tmp_path):
    """run.main twice in one process (a notebook, a loop over studies) with the data file edited between: the second
    run kept the first one's hash of the file and served its rows as already stored."""
    path = _export_with_preamble(tmp_path)
    study = _file_study(tmp_path, 'skip_rows = 3\ncolumns = ["X", "Y"]')
    args = [str(study), "--out", str(tmp_path / "o"), "--no-report", "--jobs", "1"]
    assert run.main(args) == 0
    path.write_text(path.read_text().replace("Y (um)", "Y (um) ").replace("5000.000", "6000.000"))
    assert run.main(args) == 0
    df = pd.read_csv(tmp_path / "o" / "fromfile" / "results.csv")
    assert df["radius"][0] != pytest.approx(5.0, rel=1e-6)  # the edited points: no longer the first file's circle


@pytest.mark.parametrize("reading, words", [
    ("", "give skip_rows = 3"),
    ('skip_rows = 3\nunit = "mm"', "drop unit or correct the header"),
    ('skip_rows = 3\ncolumns = ["X", "Z"]', "no column 'Z'"),
])
def test_a_file_the_rows_cannot_read_is_refused_before_any_row(tmp_path, capsys, reading, words):
    _export_with_preamble(tmp_path)
    study = _file_study(tmp_path, reading)
    assert run.main([str(study), "--out", str(tmp_path / "o"), "--no-report", "--jobs", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "fromfile.toml datasets[0]" in err[0] and words in err[0], err
    assert not (tmp_path / "o" / "fromfile" / "rows.sqlite").exists()


def test_reading_options_belong_to_a_file_data_set(tmp_path):
    path = tmp_path / "gen.toml"
    path.write_text('name = "gen"\ntitle = "t"\nkind = "grid"\nseed = 1\n[[datasets]]\nsource = "circle"\n'
                    'skip_rows = 2\nparams = { radius = 1.0, noise = 0.01, n = 10 }\n[[methods]]\nid = "circle.kasa"\n')
    with pytest.raises(InvalidInputError, match="skip_rows"):
        cfg = run.configs.load(str(path))
        engine.expand_datasets(cfg, cfg.where)


@pytest.mark.slow
def test_worker_processes_do_not_import_the_run_s_main_module(tmp_path):
    """A spawned worker imported the parent's __main__ first (experiments.run under python -m: 0.6 s of CPU a
    worker, for code no worker runs); the workers start without it."""
    study = write_study(tmp_path, reps=4)
    marker = tmp_path / "main-imported-by"
    script = tmp_path / "main_script.py"
    script.write_text("import os, sys\n"
                      "if __name__ != '__main__':\n"
                      f"    open({str(marker)!r}, 'a').write(f'{{os.getpid()}}\\n')\n"
                      "else:\n"
                      "    from experiments import run\n"
                      f"    sys.exit(run.main([{str(study)!r}, '--jobs', '2', '--no-report', "
                      f"'--out', {str(tmp_path / 'o')!r}]))\n")
    res = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                         env=subprocess_env(OPENBLAS_NUM_THREADS="1"))
    assert res.returncode == 0, res.stderr
    assert len(pd.read_csv(tmp_path / "o" / "eng" / "results.csv")) > 0
    assert not marker.exists(), f"workers imported the main module: {marker.read_text()}"


SCRIPT = '''import sys
import numpy as np
from methods import register
from methods.results import circle_result
from experiments import run

@register("circle.script_fit", kind="closed form", summary="centroid", reference="test")
def script_fit(points):
    """The centroid and FACTOR times the mean distance to it."""
    c = points.mean(axis=0)
    return circle_result(points, c, FACTOR * float(np.hypot(*(points - c).T).mean()), converged=True, message="c")

FACTOR = 1.0
sys.exit(run.main(sys.argv[1:]))
'''


def _script_run(tmp_path, program, *args):
    return subprocess.run([sys.executable, *program, str(tmp_path / "sc.toml"), "--no-report", "--out",
                           str(tmp_path / "out"), *args], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                          env=subprocess_env(OPENBLAS_NUM_THREADS="1"))


@pytest.mark.slow
def test_a_method_a_script_registers_is_keyed_by_the_script_and_refused_on_workers(tmp_path):
    """A method registered by the program that runs (the documented run.main API) was keyed by no code at all: an edit
    of it kept the old rows ("up to date"); with --jobs 2 every row was 'skipped: unknown method id' (workers do not
    import the program) and cached."""
    write_study(tmp_path, name="sc", reps=2, methods='[[methods]]\nid = "circle.script_fit"\n')
    script = tmp_path / "fits.py"
    script.write_text(SCRIPT)
    first = _script_run(tmp_path, [script], "--jobs", "1")
    assert first.returncode == 0, first.stderr
    before = pd.read_csv(tmp_path / "out" / "sc" / "results.csv")["radius"]
    script.write_text(SCRIPT.replace("FACTOR = 1.0", "FACTOR = 2.0"))
    again = _script_run(tmp_path, [script], "--jobs", "1")
    assert again.returncode == 0 and "0 already stored, 4 to run" in again.stdout, again.stdout + again.stderr
    assert np.allclose(pd.read_csv(tmp_path / "out" / "sc" / "results.csv")["radius"] / before, 2.0, rtol=1e-12)
    refused = _script_run(tmp_path, [script], "--jobs", "2", "--force")
    lines = refused.stderr.strip().splitlines()
    assert refused.returncode == 2 and len(lines) == 1 and "circle.script_fit is registered by the program" in lines[0]
    assert "--jobs 2" in lines[0] and "run with --jobs 1" in lines[0], lines


@pytest.mark.slow
def test_a_method_of_a_program_without_a_file_is_never_reused(tmp_path):
    """python -c (or a notebook) has no file to key its methods by: their rows are computed again by every run."""
    write_study(tmp_path, name="sc", reps=2, methods='[[methods]]\nid = "circle.script_fit"\n')
    for _ in range(2):
        done = _script_run(tmp_path, ["-c", SCRIPT], "--jobs", "1")
        assert done.returncode == 0 and "0 already stored, 4 to run" in done.stdout, done.stdout + done.stderr


@pytest.mark.parametrize("received, code, words", [(KeyboardInterrupt, 130, "interrupted"),
                                                   (row_code.Terminated, 143, "terminated (SIGTERM)")])
def test_an_interrupt_that_code_swallowed_still_stops_the_run(tmp_path, monkeypatch, capsys, received, code, words):
    """A signal handler raises wherever the main thread is, and code there can drop the exception (numpy's dtype
    comparison while a chunk lands, a weakref callback): the run went on to exit 0, about once in 20 Ctrl-Cs. The
    recorded signal is raised again at the run's next safe point: one line, exit 130/143, no meta.json (not done)."""
    real = engine.run

    def run_and_lose_the_interrupt(*args, **kwargs):
        out = real(*args, **kwargs)
        row_code.note_signal(received)  # the handler ran; the exception it raised was swallowed where it was raised
        return out
    monkeypatch.setattr(engine, "run", run_and_lose_the_interrupt)
    study = write_study(tmp_path, reps=2)
    assert run.main([str(study), "--jobs", "1", "--no-report", "--out", str(tmp_path / "o")]) == code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"experiments.run: {words}; finished rows are kept"), err
    assert not (tmp_path / "o" / "eng" / "meta.json").exists()
    monkeypatch.setattr(engine, "run", real)
    assert run.main([str(study), "--jobs", "1", "--no-report", "--out", str(tmp_path / "o")]) == 0  # a new run


# ---------------------------------------------------------------- results.csv made by the run's idle workers

def _results_frame(n: int) -> pd.DataFrame:
    rng = np.random.default_rng(5)
    return pd.DataFrame({"method": np.resize(["circle.kasa", "circle.gauss_newton"], n), "radius": rng.normal(size=n),
                         "iterations": np.where(rng.random(n) < 0.3, np.nan, 4.0), "message": np.resize(["a,b", "ok"], n)})


def test_results_csv_made_by_idle_workers_is_the_file_made_here(tmp_path):
    """With a run's workers idle, the blocks of results.csv are made by them (while the run analyses the rows): the same
    bytes, in order; a worker that ends while it makes a block leaves that block to this process, whose file is the
    same."""
    df = _results_frame(2345)
    from experiments.csvtext import blocks, csv_text, write_results
    expected = write_results(df, tmp_path / "here.csv")
    with executors.kept_workers(2):
        executors.start_kept_workers()
        workers = list(executors._KEPT)
        texts = executors.map_in_idle_workers(csv_text, blocks(df, 500))
        first = next(texts)  # both workers have a block now
        assert all(w.proc.is_alive() for w in workers)
        workers[1].proc.kill()  # it had the second block: this process makes it
        workers[1].proc.join(5)
        rest = list(texts)
        assert "".join([first, *rest]) == (tmp_path / "here.csv").read_text()
        assert workers[1] not in [w for w in executors._KEPT if w.proc.is_alive()]
        got = write_results(df, tmp_path / "workers.csv", executors.map_in_idle_workers(csv_text, blocks(df, 300)))
    assert got == expected and (tmp_path / "workers.csv").read_bytes() == (tmp_path / "here.csv").read_bytes()


def _touch(path):
    Path(path).touch()
    return path


def test_idle_workers_start_their_first_calls_before_the_results_are_read(tmp_path):
    """map_in_idle_workers sends each idle worker its first call when it is made, not when its first result is read:
    the run makes results.csv in its workers while it analyses the rows, and reads the texts only afterwards."""
    with executors.kept_workers(2):
        executors.start_kept_workers()
        marks = [tmp_path / f"call{i}" for i in range(3)]
        texts = executors.map_in_idle_workers(_touch, [(m,) for m in marks])
        deadline = time.monotonic() + 30
        while not (marks[0].exists() and marks[1].exists()) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert marks[0].exists() and marks[1].exists() and not marks[2].exists()  # one call a worker, none read
        assert list(texts) == marks


def _fails_on_second(frame, header):
    if not header:
        raise ValueError("cannot format this block")
    return "first"


def test_an_abandoned_map_ends_its_busy_workers_and_a_failure_is_raised_here():
    """A failure in a worker is raised in this process, as the call itself raises it; a map left before its end (an
    error, Ctrl-C) ends the workers that still make a block, so that their result reaches no later user of them."""
    df = _results_frame(100)
    from experiments.csvtext import blocks
    with executors.kept_workers(2):
        executors.start_kept_workers()
        texts = executors.map_in_idle_workers(_fails_on_second, blocks(df, 10))
        assert next(texts) == "first"
        with pytest.raises(ValueError, match="cannot format this block"):
            next(texts)
        busy = executors.map_in_idle_workers(_fails_on_second, blocks(df, 10))
        assert next(busy) == "first"
        busy.close()  # one worker still had a call
        alive = [w for w in executors._KEPT if w.proc.is_alive()]
        assert len(alive) <= 1
        for w in executors._KEPT:  # what remains is idle: a call gets its own answer
            assert not w.conn.poll(0.2)


def test_the_command_starts_its_workers_before_its_own_imports_only_when_rows_will_run(tmp_path, monkeypatch):
    """``python -m experiments.run`` starts its local workers as it begins (they import while it imports) when its
    arguments ask for several jobs on the local executor into a new --out folder, or with --force; otherwise (one job,
    Dask, an --out folder that holds results, --help, an argument it cannot read) it starts none and the run decides
    as before. The run takes the workers started so (kept_workers)."""
    from experiments import localworkers
    monkeypatch.setattr(localworkers.os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    new, old = str(tmp_path / "new"), str(tmp_path)
    for argv in (["s.toml", "--jobs", "1", "--out", new], ["--jobs", "2", "--executor", "dask", "--out", new],
                 ["--jobs", "2", "--out", old], ["--jobs", "2", "--out", new, "--help"], ["--jobs", "two", "--out", new],
                 ["--jobs", "2", "--scheduler", "tcp://h:1", "--out", new], ["--list", "--out", new]):
        localworkers.start_early(argv)
        assert localworkers.take_early(2) == [], argv
    localworkers.start_early(["s.toml", "--jobs", "2", "--out", old, "--force"])
    started = list(localworkers._EARLY)
    assert len(started) == 2 and all(w.proc.is_alive() for w in started)
    with executors.kept_workers(1):  # a run of one job keeps one of them, the other ends
        assert executors._KEPT == started[:1] and localworkers._EARLY == []
        started[1].proc.join(5)
        assert not started[1].proc.is_alive()
    started[0].proc.join(5)
    assert not started[0].proc.is_alive()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers are forked early on Linux only")
def test_early_workers_are_forked_copies_of_a_run_without_threads_and_spawned_with_one(tmp_path):
    """On Linux the command's early workers are copies of the run (fork, after it imported the rows' code and pandas,
    which a chunk's columns need: no worker imports them again), made while the run has no other thread; with a thread
    running they are spawned. Either way they make the rows a run makes in its own process."""
    code = textwrap.dedent(f"""
        import sys, threading
        from experiments import localworkers
        from loaded_probe import loaded
        if sys.argv[1] == "thread":
            threading.Thread(target=threading.Event().wait, daemon=True).start()
        localworkers.start_early(["s.toml", "--jobs", "2", "--out", {str(tmp_path / "o")!r}, "--force"])
        workers = localworkers.take_early(2)
        if sys.argv[1] == "plain":
            workers[0].conn.send((localworkers._CALL, loaded, ()))
            assert workers[0].conn.recv() == (True, ["pandas", "experiments.chunkrows", "experiments.rowframe"])
        from experiments.chunkrows import run_chunk
        from experiments.engine import grid_tasks, prepare
        cfg = {{"name": "w", "kind": "grid", "seed": 3, "repetitions": 2,
               "datasets": [{{"source": "circle", "params": {{"n": 20}}}}], "methods": [{{"id": "circle.kasa"}}]}}
        tasks = prepare(grid_tasks(cfg, "w"))
        workers[0].send(0, tasks, None)
        _, out = workers[0].conn.recv()
        here = run_chunk(tasks)
        print(sorted({{type(w.proc).__name__ for w in workers}}), out["columns"]["row"] == here["columns"]["row"])
        for w in workers:
            w.stop(now=True)
        """)
    (tmp_path / "loaded_probe.py").write_text(  # asked in a forked worker: the modules a chunk needs, already there
        "import sys\n\ndef loaded():\n    return [m for m in ('pandas', 'experiments.chunkrows', "
        "'experiments.rowframe') if m in sys.modules]\n", encoding="utf-8")
    path = os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")]))
    for mode, kind in (("plain", "ForkProcess"), ("thread", "SpawnProcess")):
        res = subprocess.run([sys.executable, "-c", code, mode], capture_output=True, text=True, timeout=120,
                             env={**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": path})
        assert res.returncode == 0, res.stderr
        assert res.stdout.split() == [f"['{kind}']", "True"], (mode, res.stdout, res.stderr)


def test_the_run_collects_garbage_less_often_and_gives_the_caller_its_thresholds_back(tmp_path, monkeypatch):
    """Rows allocate many containers and almost no cycle: the run raises the collector's first threshold while it
    makes them (at CPython's 700 the collector took 0.3 s of a 5 s, 40,000-row study) and a program calling
    run.main gets its own thresholds back, also when the run fails."""
    import gc

    from experiments import chunkrows, rows
    seen = []
    real = chunkrows.run_chunk

    def spy(*a, **k):
        seen.append(gc.get_threshold()[0])
        return real(*a, **k)
    monkeypatch.setattr(engine, "run_chunk", spy)
    before = gc.get_threshold()
    try:
        gc.set_threshold(500, 7, 9)
        assert run.main([str(write_study(tmp_path)), "--out", str(tmp_path / "o"), "--no-report", "--jobs", "1"]) == 0
        assert seen and set(seen) == {rows.ROW_GC_THRESHOLD}
        assert gc.get_threshold() == (500, 7, 9)
        assert run.main([str(tmp_path / "missing.toml"), "--out", str(tmp_path / "o")]) == 2
        assert gc.get_threshold() == (500, 7, 9)
    finally:
        gc.set_threshold(*before)


def test_batched_generic_rows_are_the_rows_of_one_task_at_a_time(monkeypatch):
    """Without a time limit a chunk's generic fit rows run in batches (its data, then its fits, then its gates and
    metrics): every outcome is the row run_task gives the task alone, in task order: a good fit, a method refusing its
    input (skipped), raising (error), raising ImportError inside the fit (error: the method's own), SystemExit and
    KeyboardInterrupt (crashed), a result the gate refuses (invalid), a result whose metrics raise (error), a data
    source that raises (error) or cannot import a module (unavailable). Batches are cut by task count and by bytes;
    the fits of a batch run a method's together (two methods here), the rows stay in task order."""
    import methods
    from datasets import sources
    from experiments import chunkrows, rows
    from methods import results as mres
    from methods._registry import _REGISTRY

    class BrokenGeometry(mres.CircleFit):
        def geometry(self):
            raise RuntimeError("geometry broke")

    def method(points, *, how="good"):
        c = points.mean(axis=0)
        res = mres.circle_result(points, c, float(np.hypot(*(points - c).T).mean()), converged=True, message="mean")
        if how == "skip":
            raise methods.InvalidInputError("too few points")
        if how == "bug":
            return 1 / 0
        if how == "import":
            import no_such_module_here  # noqa: F401
        if how in ("exit", "ctrl_c"):
            raise SystemExit(3) if how == "exit" else KeyboardInterrupt()
        if how == "lie":
            res.form_error += 1.0
        if how == "metrics":
            res.__class__ = BrokenGeometry
        return res

    def source(rng, *, n=12, fail=""):
        if fail == "bug":
            raise ValueError("source broke")
        if fail == "import":
            import no_such_module_either  # noqa: F401
        t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        pts = np.column_stack([np.cos(t), np.sin(t)]) * 3.0 + rng.normal(0.0, 0.01, (n, 2))
        return pts, {"center": (0.0, 0.0), "radius": 3.0}

    methods.register("circle.test_batch", kind="closed form", summary="batch test", reference="test")(method)
    methods.register("circle.test_batch_b", kind="closed form", summary="batch test", reference="test")(method)
    sources.register_source("test_batch", random=True, summary="batch test", gives=np.ndarray)(source)
    try:
        tasks = []
        for d, fail in enumerate(["", "bug", "import", ""]):
            spec = {"label": f"d{d}", "source": "test_batch", "params": {"n": 12 + d, "fail": fail}}
            for r in range(3):
                for how in ["good", "skip", "bug", "import", "exit", "ctrl_c", "lie", "metrics"]:
                    tasks.append({"study": "b", "kind": "grid", "dataset": spec, "repetition": r, "stream": [d, 0, r],
                                  "seed": 5, "params": {"how": how},
                                  "method": "circle.test_batch_b" if how in ("good", "lie") else "circle.test_batch", "timing": None,
                                  "index": len(tasks)})
        one_by_one = [rows.run_task(t) for t in tasks]
        statuses = {r["status"] for r in one_by_one}
        assert statuses == {"ok", "skipped", "error", "crashed", "invalid", "unavailable"}, statuses
        for cut in ({}, {"BATCH_TASKS": 5}, {"BATCH_BYTES": 1}):
            for name, value in cut.items():
                monkeypatch.setattr(rows, name, value)
            rows._LAST_DATA[:] = [None] * 4
            batched = rows._generic_rows(tasks, 0, None)
            assert batched == one_by_one
            chunk = chunkrows.run_chunk(tasks)["columns"]
            assert chunk["row"] == [rows.row_json(r) for r in one_by_one]
            monkeypatch.undo()
    finally:
        _REGISTRY.pop("circle.test_batch", None)
        _REGISTRY.pop("circle.test_batch_b", None)
        sources._REGISTRY.pop("test_batch", None)


def test_the_command_ends_without_teardown_but_as_python_would_for_its_threads_and_exit_handlers(tmp_path):
    """``python -m experiments.run`` ends with exit_now once its outputs are written (the interpreter's teardown of
    NumPy, SciPy, pandas and matplotlib took 0.3 s after a 40,000-row study): its exit status, everything it printed
    (100 kB to a pipe), a non-daemon thread's work and an atexit handler (a plugin's, logging's) are kept."""
    code = ("import atexit, threading, time, sys\n"
            "from experiments.localworkers import exit_now\n"
            f"atexit.register(lambda: open({str(tmp_path / 'atexit')!r}, 'w').write('ran'))\n"
            f"threading.Thread(target=lambda: (time.sleep(0.3), open({str(tmp_path / 'thread')!r}, 'w').write('done')))"
            ".start()\n"
            "sys.stdout.write('x' * 100_000)\n"
            "exit_now(3, as_python_does=True)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 3, out.stderr
    assert out.stdout == "x" * 100_000 and out.stderr == ""
    assert (tmp_path / "atexit").read_text() == "ran" and (tmp_path / "thread").read_text() == "done"


def test_a_file_data_set_with_x_y_z_columns_needs_its_plane(tmp_path):
    """A study's file data set took columns x, y by default, so a circle measured in the z, x plane (x, y, z columns)
    was fitted in x, y without a word. The file source now reads as the CLI does: refused in one line that names the
    plane in the TOML's words (plane = "zx"), and read right with it."""
    t = np.linspace(0.0, 2 * np.pi, 40, endpoint=False)
    (tmp_path / "zx.csv").write_text("x,y,z\n" + "".join(f"{5 * np.cos(a):.6f},2.5,{5 * np.sin(a):.6f}\n" for a in t))
    body = 'title = "t"\nkind = "grid"\nseed = 1\n[[datasets]]\nfile = "zx.csv"\n{}\n[[methods]]\nid = "circle.kasa"\n'
    (tmp_path / "guess.toml").write_text('name = "guess"\n' + body.format(""))
    (tmp_path / "plane.toml").write_text('name = "plane"\n' + body.format('plane = "zx"'))
    out = subprocess.run([sys.executable, "-m", "experiments.run", str(tmp_path / "guess.toml"), "--out",
                          str(tmp_path / "o"), "--no-report", "--jobs", "1"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 2 and "Traceback" not in out.stderr and len(out.stderr.strip().splitlines()) == 1
    assert "three coordinate columns (x, y, z)" in out.stderr and 'give plane = "zx"' in out.stderr, out.stderr
    assert run.main([str(tmp_path / "plane.toml"), "--out", str(tmp_path / "o"), "--no-report", "--jobs", "1"]) == 0
    df = pd.read_csv(tmp_path / "o" / "plane" / "results.csv")
    assert df["status"].tolist() == ["ok"] and df["radius"][0] == pytest.approx(5.0, rel=1e-6)


def test_summary_by_may_name_a_column_of_a_result_class_loaded_after_the_engine(tmp_path):
    """The columns a row may have are read when a study is checked, not when the engine was imported: a plugin's
    result class (plugins load on first use, after the engine) adds its columns, and ``summary_by`` may name them."""
    from dataclasses import dataclass

    from experiments import config as configs
    from experiments.studies import study_of
    from methods import results

    @dataclass(kw_only=True)
    class LateFit(results.CircleFit):
        COLUMNS = (*results.CircleFit.COLUMNS, results.Column("late_class_lobes", "count", results.EXACT))

    study = tmp_path / "late.toml"
    study.write_text('name = "late"\ntitle = "t"\nseed = 1\nsummary_by = ["method", "late_class_lobes"]\n'
                     '[[datasets]]\nsource = "circle"\nparams = { n = 10 }\n[[methods]]\nid = "circle.kasa"\n')
    cfg = configs.load(str(study))
    run.check_summary_by(cfg, study_of(cfg["kind"]), list(cfg.grid_tasks()))  # raised 'no row will have' before
    assert "late_class_lobes" in engine.result_columns() and LateFit


@pytest.mark.parametrize("signum, status, what", [(signal.SIGINT, 130, "interrupted"),
                                                  (signal.SIGTERM, 143, "terminated (SIGTERM)"),
                                                  (signal.SIGHUP, 129, "terminated (SIGHUP)")])
@pytest.mark.parametrize("held, jobs", [("experiments.compare", "1"), ("pandas", "2")],
                         ids=["its-own-modules", "starting-its-workers"])
def test_ctrl_c_while_the_command_imports_is_one_line(tmp_path, signum, status, what, held, jobs):
    """Ctrl-C (or SIGTERM, SIGHUP) while ``python -m experiments.run`` still imports its modules, or imports what its
    early workers need before it forks them (``--jobs 2``: NumPy, the methods, pandas), before its main function
    handles signals: one line and 130 (143, 129), no traceback (it printed the KeyboardInterrupt's traceback of the
    import and ended by the signal). An import hook holds the run in that import until the signal comes."""
    from conftest import default_sigint, subprocess_env
    site = tmp_path / "site"
    site.mkdir()
    mark = tmp_path / "importing"
    (site / "sitecustomize.py").write_text(textwrap.dedent(f"""
        import sys, time
        class _Hold:
            def find_spec(self, name, path=None, target=None):
                if name == {held!r}:
                    open({str(mark)!r}, "w").close()
                    time.sleep(30)
                return None
        if sys.argv[:1] != ["-c"]:
            sys.meta_path.insert(0, _Hold())
        """))
    study = write_study(tmp_path, reps=1)
    proc = subprocess.Popen([sys.executable, "-m", "experiments.run", str(study), "--jobs", jobs, "--out",
                             str(tmp_path / "o")], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=subprocess_env(site, OPENBLAS_NUM_THREADS="1"), preexec_fn=default_sigint)
    deadline = time.monotonic() + 60
    while not mark.exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.02)
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == status, err
    assert err.strip().splitlines() == [f"experiments.run: {what} while starting; no rows had run"], err
