"""Config slips a user makes, each told in one line before any row runs: a grid value given twice, a size limit
counted on the rows that will run (methods' ``on`` leave some data sets out), a name with letters the file system
rules out, a table asking for no digits."""
from __future__ import annotations

import pytest

from experiments import config as configs
from experiments import run
from experiments.study import ConfigError

STUDY = '''
name = "{name}"
title = "t"
seed = 1
repetitions = 3
[[datasets]]
source = "circle"
label = "circle"
params = {{ n = 20, noise = 0.01 }}
grid = {{ arc_deg = {arcs} }}
[[datasets]]
source = "ellipse"
label = "ellipse"
params = {{ n = 20 }}
[[methods]]
id = "circle.kasa"
on = ["circle"]
[[methods]]
id = "circle.pratt"
on = ["circle"]
[[methods]]
id = "ellipse.fitzgibbon"
on = ["ellipse"]
{extra}
'''


def _load(tmp_path, name="slips", arcs="[90.0, 360.0]", extra=""):
    path = tmp_path / f"{name}.toml"
    path.write_text(STUDY.format(name=name, arcs=arcs, extra=extra), encoding="utf-8")
    return configs.load(str(path))


def test_the_row_limit_counts_the_rows_that_will_run(tmp_path):
    cfg = _load(tmp_path)
    rows = len(list(cfg.grid_tasks()))
    assert rows == 2 * 3 * 2 + 3 * 1  # circle: 2 arcs x 3 repetitions x 2 methods; ellipse: 3 x 1
    run.check_size(cfg, rows)  # exactly at the limit: accepted (the grid's bound, 27 rows, was refused)
    with pytest.raises(ConfigError, match=f"the grid has {rows} rows, more than the limit of {rows - 1}; .*"
                                          f"--max-rows {rows}$"):
        run.check_size(cfg, rows - 1)


@pytest.mark.parametrize("arcs, said", [("[90.0, 90.0]", "90.0 appears twice"),
                                        ("[90, 90.0]", "90 and 90.0 are the same value")])
def test_a_grid_value_given_twice_is_refused(tmp_path, arcs, said):
    with pytest.raises(ConfigError, match=f"datasets\\[0\\]: grid.arc_deg: {said}; give each value once"):
        _load(tmp_path, arcs=arcs).expand_datasets()


def test_the_name_rule_says_ascii_and_a_table_needs_a_digit(tmp_path):
    with pytest.raises(ConfigError, match=r"'mesure_é' is not allowed .*ASCII letters A-Z a-z, digits, _ and -"):
        _load(tmp_path, name="mesure_é")
    table = '[[tables]]\ncaption = "c"\nrows = "method"\nvalues = "form_error"\ndigits = 0'
    with pytest.raises(ConfigError, match=r"tables\[0\]\.digits: must be >= 1, got 0"):
        _load(tmp_path, extra=table)
