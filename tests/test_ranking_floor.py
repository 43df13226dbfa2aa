"""A ranking's ``floor`` (costs below it are equal) is in the ranking's unit, the unit its costs are shown in, and
its default ties the same costs whatever that unit is. Before: the default was 0 only when the ranking's unit was
written "s" (a runtime ranked in ms got 1e-12 ms) and 1e-12 of whatever unit the ranking shows (mm data ranked in
µm tied at 1e-15 mm, 1000x below the 1e-12 mm of the same data ranked in mm)."""
import pandas as pd
import pytest

from experiments.render.rankings import collect


def ranked(tmp_path, name, metric, costs, unit=None, floor=None):
    """The ranking of one study on mm data (a file data set): ``costs`` {method: [cost per problem]}."""
    decl = {"profile": "p", "metric": metric, **({"unit": unit} if unit else {}),
            **({"floor": floor} if floor is not None else {})}
    cfg = {"name": name, "datasets": [{"file": "trace.csv"}], "rankings": [decl]}
    folder = tmp_path / name
    folder.mkdir()
    pd.DataFrame([{"dataset": "trace", "data_stream": f"0.0.{i}", "repetition": 0, "method": m, "params": "{}",
                   "status": "ok", metric: v} for m, values in costs.items() for i, v in enumerate(values)]
                 ).to_csv(folder / "results.csv", index=False)
    return collect([(name, folder, {"config": cfg})])["p"]


@pytest.mark.parametrize("unit", [None, "s", "ms", "us"])
def test_a_runtime_has_no_default_floor_in_any_unit(tmp_path, unit):
    r = ranked(tmp_path, "t", "time_median_s", {"circle.kasa": [2e-15, 4e-6], "circle.taubin": [4e-15, 8e-6]}, unit)
    assert r.table.attrs["floor"] == 0.0
    ratios = r.table.div(r.table.min(axis=1), axis=0)
    assert ratios["circle.taubin"].tolist() == pytest.approx([2.0, 2.0])   # tiny times still compared


@pytest.mark.parametrize("unit, factor", [(None, 1.0), ("mm", 1.0), ("um", 1e3), ("nm", 1e6)])
def test_the_default_floor_of_a_length_ties_the_same_costs_in_every_unit(tmp_path, unit, factor):
    """Form errors of 2e-13 and 5e-13 mm (exact fits) tie at the default floor, whether ranked in mm, µm or nm;
    0.002 and 0.004 mm do not."""
    r = ranked(tmp_path, "f", "form_error", {"circle.kasa": [2e-13, 0.002], "circle.taubin": [5e-13, 0.004]}, unit)
    assert r.table.attrs["floor"] == pytest.approx(1e-12 * factor)
    floored = r.table.clip(lower=r.table.attrs["floor"])
    ratios = floored.div(floored.min(axis=1), axis=0)["circle.taubin"].tolist()
    assert ratios == pytest.approx([1.0, 2.0])


def test_a_declared_floor_is_in_the_ranking_s_unit(tmp_path):
    """floor = 0.001 with unit = "um" on mm data: costs under 1 nm tie, 2 and 4 nm do not."""
    r = ranked(tmp_path, "d", "form_error", {"circle.kasa": [3e-7, 2e-6], "circle.taubin": [8e-7, 4e-6]}, "um", 0.001)
    assert r.table.attrs["floor"] == 0.001
    floored = r.table.clip(lower=0.001)
    assert floored.div(floored.min(axis=1), axis=0)["circle.taubin"].tolist() == pytest.approx([1.0, 2.0])


def test_pooled_studies_keep_each_its_own_floor(tmp_path):
    """One study ranks form errors in mm (default floor 1e-12 mm), another in µm with floor = 0.001 µm: the µm
    floor is not applied to the mm study's costs (1e-4 and 2e-4 mm stay a ratio of 2; the largest floor of the
    pool, 0.001, made them a tie)."""
    def study(name, costs, unit, floor=None):
        decl = {"profile": "p", "metric": "form_error", "unit": unit, **({"floor": floor} if floor else {})}
        folder = tmp_path / name
        folder.mkdir()
        pd.DataFrame([{"dataset": "trace", "data_stream": f"0.0.{i}", "repetition": 0, "method": m, "params": "{}",
                       "status": "ok", "form_error": v} for m, values in costs.items() for i, v in enumerate(values)]
                     ).to_csv(folder / "results.csv", index=False)
        return name, folder, {"config": {"name": name, "datasets": [{"file": "trace.csv"}], "rankings": [decl]}}

    r = collect([study("a", {"circle.kasa": [1e-4], "circle.taubin": [2e-4]}, "mm"),
                 study("b", {"circle.kasa": [3e-7], "circle.taubin": [8e-7]}, "um", 0.001)])["p"]
    costs = r.table.loc[["a | trace | 0.0.0 | 0", "b | trace | 0.0.0 | 0"]]
    ratios = costs.div(costs.min(axis=1), axis=0)["circle.taubin"].tolist()
    assert ratios == pytest.approx([2.0, 1.0])
