"""Everything a study declares is checked before its first row (columns against the study's columns, plot
arguments, aggregates against column types, the findings template), with one line ``FILE: KEY: PROBLEM``;
findings are filled by a sandboxed template; a TOML-only study that declares nothing gets one table and one
figure chosen from its metrics, with units from the metric declarations."""
import textwrap

import numpy as np
import pandas as pd
import pytest

from experiments import config as configs
from experiments import analysis, figures, findings, tables, units
from experiments import study as contract
from experiments.study import ConfigError

STUDY = '''
name = "decl"
title = "Declarations"
kind = "grid"
seed = 1
repetitions = 2
[[datasets]]
source = "circle"
params = { radius = 5.0, noise = 0.01, n = 30 }
grid = { arc_deg = [360.0, 90.0, 22.5] }
[[methods]]
id = "circle.kasa"
[[methods]]
id = "circle.gauss_newton"
'''


def write(tmp_path, extra: str):
    path = tmp_path / "decl.toml"
    path.write_text(textwrap.dedent(STUDY) + textwrap.dedent(extra))
    return path


BAD = {
    "unknown column in y": ('[[figures]]\nplot = "lines"\nx = "data_arc_deg"\ny = "radius_eror"\ncaption = "c"\n',
                            "decl.toml: figures[0].y: no row will have the column 'radius_eror'; did you mean 'radius_error'?"),
    "unknown column in by": ('[[figures]]\nplot = "lines"\nx = "data_arc_deg"\ny = "radius_error"\nby = "methd"\ncaption = "c"\n',
                             "decl.toml: figures[0].by: no row will have the column 'methd'"),
    "unknown column in where": ('[[tables]]\ncaption = "c"\nrows = "method"\nvalues = "radius_error"\nwhere = { arc = 90.0 }\n',
                                "decl.toml: tables[0].where: no row will have the column 'arc'"),
    "unknown plot argument": ('[[figures]]\nplot = "lines"\nx = "data_arc_deg"\ny = "radius_error"\ncaption = "c"\n'
                              'args = { colour = "red" }\n',
                              "decl.toml: figures[0]: plot 'lines': got an unexpected keyword argument 'colour'"),
    "a list for values": ('[[tables]]\ncaption = "c"\nrows = "method"\nvalues = ["radius_error", "center_error"]\n',
                          "decl.toml: tables[0].values: must be one column name"),
    "the mean of a text column": ('[[tables]]\ncaption = "c"\nrows = "dataset"\nvalues = "method"\n',
                                  "decl.toml: tables[0].aggregate: the mean of 'method' (a text column) is not defined"),
    "the rmse of a text column in a figure": ('[[figures]]\nplot = "bars"\nx = "method"\ny = "status"\naggregate = "rmse"\n'
                                              'caption = "c"\n', "decl.toml: figures[0].aggregate: the rmse of 'status'"),
    "unknown column in rows": ('[[tables]]\ncaption = "c"\nrows = ["method", "arc"]\nvalues = "radius_error"\n',
                               "decl.toml: tables[0].rows: no row will have the column 'arc'"),
    "a degree column labelled mm": ('[[tables]]\ncaption = "c"\nrows = "method"\nvalues = "data_arc_deg"\nunit = "mm"\n',
                                    "decl.toml: tables[0].unit: 'data_arc_deg' is in °, not a length ('mm')"),
    "an attribute in the findings": ('[report]\nfindings = "{n_rows.foo}"\n', "decl.toml: report.findings: {n_rows.foo}: a field is a plain value name"),
    "a huge width in the findings": ('[report]\nfindings = "{n_rows:>300000000}"\n', "decl.toml: report.findings: {n_rows:>300000000}: the format spec"),
    "the class of a value": ('[report]\nfindings = "{n_rows.__class__.__mro__}"\n', "report.findings: {n_rows.__class__.__mro__}"),
    "an item in the findings": ('[report]\nfindings = "{n_rows[0]}"\n', "report.findings: {n_rows[0]}"),
    "an unknown value in the findings": ('[report]\nfindings = "{best_method} wins"\n',
                                         "decl.toml: report.findings: unknown value(s) best_method (the values: n_ok, n_rows)"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_declarations_are_refused_at_load_in_one_line(tmp_path, case):
    extra, message = BAD[case]
    with pytest.raises(ConfigError) as err:
        configs.load(str(write(tmp_path, extra)))
    text = str(err.value)
    assert message in text and "\n" not in text, text


def test_good_declarations_load(tmp_path):
    configs.load(str(write(tmp_path, '''
        [report]
        findings = "{n_ok} of {n_rows:,d} fits converged ({n_ok:>5})."
        [[tables]]
        caption = "Radius RMSE by arc"
        rows = ["method"]
        columns = "data_arc_deg"
        values = "radius_error"
        aggregate = "rmse"
        unit = "mm"
        where = { method = ["circle.kasa"] }
        [[figures]]
        plot = "lines"
        x = "data_arc_deg"
        y = "radius_error"
        by = "method"
        aggregate = "rmse"
        caption = "Radius RMSE against the arc"
    ''')))


def test_findings_are_rendered_by_a_sandbox():
    values = {"n_rows": 12, "n_ok": np.int64(10), "best": "circle.kasa", "rmse": 1.25e-3}
    text = findings.render_findings("{best} best: {rmse:.2e} mm; {n_ok} of {n_rows}\n<!--block:zz-->", values)
    assert text == "circle.kasa best: 1.25e-03 mm; 10 of 12 <!--block:zz-->"   # one paragraph, no line of its own
    for bad in ("{n_rows.__class__}", "{n_rows[0]}", "{0}", "{n_rows!r}", "{n_rows:>1000}", "{n_rows:{n_ok}}"):
        with pytest.raises(ValueError):
            findings.render_findings(bad, values)
    with pytest.raises(ValueError, match="unknown value 'x'"):
        findings.render_findings("{x}", values)


def rows_of_a_toml_only_study() -> pd.DataFrame:
    rng = np.random.default_rng(0)
    rows = []
    for arc in (360.0, 90.0, 22.5):
        for m in ("circle.kasa", "circle.gauss_newton"):
            for r in range(3):
                rows.append({"study": "decl", "dataset": "circle", "data_arc_deg": arc, "data_stream": f"0.{r}",
                             "repetition": r, "method": m, "params": "{}", "status": "ok",
                             "form_error": rng.uniform(0.01, 0.02), "radius": 5.0, "center_error": rng.uniform(0, 1e-3),
                             "radius_error": rng.normal(0, 1e-3)})
    return pd.DataFrame(rows)


def test_an_undeclared_toml_study_gets_a_table_and_a_figure_with_units(tmp_path):
    cfg = configs.load(str(write(tmp_path, "")))
    study = contract.study_of("grid")
    _, analysed = analysis.analyse(study, rows_of_a_toml_only_study(), cfg, tmp_path, log=lambda *a: None)
    assert len(analysed.tables) == 1 and len(analysed.figures) == 1
    table = analysed.tables[0]
    # a generator's lengths are in the unit of its own parameters: the data's unit, mm only when declared
    assert table.unit == units.DATA_UNITS and "center error" in table.caption and "center_error" not in table.caption
    declared = dict(cfg)
    declared["length_unit"] = "mm"
    assert analysis.default_declarations(declared, rows_of_a_toml_only_study())[0]["unit"] == "mm"
    # the degree column is a key named with its own unit: the table's mm never labels it
    # and a pivot's column names carry the key's unit, not the table's (read as 'arc 360 °', never 'arc [mm]')
    assert list(table.data.columns) == ["method", "arc = 360 °", "arc = 90 °", "arc = 22.5 °"]
    assert (tmp_path / analysed.figures[0].file).is_file()


def test_a_declared_table_names_the_unit_of_its_numeric_key(tmp_path):
    table = tables.declared_table(rows_of_a_toml_only_study(), {"caption": "c", "rows": ["data_arc_deg", "method"],
                                                                  "values": "radius_error", "unit": "mm"})
    assert list(table.data.columns) == ["arc [°]", "method", "mean of radius error"]


def test_figure_axes_carry_units(tmp_path, monkeypatch):
    seen = {}
    monkeypatch.setitem(contract.PLOTS, "probe", lambda df, ax, *, x, y, by=None, aggregate="mean", xlabel=None,
                        ylabel=None: seen.update(xlabel=xlabel, ylabel=ylabel))
    figures.declared_figure(rows_of_a_toml_only_study(), {"plot": "probe", "x": "data_arc_deg", "y": "center_error", "aggregate": "rmse", "caption": "c"}, tmp_path, 1)
    assert seen == {"xlabel": "arc [°]", "ylabel": "RMSE of center error [mm]"}
