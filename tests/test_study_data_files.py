"""``meta.json`` records the SHA-256 of every data file a study's rows read, also for a study kind whose own tasks
read them (``Study.data_sets``; ``nist_circle`` reads the converted NIST sets of ``FITBENCH_NIST_DIR``, not
``[[datasets]]``), so that verify tells results of other data apart."""
from __future__ import annotations

import hashlib
import json

import numpy as np

from experiments import compare, config


def _nist_like_set(folder, k: int, shift: float = 0.0) -> None:
    t = np.linspace(0.0, 2 * np.pi, 12, endpoint=False)
    rows = "\n".join(f"{1 + np.cos(a) + shift!r},{2 + np.sin(a)!r}" for a in t)
    (folder / f"nist_cir2d_{k:02d}.csv").write_text("x,y\n" + rows + "\n")
    (folder / f"nist_cir2d_{k:02d}.json").write_text(json.dumps(
        {"name": f"cir2d{k}", "reference_least_squares": {"center": ["1", "2"], "diameter": "2"}}))


def test_the_nist_sets_a_study_reads_are_recorded_and_a_changed_one_is_named(tmp_path, monkeypatch):
    for k in (1, 2):
        _nist_like_set(tmp_path, k)
    monkeypatch.setenv("FITBENCH_NIST_DIR", str(tmp_path))
    cfg = config.load("nist_circle")
    files = compare.inputs(cfg)["data_files"]
    assert files == {f"datasets[{i}] nist_cir2d_{k:02d}.csv":
                     hashlib.sha256((tmp_path / f"nist_cir2d_{k:02d}.csv").read_bytes()).hexdigest()
                     for i, k in enumerate((1, 2))}
    before = {"inputs": compare.inputs(cfg)}
    _nist_like_set(tmp_path, 2, shift=1e-9)
    assert compare.changed_inputs(before, compare.inputs(cfg)) == ["data file datasets[1] nist_cir2d_02.csv changed"]


def test_many_changed_data_files_are_named_by_the_first_three():
    old = {"inputs": {"config": {}, "data_files": {}}}
    now = {"config": {}, "data_files": {f"datasets[{i}] s{i}.csv": "x" for i in range(12)}}
    assert compare.changed_inputs(old, now) == [
        "data files datasets[0] s0.csv, datasets[1] s1.csv, datasets[2] s2.csv and 9 more added"]
