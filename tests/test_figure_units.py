"""A declared figure's axes carry the unit of the values in the study, as its default table and figure do: a
generator's lengths are in data units (they were labelled mm: 'RMSE of radius error [mm]' beside a default table in
'[data units]'), in the study's length_unit when it declares one, mm for data read in mm; a count has no unit (a bar
of 3 rows was labelled 'count of radius error [mm]')."""
import pandas as pd
import pytest

from experiments import figures
from experiments import study as contract
from experiments.units import DATA_UNITS

GENERATOR = {"name": "g", "datasets": [{"source": "circle"}]}


def rows() -> pd.DataFrame:
    return pd.DataFrame({"method": ["circle.kasa"] * 4, "dataset": "circle", "status": "ok",
                         "data_arc_deg": [360.0, 360.0, 90.0, 90.0], "radius_error": [0.01, 0.02, 0.03, 0.04]})


@pytest.mark.parametrize("cfg, aggregate, ylabel, note", [
    (GENERATOR, "rmse", f"RMSE of radius error [{DATA_UNITS}]", True),
    ({**GENERATOR, "length_unit": "R"}, "rmse", "RMSE of radius error [R]", False),
    ({"name": "f", "datasets": [{"file": "trace.csv"}]}, "mean", "mean of radius error [mm]", False),
    (GENERATOR, "count", "count of radius error", False),
])
def test_declared_figure_axes_carry_the_study_s_units(tmp_path, monkeypatch, cfg, aggregate, ylabel, note):
    seen = {}
    monkeypatch.setitem(contract.PLOTS, "probe", lambda df, ax, *, x, y, by=None, aggregate="mean", xlabel=None,
                        ylabel=None: seen.update(xlabel=xlabel, ylabel=ylabel))
    fig = figures.declared_figure(rows(), {"plot": "probe", "x": "data_arc_deg", "y": "radius_error",
                                           "aggregate": aggregate, "caption": "c"}, tmp_path, 1, cfg)
    assert seen == {"xlabel": "arc [°]", "ylabel": ylabel}
    assert ("length_unit in the study's TOML names it" in fig.caption) == note
    assert fig.caption.startswith("c." if note else "c")
