"""A table or figure keyed on a data parameter that only some data sets have drops none of the others' rows silently:
a study pairing a source with `grid = { share = [...] }` and a source without `share` shows the second one's rows
under 'share = none' (the pivot used to drop rows with a NaN key), and a line figure over `share`, which cannot place
them, says in its caption how many rows it leaves out and of which data sets."""
import numpy as np
import pandas as pd

from experiments.analysis import default_declarations
from experiments.figures import declared_figure
from experiments.tables import NO_VALUE, declared_table

CFG = {"name": "mixed", "datasets": [{"source": "outliers", "grid": {"share": [0.0, 0.1]}}, {"source": "squares"}]}


def mixed_rows() -> pd.DataFrame:
    """5 repetitions of two methods on a source with a `share` grid and on one without that parameter."""
    rng = np.random.default_rng(1)
    out = []
    for method in ("circle.kasa", "circle.my_fit"):
        for dataset, shares in (("outliers", [0.0, 0.1]), ("squares", [np.nan])):
            for share in shares:
                for rep in range(5):
                    out.append({"study": "mixed", "dataset": dataset, "method": method, "params": "{}", "status": "ok",
                                "repetition": rep, "data_share": share, "center_error": rng.random(),
                                "form_error": rng.random()})
    return pd.DataFrame(out)


def test_the_default_table_keeps_the_rows_of_a_data_set_without_the_pivoted_parameter():
    df = mixed_rows()
    table, _ = default_declarations(CFG, df)
    assert table["columns"] == "data_share" and table["rows"] == ["method", "dataset"]
    got = declared_table(df, table)
    col = f"share = {NO_VALUE}"
    assert col in got.data.columns and "squares" in got.caption and NO_VALUE in got.caption
    for (method, dataset), g in df.groupby(["method", "dataset"]):
        line = got.data[(got.data["method"] == method) & (got.data["dataset"] == dataset)]
        assert len(line) == 1
        if dataset == "squares":
            assert line[col].item() == np.sqrt(np.mean(g["center_error"] ** 2))
            assert line.drop(columns=["method", "dataset", col]).isna().all(axis=None)
        else:
            assert np.isnan(line[col].item())
    # every ok row is counted in exactly one cell
    count = declared_table(df, {**table, "aggregate": "count", "unit": ""}).data
    assert count.drop(columns=["method", "dataset"]).sum().sum() == len(df)


def test_a_row_key_some_data_sets_lack_keeps_their_rows():
    df = mixed_rows()
    t = {"caption": "form error", "rows": ["method", "data_share"], "values": "form_error", "aggregate": "count"}
    got = declared_table(df, t)
    assert got.data.iloc[:, -1].sum() == len(df)
    none = got.data[got.data["data_share"] == NO_VALUE]
    assert sorted(none["method"]) == ["circle.kasa", "circle.my_fit"] and (none.iloc[:, -1] == 5).all()
    assert "squares" in got.caption
    pivot = declared_table(df, {**t, "rows": ["data_share"], "columns": "method"})
    assert pivot.data.drop(columns=["data_share"]).sum().sum() == len(df)


def test_a_line_figure_says_which_rows_it_cannot_place(tmp_path):
    df = mixed_rows()
    _, figure = default_declarations(CFG, df)
    assert figure["x"] == "data_share"
    got = declared_figure(df, figure, tmp_path, 1)
    assert got.caption.startswith(figure["caption"])
    lacking = int(df["data_share"].isna().sum())
    assert lacking == 10 and len(df) == 30
    assert f"Not drawn: the {lacking} of {len(df)} ok rows of the data sets without share (squares)" in got.caption
    assert (tmp_path / got.file).is_file()
    complete = declared_figure(df[df["dataset"] == "outliers"], figure, tmp_path, 2)
    assert complete.caption == figure["caption"]
