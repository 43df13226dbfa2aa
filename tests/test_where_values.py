"""A ``where`` value of a ``[[tables]]``, ``[[figures]]`` or ``[[rankings]]`` declaration that no row will hold (a
method id with a typo, a grid value the study does not have) is refused when the config is loaded, in one line with
the close match: it gave an empty table and an empty figure, exit 0, without a word. The values of the generic
grid's identity columns are known from its config (``experiments.declarations.known_values``)."""
from __future__ import annotations

import pytest

from cli_calls import call, one_error_line
from experiments import config as configs
from experiments import run
from experiments.declarations import known_values
from experiments.study import ConfigError

STUDY = '''
name = "wh"
title = "w"
seed = 1
[[datasets]]
source = "circle"
label = "arcs"
params = {{ radius = 5.0, noise = 0.01 }}
grid = {{ n = [30, 60] }}
[[datasets]]
source = "ellipse"
label = "ellipses"
params = {{ n = 40 }}
[[methods]]
id = "circle.kasa"
on = ["arcs"]
[[methods]]
id = "circle.gauss_newton"
on = ["arcs"]
grid = {{ stop = ["step", "gradient"] }}
[[methods]]
id = "ellipse.fitzgibbon"
on = ["ellipses"]
max_n = 20
{extra}
[quick]
datasets = [{{ source = "circle", label = "arcs", params = {{ radius = 5.0, noise = 0.01, n = 30 }} }},
            {{ source = "ellipse", label = "ellipses", params = {{ n = 40 }} }}]
'''

TABLE = '[[tables]]\ncaption = "t"\nrows = ["method"]\nvalues = "radius_error"\nwhere = {where}\n'
FIGURE = '[[figures]]\nplot = "lines"\nx = "data_n"\ny = "radius_error"\ncaption = "f"\nwhere = {where}\n'
RANKING = '[[rankings]]\nprofile = "p"\nmetric = "radius_error"\nwhere = {where}\n'


def _write(tmp_path, extra):
    path = tmp_path / "wh.toml"
    path.write_text(STUDY.format(extra=extra), encoding="utf-8")
    return path


@pytest.mark.parametrize("extra, said", [
    (TABLE.format(where='{ method = "circle.kasaa" }'),
     "tables[0].where.method: 'circle.kasaa' matches no row (did you mean 'circle.kasa'?); the rows' method will be: "
     "circle.gauss_newton, circle.kasa"),
    (FIGURE.format(where="{ data_n = 31 }"), "figures[0].where.data_n: 31 matches no row; the rows' data_n will be: 30, 60"),
    (FIGURE.format(where='{ data_n = "30" }'), "figures[0].where.data_n: '30' matches no row"),
    (TABLE.format(where='{ method = ["circle.kasa", "circle.gauss_newtn"] }'),
     "tables[0].where.method: 'circle.gauss_newtn' matches no row (did you mean 'circle.gauss_newton'?)"),
    (TABLE.format(where='{ param_stop = "objective" }'), "tables[0].where.param_stop: 'objective' matches no row"),
    # ellipse.fitzgibbon's max_n = 20 leaves it no data set (n = 40): no row of it, nor of the ellipses
    (TABLE.format(where='{ method = "ellipse.fitzgibbon" }'), "tables[0].where.method: 'ellipse.fitzgibbon' matches no row"),
    (RANKING.format(where='{ dataset = "ellipses" }'), "rankings[0].where.dataset: 'ellipses' matches no row"),
])
def test_a_where_value_no_row_will_hold_is_refused(tmp_path, extra, said):
    with pytest.raises(ConfigError) as caught:
        configs.load(str(_write(tmp_path, extra)))
    assert said in str(caught.value) and "\n" not in str(caught.value), str(caught.value)


def test_the_run_refuses_it_in_one_line(tmp_path):
    path = _write(tmp_path, TABLE.format(where='{ method = "circle.kasaa" }'))
    one_error_line(call(run.main, path, "--out", tmp_path / "out", "--no-report"),
                   "wh.toml: tables[0].where.method: 'circle.kasaa' matches no row")


def test_values_rows_will_hold_load_also_those_of_the_full_grid_in_a_quick_run(tmp_path):
    extra = (TABLE.format(where='{ method = ["circle.kasa", "circle.gauss_newton"], param_stop = "gradient" }')
             + FIGURE.format(where="{ data_n = [30.0, 60], study = \"wh\", dataset = \"arcs\" }"))
    path = _write(tmp_path, extra)
    configs.load(str(path))
    quick = configs.load(str(path), quick=True)  # data_n = 60: the full grid's (the quick one has n = 30 only)
    assert known_values(quick)["data_n"] == {30}


def test_the_values_are_those_of_the_rows(tmp_path):
    cfg = configs.load(str(_write(tmp_path, "")))
    rows = [t for t in cfg.grid_tasks()]
    values = known_values(cfg)
    assert values["method"] == {t["method"] for t in rows} and values["dataset"] == {t["dataset"]["label"] for t in rows}
    assert values["param_stop"] == {t["params"]["stop"] for t in rows if "stop" in t["params"]}
    assert values["data_n"] == {t["dataset"]["params"]["n"] for t in rows}
