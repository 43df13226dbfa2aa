"""Number formats a reader sees: never ×10⁰, one format per column (not scientific beside plain), whole
cut-offs as integers, a unit said once in a caption, the Markdown table in the same formats as the HTML."""
import numpy as np
import pandas as pd

from experiments.render.numbers import NumberFormat, column_format
from experiments.render.report_tables import html_table, text_frame
from experiments.report import _with_unit

#: median runtimes [ms] of the scaling study's N = 10 column (committed results): 1.6 ms beside 0.008 ms
RUNTIMES = [1.605, 0.048, 0.01, 0.008, 0.057, 1.419, 0.438, 1.783, 2.299, 0.175, 16.647, 12.071]


def test_never_times_ten_to_the_zero():
    assert NumberFormat("exponent", 3).text(5.115) == "5.115"
    assert NumberFormat("exponent", 3).text(51.15) == "5.115×10¹"


def test_a_column_spanning_a_few_decades_is_plain_in_one_format():
    fmt = column_format(RUNTIMES, 4)
    texts = [fmt.text(v) for v in RUNTIMES]
    assert fmt.kind == "fixed" and not any("×" in t for t in texts)
    assert len({len(t.split(".")[1]) for t in texts}) == 1                  # one number of decimals
    assert all(len(t.replace("0.", "").lstrip("0")) >= 2 for t in texts)  # two digits of the smallest kept
    html = html_table(pd.DataFrame({"method": list("abcdefghijkl"), "N=10 [ms]": RUNTIMES}), caption="c", unit="ms")
    assert "×10" not in html


def test_markdown_cells_are_the_html_formats():
    df = pd.DataFrame({"method": ["a", "b"], "error": [0.048, 0.05], "runs": [3.0, 12.0]})
    shown = text_frame(df, unit="mm", digits=4)
    assert list(shown.columns) == ["method", "error [mm]", "runs"]
    fmt = column_format([0.048, 0.05], 4)
    assert list(shown["error [mm]"]) == [fmt.text(0.048), fmt.text(0.05)] and list(shown["runs"]) == ["3", "12"]
    assert shown["error [mm]"].str.len().nunique() == 1           # '0.05' is not shown beside '0.048'


def test_unit_said_once_in_a_caption():
    assert _with_unit("Error of each method [mm]", "mm") == "Error of each method [mm]"
    assert _with_unit("Error of each method", "mm") == "Error of each method. Unit: mm."
    assert _with_unit("RONt [µm] and share [%]", "µm, %") == "RONt [µm] and share [%]"


def test_whole_cutoffs_print_as_integers():
    from experiments.studies.roundness import REFS, cutoff_table
    rows = pd.DataFrame({"dataset": ["p"] * 3, "cutoff_upr": [50.0, 500.0, "none"], "status": ["ok"] * 3,
                         **{f"RONt_{k}_um": np.ones(3) for k in REFS}, **{f"certified_{k}": [True] * 3 for k in REFS}})
    assert list(cutoff_table(rows)["cutoff_upr"]) == ["50", "500", "none"]
