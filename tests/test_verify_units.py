"""verify's table of differences gives each number its column's unit, the atol too (``rep radius 1 outside
rtol=1e-09, atol=1e-12 ... 5.001526145967651  5.001526646120267  5e-07`` had none): a length in the study's unit of
lengths (the data's unit for a generator, mm for a file), read from the config ``meta.json`` records
(``experiments.units.value_unit``); a count none."""
from __future__ import annotations

import json

import pandas as pd
import pytest

from experiments import compare

GENERATOR = {"name": "vu", "title": "t", "kind": "grid", "seed": 1,
             "datasets": [{"source": "circle", "params": {"radius": 5.0, "n": 30}}], "methods": ["circle.kasa"]}
FILE = {**GENERATOR, "datasets": [{"file": "ring.csv"}]}
NAMED = {**GENERATOR, "length_unit": "R"}


def _folder(root, cfg, radius, iterations="3"):
    study = root / "vu"
    study.mkdir(parents=True)
    pd.DataFrame({"study": ["vu"], "dataset": ["circle"], "data_stream": ["0.0.0"], "repetition": ["0"], "seed": ["1"],
                  "method": ["circle.kasa"], "params": ["{}"], "status": ["ok"], "radius": [radius],
                  "angle_error": ["0.25"], "iterations": [iterations]}).to_csv(study / "results.csv", index=False)
    (study / "meta.json").write_text(json.dumps({"config": cfg}), encoding="utf-8")
    return root


@pytest.mark.parametrize("cfg, unit", [(GENERATOR, "data units"), (FILE, "mm"), (NAMED, "R")])
def test_each_number_of_the_difference_table_has_its_unit(tmp_path, cfg, unit):
    results = _folder(tmp_path / "committed", cfg, "5.001526145967651")
    against = _folder(tmp_path / "fresh", cfg, "5.001526646120267", iterations="4")
    said = []
    verdict = compare.verify(["vu"], results, against, log=said.append)
    assert not verdict["agree"]
    table = "\n".join(said)
    (line,) = [ln for ln in table.splitlines() if ln.startswith("vu ") and "radius" in ln]
    assert f"5.001526145967651 {unit}" in line and f"5.001526646120267 {unit}" in line and f"5e-07 {unit}" in line, line
    problem = next(p for p in verdict["studies"][0]["problems"] if p["column"] == "radius")
    tol = compare.tolerance("radius", "vu", "circle.kasa")
    assert problem["unit"] == unit and f"outside rtol={tol.rtol:g}, atol={tol.atol:g} {unit}" in line
    (count,) = [ln for ln in table.splitlines() if "iterations" in ln]
    assert "3  " in count and "data units" not in count and " mm" not in count   # a count: no unit


def test_an_angle_is_in_rad(tmp_path):
    committed = pd.read_csv(_folder(tmp_path / "a", GENERATOR, "5.0") / "vu" / "results.csv", dtype=str)
    fresh = committed.copy()
    fresh.loc[0, "angle_error"] = "0.5"
    report = compare.compare_study("vu", committed, fresh, cfg=GENERATOR)
    (problem,) = report["problems"]
    assert problem["column"] == "angle_error" and problem["unit"] == "rad"
    assert "0.25 rad" in compare._table([("vu", problem)])
