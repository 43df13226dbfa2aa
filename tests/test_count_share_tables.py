"""A table of the share of ok rows is headed 'ok share' (it was 'mean of radius error': a share of 1 read as a
radius error of 1 data unit), a count 'count of ...'; neither takes a unit (a count of 3 was shown 'Unit: mm', a
share of 1 as '[rad]'): a unit there is refused when the study is loaded, in one line."""
import numpy as np
import pandas as pd
import pytest

from experiments import config as configs
from experiments.study import ConfigError
from experiments.tables import declared_table

STUDY = '''name = "c"
title = "c"
seed = 1
repetitions = 3
[[datasets]]
source = "circle"
params = { radius = 5.0, noise = 0.01, n = 30 }
[[methods]]
id = "circle.kasa"
[[tables]]
caption = "t"
rows = ["method"]
values = "radius_error"
aggregate = "AGG"
'''


def rows() -> pd.DataFrame:
    return pd.DataFrame({"method": ["circle.kasa"] * 3 + ["circle.max_inscribed"] * 4,
                         "status": ["ok"] * 3 + ["ok", "not converged", "not converged", "ok"],
                         "radius_error": [0.5, 0.7, 0.9, 2.0, np.nan, np.nan, 4.0]})


def test_an_ok_share_table_is_headed_ok_share_and_has_no_unit():
    got = declared_table(rows(), {"caption": "share", "rows": ["method"], "values": "radius_error",
                                  "aggregate": "ok_share"}, {"datasets": [{"source": "circle"}]})
    assert list(got.data.columns) == ["method", "ok share"] and got.unit == ""
    assert got.data.set_index("method")["ok share"].to_dict() == {"circle.kasa": 1.0, "circle.max_inscribed": 0.5}
    count = declared_table(rows(), {"caption": "n", "rows": ["method"], "values": "radius_error",
                                    "aggregate": "count"}, {"datasets": [{"source": "circle"}]})
    assert list(count.data.columns) == ["method", "count of radius error"] and count.unit == ""
    assert count.data.set_index("method")["count of radius error"].to_dict() == {"circle.kasa": 3,
                                                                                 "circle.max_inscribed": 2}


@pytest.mark.parametrize("aggregate, unit, message", [
    ("count", "mm", "tables[0].unit: aggregate = 'count' gives a count of rows, which has no unit: drop the unit 'mm'"),
    ("ok_share", "rad", "tables[0].unit: aggregate = 'ok_share' gives the share of ok rows (0 to 1), which has no "
                        "unit but % (unit = \"%\" shows it x 100): drop the unit 'rad'"),
])
def test_a_unit_on_a_count_or_a_share_is_refused_at_load(tmp_path, aggregate, unit, message):
    path = tmp_path / "c.toml"
    path.write_text(STUDY.replace("AGG", aggregate) + f'unit = "{unit}"\n', encoding="utf-8")
    with pytest.raises(ConfigError) as err:
        configs.load(str(path))
    assert message in str(err.value) and "\n" not in str(err.value), str(err.value)
    path.write_text(STUDY.replace("AGG", aggregate), encoding="utf-8")
    configs.load(str(path))


def test_a_pivot_of_ok_shares_or_counts_says_what_its_cells_are():
    """A pivot's headers are the column key's values ('n = 3'): its caption says the cells are shares of ok rows
    (or counts); before, only a caption the user wrote could say so."""
    df = rows().assign(data_n=[3, 30, 30, 3, 3, 30, 30])
    share = declared_table(df, {"caption": "ok rows", "rows": ["method"], "columns": "data_n",
                                "values": "radius_error", "aggregate": "ok_share"}, {"datasets": [{"source": "circle"}]})
    assert share.caption == "ok rows. Values: the share of rows whose status is ok (0 to 1)." and share.unit == ""
    assert share.data.set_index("method").loc["circle.max_inscribed"].tolist() == [0.5, 0.5]
    count = declared_table(df, {"caption": "n", "rows": ["method"], "columns": "data_n", "values": "radius_error",
                                "aggregate": "count"}, {"datasets": [{"source": "circle"}]})
    assert count.caption == "n. Values: the count of ok rows with radius error."


def test_an_ok_share_in_per_cent(tmp_path):
    """unit = "%" on an ok share shows it x 100 (it was refused as a unit a share has not)."""
    got = declared_table(rows(), {"caption": "share", "rows": ["method"], "values": "radius_error",
                                  "aggregate": "ok_share", "unit": "%"}, {"datasets": [{"source": "circle"}]})
    assert got.unit == "%"
    assert got.data.set_index("method")["ok share"].to_dict() == {"circle.kasa": 100.0, "circle.max_inscribed": 50.0}
    path = tmp_path / "c.toml"
    path.write_text(STUDY.replace("AGG", "ok_share") + 'unit = "%"\n', encoding="utf-8")
    configs.load(str(path))


@pytest.mark.parametrize("unit", ["%", "furlong"])
def test_a_unit_that_is_no_length_on_a_generator_s_length_is_refused_with_advice_that_applies(tmp_path, unit):
    """It advised 'length_unit = "%"', which length_unit then refuses as no unit of length."""
    path = tmp_path / "c.toml"
    path.write_text(STUDY.replace("AGG", "mean") + f'unit = "{unit}"\n', encoding="utf-8")
    with pytest.raises(ConfigError) as err:
        configs.load(str(path))
    text = str(err.value)
    assert f"tables[0].unit: 'radius_error' is a length, and {unit!r} is not a unit of length fitbench knows" in text
    assert "length_unit =" not in text and "\n" not in text, text
