"""The default table and figure of a TOML study pool nothing silently: every grid parameter that varies has its own
rows (table) and lines (figure); a length is labelled with the data's unit, mm only where the data are in mm."""
import numpy as np
import pandas as pd

from experiments.analysis import default_declarations
from experiments.tables import declared_table
from experiments.units import DATA_UNITS

CIRCLE = {"name": "pool", "datasets": [{"generator": "circle", "params": {"radius": 1.0}}]}


def rows(**grid):
    """Rows of two methods over a grid of data parameters; the centre error grows with 1/n so pooling n shows."""
    rng = np.random.default_rng(0)
    keys = list(grid)
    combos = pd.MultiIndex.from_product([grid[k] for k in keys], names=keys).to_frame(index=False)
    out = []
    for method in ("circle.kasa", "circle.gauss_newton"):
        for _, combo in combos.iterrows():
            for rep in range(4):
                scale = 1.0 / combo.get("data_n", 1)
                out.append({"study": "pool", "dataset": "circle", "method": method, "params": "{}", "status": "ok",
                            "repetition": rep, **combo.to_dict(), "center_error": scale * (1 + rng.random()),
                            "radius_error": scale * rng.normal()})
    return pd.DataFrame(out)


def test_other_varying_parameters_get_their_own_rows_and_lines():
    df = rows(data_arc_deg=[360.0, 90.0], data_n=[20, 200])
    table, figure = default_declarations(CIRCLE, df)
    assert table["columns"] == "data_arc_deg" and table["rows"] == ["method", "data_n"]
    assert "per method, n and arc" in table["caption"]
    got = declared_table(df, table).data
    assert len(got) == 4   # 2 methods x 2 n: no RMSE of a mix of sample sizes
    for (method, n, arc), g in df.groupby(["method", "data_n", "data_arc_deg"]):
        cell = got[(got["method"] == method) & (got["data_n"] == n)][f"arc = {arc:g} °"].item()
        assert cell == np.sqrt(np.mean(g["center_error"] ** 2))
    assert figure["x"] == "data_arc_deg" and figure["by"] == ["method", "data_n"]
    assert "one line per method and n" in figure["caption"]


def test_a_single_varying_parameter_keeps_one_row_per_method():
    table, figure = default_declarations(CIRCLE, rows(data_arc_deg=[360.0, 90.0]))
    assert table["rows"] == ["method"] and figure["by"] == "method"


def test_lengths_of_a_generator_are_in_the_data_s_unit_unless_declared():
    df = rows(data_arc_deg=[360.0, 90.0])
    table, figure = default_declarations(CIRCLE, df)
    assert table["unit"] == DATA_UNITS and f"[{DATA_UNITS}]" in figure["ylabel"]
    assert "length_unit" in table["caption"] and "length_unit" in figure["caption"]
    table, figure = default_declarations({**CIRCLE, "length_unit": "R"}, df)
    assert table["unit"] == "R" and figure["ylabel"].endswith("[R]") and "length_unit" not in table["caption"]
    published = {"name": "pub", "datasets": [{"published": "gauss_2008"}, {"file": "trace.csv"}]}
    table, figure = default_declarations(published, df)
    assert table["unit"] == "mm" and figure["ylabel"].endswith("[mm]")
    plugin = {"name": "plug", "datasets": [{"source": "someone_elses"}]}
    assert default_declarations(plugin, df)[0]["unit"] == DATA_UNITS
