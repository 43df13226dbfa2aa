"""What explorer.html draws for a ranking, from its data (the browser side is tests/test_explorer.py): the metric
against the runtime has one panel per unit (a study ranked in R and one in mm never share an axis: their heights
cannot be compared), and none when the ranking's metric is the runtime itself (a diagonal)."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from experiments.render.explorer import ranking_data
from experiments.render.rankings import collect

CIRCULARITY = "circularity"
RUNTIME = "runtime"


def _study(root: Path, name: str, *, unit: str | None, timed: bool, scale: float) -> tuple[str, Path, dict]:
    """A finished study of two methods on three data sets, ranked by its form error (in ``unit``) and its runtime."""
    rng = np.random.default_rng(len(name))
    rows = [{"study": name, "dataset": f"{name}-d{i}", "data_stream": f"0.{i}.0", "repetition": 0, "seed": 1,
             "method": m, "params": "{}", "status": "ok", "form_error": scale * rng.uniform(1, 2),
             **({"time_median_s": rng.uniform(1e-5, 1e-3)} if timed else {})}
            for i in range(3) for m in ("circle.kasa", "circle.pratt")]
    folder = root / name
    folder.mkdir()
    pd.DataFrame(rows).to_csv(folder / "results.csv", index=False)
    rankings = [{"profile": CIRCULARITY, "metric": "form_error", "methods": "circle.*", **({"unit": unit} if unit else {})}]
    if timed:
        rankings.append({"profile": RUNTIME, "metric": "time_median_s", "unit": "s", "methods": "circle.*"})
    return name, folder, {"config": {"name": name, "rankings": rankings}}


def _data(tmp_path: Path, *studies) -> dict[str, dict]:
    found = [_study(tmp_path, name, **kw) for name, kw in studies]
    folders, metas = {n: f for n, f, _ in found}, {n: m for n, _, m in found}
    return {name: json.loads(json.dumps(ranking_data(name, r, folders, metas)))   # what the page's JSON holds
            for name, r in collect(found).items()}


def test_costs_of_different_units_get_one_panel_each(tmp_path):
    """Before: one axis 'form error [mm (published, scaling) or R (noise)]' for both."""
    data = _data(tmp_path, ("in_mm", dict(unit=None, timed=True, scale=1e-3)),
                 ("in_r", dict(unit="R", timed=True, scale=1e-2)))[CIRCULARITY]
    assert sorted(p["unit"] for p in data["panels"]) == ["R", "mm"]
    for panel in data["panels"]:
        studies = {data["problems"][i].split(" | ")[0] for i in panel["problems"]}
        assert {data["units"][i] for i in panel["problems"]} == {panel["unit"]}
        assert studies == {"in_mm" if panel["unit"] == "mm" else "in_r"}
    assert sorted(i for p in data["panels"] for i in p["problems"]) == list(range(len(data["problems"])))
    assert data["untimed"] == []


def test_a_study_that_did_not_time_its_fits_is_named_not_drawn(tmp_path):
    data = _data(tmp_path, ("in_mm", dict(unit=None, timed=True, scale=1e-3)),
                 ("in_r", dict(unit="R", timed=False, scale=1e-2)))[CIRCULARITY]
    assert [p["unit"] for p in data["panels"]] == ["mm"] and data["untimed"] == ["in_r"]
    assert all(data["problems"][i].startswith("in_mm | ") for i in data["panels"][0]["problems"])


def test_no_runtime_against_runtime(tmp_path):
    """Before: the runtime ranking plotted the median runtime against the median runtime (a diagonal)."""
    data = _data(tmp_path, ("in_mm", dict(unit=None, timed=True, scale=1e-3)))[RUNTIME]
    assert data["time"] is None and "runtime" in data["no_time"]
