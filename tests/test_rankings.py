"""Cross-study rankings are open: every method run on the pooled problems is profiled without a config edit, a
study declaring a ranking never removes a method from it, and a problem no method solved counts for nobody."""
from pathlib import Path

import numpy as np
import pandas as pd

from experiments.render.profiles import performance_ratios, profile
from experiments.render.rankings import collect

DECL = {"profile": "circularity", "metric": "form_error", "methods": "circle.*"}


def study(tmp_path, name, costs: dict, status=None):
    """A study folder whose rows give each method (key) its costs on problems s0, s1, ... (NaN: failed)."""
    folder = tmp_path / name
    folder.mkdir()
    rows = []
    for method, values in costs.items():
        for i, v in enumerate(values):
            rows.append({"study": name, "dataset": "d", "data_stream": f"s{i}", "repetition": 0, "method": method,
                         "params": "{}", "status": "ok" if np.isfinite(v) else "not converged", "form_error": v})
    pd.DataFrame(rows).to_csv(folder / "results.csv", index=False)
    return name, folder, {"config": {"rankings": [DECL]}}


def test_a_new_study_with_fewer_methods_removes_none(tmp_path):
    """A user's study declaring the same profile with kasa and a plugin method: the existing profile keeps its
    four methods, and the plugin joins over the problems it ran on."""
    old = study(tmp_path, "published", {"circle.kasa": [1.0, 2.0], "circle.gauss_newton": [1.0, 1.5],
                                        "circle.minimum_zone": [0.5, 1.0], "circle.max_inscribed": [2.0, 3.0]})
    new = study(tmp_path, "mine", {"circle.kasa": [1.0], "circle.my_fit": [0.5]})
    before = collect([old])["circularity"]
    after = collect([old, new])["circularity"]
    assert set(before.table.columns) < set(after.table.columns)
    assert set(after.table.columns) == {"circle.kasa", "circle.gauss_newton", "circle.minimum_zone",
                                        "circle.max_inscribed", "circle.my_fit"}
    assert after.left_out == [] and len(after.table) == 3
    assert after.runs["circle.my_fit"] == 1 and after.runs["circle.kasa"] == 3
    rho = profile(after.table, taus=[1.0])
    assert rho.loc[1.0, "circle.my_fit"] == 1.0           # best on the one problem it ran on
    assert rho.loc[1.0, "circle.minimum_zone"] == 1.0     # best on both problems of 'published' it ran on
    assert rho.loc[1.0, "circle.kasa"] == 0.0


def test_a_problem_no_method_solved_counts_for_nobody(tmp_path):
    """Every method failed on s1 (inf == inf): it is left out, so kasa is not "best on 100 % of 2 problems"."""
    nan = float("nan")
    r = collect([study(tmp_path, "s", {"circle.kasa": [1.0, nan], "circle.taubin": [2.0, nan]})])["circularity"]
    assert r.unsolved == 1 and list(r.table.index) == ["s | d | s0 | 0"]
    best = (r.table.values == r.table.min(axis=1).values[:, None]).mean(axis=0)
    assert best.tolist() == [1.0, 0.0]
    ratios = performance_ratios(r.table)
    assert ratios.loc["s | d | s0 | 0"].tolist() == [1.0, 2.0]


def test_a_tie_names_every_best_method():
    """Two methods with the same cost on every problem are both best on all of them: the finding names both
    (it named the first column alone: 'circle.chebyshev_lp is best on 100 % of 8 problems')."""
    from types import SimpleNamespace

    from experiments.report import ranking_findings
    table = pd.DataFrame({"circle.chebyshev_lp": [1.0, 2.0, 3.0], "circle.kasa": [1.5, 2.5, 3.0],
                          "circle.minimum_zone": [1.0, 2.0 * (1 + 1e-9), 3.0]})
    words = ranking_findings({"circularity": SimpleNamespace(table=table)})
    assert words == ["circularity: circle.chebyshev_lp and circle.minimum_zone are best (tied within 1e-06 "
                     "relative) on 100 % of 3 problems"]
    alone = ranking_findings({"runtime": SimpleNamespace(table=table.assign(**{"circle.minimum_zone": [9.0] * 3}))})
    assert alone == ["runtime: circle.chebyshev_lp is best on 100 % of 3 problems"]


def test_ranking_units_per_study_from_the_metric_declarations(tmp_path):
    """A ranking without a declared unit takes the metric's declared unit (form_error: mm); a study on unit
    circles declares 'R'; the table of mixed rows says which study is in which unit, one in a single unit
    carries it."""
    import pytest

    published = study(tmp_path, "published", {"circle.kasa": [1.0], "circle.taubin": [2.0]})
    unit_circle = study(tmp_path, "noise", {"circle.kasa": [0.1], "circle.taubin": [0.2]})
    unit_circle[2]["config"]["rankings"] = [{**DECL, "unit": "R"}]
    alone = collect([published])["circularity"]
    assert alone.unit == "mm" and alone.unit_words() == ""
    mixed = collect([published, unit_circle])["circularity"]
    assert mixed.unit == "" and mixed.units == {"published": "mm", "noise": "R"}
    assert mixed.unit_words() == "mm: published; R (relative to the radius R of the data's circle): noise"
    wrong = study(tmp_path, "wrong", {"circle.kasa": [1.0]})
    wrong[2]["config"]["rankings"] = [{**DECL, "unit": "s"}]
    with pytest.raises(ValueError, match="declares unit 's' for metric 'form_error'.*a length"):
        collect([wrong])


def test_the_report_ranking_table_states_units(tmp_path):
    """The report's median table of a ranking: a unit in the caption, per study when the rows mix units."""
    from experiments.report import _rankings_section

    published = study(tmp_path, "published", {"circle.kasa": [1.0], "circle.taubin": [2.0]})
    unit_circle = study(tmp_path, "noise", {"circle.kasa": [0.1], "circle.taubin": [0.2]})
    unit_circle[2]["config"]["rankings"] = [{**DECL, "unit": "R"}]
    captions = []

    class Doc:
        def heading(self, *a, **k): pass
        def prose(self, *a, **k): pass

    def add_table(table, caption, unit, digits, colour=""):
        captions.append((caption, unit))
        return []
    for studies, want in (([published], ("", "mm")), ([published, unit_circle], ("mm: published; R", ""))):
        captions.clear()
        _rankings_section(collect(studies), None, tmp_path, add_table, lambda *a: [], Doc())
        (caption, unit), = captions
        assert want[0] in caption and unit == want[1]


def test_rows_without_the_metric_are_not_unsolved_problems(tmp_path):
    """Rows that finished (ok) with no value of the metric at all (the published study's rounding Monte Carlo
    rows: no form error, no runtime) are not problems of the ranking: they are neither in the table nor counted
    as solved by no method (the report's caption said "9 solved by no method left out")."""
    nan = float("nan")
    name, folder, meta = study(tmp_path, "published", {"circle.kasa": [1.0, 2.0], "circle.taubin": [2.0, nan]})
    rows = pd.read_csv(folder / "results.csv")
    extra = pd.DataFrame([{"study": name, "dataset": "d (rounding Monte Carlo)", "data_stream": "s0", "repetition": 0,
                           "method": m, "params": "{}", "status": "ok", "form_error": nan}
                          for m in ("circle.kasa", "circle.taubin")])
    pd.concat([rows, extra]).to_csv(folder / "results.csv", index=False)
    r = collect([(name, folder, meta)])["circularity"]
    assert r.unsolved == 0 and r.not_measured == 1
    assert sorted(r.table.index) == ["published | d | s0 | 0", "published | d | s1 | 0"]
    # a problem every method failed on is still unsolved, not "not measured"
    failed = study(tmp_path, "noise", {"circle.kasa": [nan], "circle.taubin": [nan]})
    r2 = collect([(name, folder, meta), failed])["circularity"]
    assert r2.unsolved == 1 and r2.not_measured == 1


def test_the_explorer_shows_every_cost_with_its_unit(tmp_path):
    """explorer.html's axes and hovers named the bare column ('form_error', 'time_median_s') and a ranking that
    pools studies in different units (mm and R) showed no unit at all: the page's data now carry a readable label
    and every problem's unit (the runtime panels group by it). They no longer carry the joined 'axis_unit'
    ("mm (published) or R (noise)"), which the script stopped reading when the panels came."""
    from experiments.render.explorer import ranking_data
    published = study(tmp_path, "published", {"circle.kasa": [1.0], "circle.taubin": [2.0]})
    noise = study(tmp_path, "noise", {"circle.kasa": [0.1], "circle.taubin": [0.2]})
    noise[2]["config"]["rankings"] = [{**DECL, "unit": "R"}]
    r = collect([published, noise])["circularity"]
    folders = {name: folder for name, folder, _ in (published, noise)}
    data = ranking_data("circularity", r, folders, {})
    assert data["label"] == "form error"
    assert dict(zip(data["problems"], data["units"])) == {"published | d | s0 | 0": "mm", "noise | d | s0 | 0": "R"}
    alone = ranking_data("circularity", collect([published])["circularity"], folders, {})
    assert alone["units"] == ["mm"]
    script = (Path(__file__).resolve().parents[1] / "experiments" / "render" / "templates" / "explorer.js").read_text()
    assert "axis_unit" not in data and "axis_unit" not in alone and "axis_unit" not in script
    # the hovers name each problem's unit; the runtime plot's y axes name their panel's unit (one panel per unit)
    assert "esc(r.metric)" not in script and "panel.unit" in script and "r.units[i]" in script


def test_medians_per_data_set_are_over_the_problems_every_method_ran_on(tmp_path):
    """A method skipped on a data set's hardest problem (max_n) had its median over its easier problems only, and
    looked best (the report's 'scaling: circle': Nelder–Mead 0.028 beside the minimum zone's 0.032, though above it
    at every N). Each method's median is now over the problems every method of the row ran on, and the caption says
    which data set lost problems."""
    from experiments.report import _rankings_section

    name, folder, meta = study(tmp_path, "scaling", {"circle.minimum_zone": [1.0, 2.0, 9.0],
                                                     "circle.nelder_mead": [1.1, 2.2, 9.9]})
    rows = pd.read_csv(folder / "results.csv")
    rows = rows[~((rows["method"] == "circle.nelder_mead") & (rows["data_stream"] == "s2"))]   # not run on s2
    rows.to_csv(folder / "results.csv", index=False)
    r = collect([(name, folder, meta)])["circularity"]
    med = r.by_dataset.loc["scaling: d"]
    assert med["circle.minimum_zone"] < med["circle.nelder_mead"]
    assert med["circle.minimum_zone"] == np.median([1.0, 2.0]) and med["circle.nelder_mead"] == np.median([1.1, 2.2])
    assert r.dataset_notes == ["scaling: d: 2 of its 3 problems (circle.nelder_mead ran on 2)"]
    captions = []

    class Doc:
        def heading(self, *a, **k): pass
        def prose(self, *a, **k): pass

    _rankings_section({"circularity": r}, None, tmp_path, lambda t, c, *a: captions.append(c) or [],
                      lambda *a: [], Doc())
    assert "scaling: d: 2 of its 3 problems (circle.nelder_mead ran on 2)" in captions[0]
    # a data set on which no problem was run by every method of its row is left out, and said so
    other = study(tmp_path, "other", {"circle.minimum_zone": [1.0], "circle.nelder_mead": [2.0]})
    rows = pd.read_csv(other[1] / "results.csv")
    rows.loc[rows["method"] == "circle.nelder_mead", "data_stream"] = "s1"
    rows.to_csv(other[1] / "results.csv", index=False)
    r2 = collect([other])["circularity"]
    assert r2.by_dataset.empty and r2.dataset_notes == [
        "left out, no problem that every method of the row ran on: other: d"]


def test_a_method_not_run_on_a_data_set_is_not_shown_failed(tmp_path):
    """A method run by one study only was shown 'failed' (grey) in the other studies' rows of the HTML median
    table: not run is not failed. A median of inf (failed on at least half) stays 'failed'; not run is '–',
    uncoloured."""
    import re

    from experiments.render.report_tables import html_table
    nan = float("nan")
    a = study(tmp_path, "a", {"circle.kasa": [1.0, 2.0], "circle.max_inscribed": [nan, nan]})
    b = study(tmp_path, "b", {"circle.kasa": [1.0], "circle.max_inscribed": [2.0], "circle.plugin": [0.5]})
    r = collect([a, b])["circularity"]
    med = r.by_dataset
    assert np.isinf(med.loc["a: d", "circle.max_inscribed"]) and np.isnan(med.loc["a: d", "circle.plugin"])
    html = html_table(med.reset_index(), caption="c", unit="mm", digits=3, colour="lower_is_better")
    cells = dict(re.findall(r'<td[^>]*class="data (row0 col\d+) num" >([^<]*)', html))
    assert cells["row0 col1"] == "failed" and cells["row0 col2"] == "–"
    assert "T_table_row0_col2" not in html.split("</style>")[0]   # no colour for a cell without a value
