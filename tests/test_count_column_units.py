"""A [[tables]] or [[rankings]] declaration that gives a unit to a column of counts (the method's iterations,
function evaluations) or numbers (repetition, seed) is refused when the study is loaded, in one line. Before, a
table of the max of iterations with unit = "um" ran and was captioned 'Unit: µm.' over 'max of iterations 2'."""
import pytest

from experiments import config as configs
from experiments.study import ConfigError

STUDY = '''name = "c"
title = "c"
seed = 1
repetitions = 2
[[datasets]]
source = "circle"
params = { radius = 5.0, noise = 0.01, n = 30 }
[[methods]]
id = "circle.gauss_newton"
'''
TABLE = '[[tables]]\ncaption = "t"\nrows = ["method"]\nvalues = "{column}"\naggregate = "{how}"\n'


def load(tmp_path, text):
    path = tmp_path / "c.toml"
    path.write_text(STUDY + text, encoding="utf-8")
    return configs.load(str(path))


@pytest.mark.parametrize("column, how, words", [("iterations", "max", "a count (the method's iterations)"),
                                                ("nfev", "median", "a count (function evaluations)"),
                                                ("repetition", "max", "a number (the repetition's)")])
@pytest.mark.parametrize("unit", ["um", "mm", "s", "rad"])
def test_a_unit_on_a_count_column_of_a_table_is_refused(tmp_path, column, how, words, unit):
    with pytest.raises(ConfigError) as err:
        load(tmp_path, TABLE.format(column=column, how=how) + f'unit = "{unit}"\n')
    text = str(err.value)
    assert f"tables[0].unit: {column!r} is {words}, which has no unit: drop the unit {unit!r}" in text, text
    assert "\n" not in text


def test_a_unit_on_a_count_metric_of_a_ranking_is_refused(tmp_path):
    with pytest.raises(ConfigError) as err:
        load(tmp_path, '[[rankings]]\nprofile = "p"\nmetric = "iterations"\nunit = "um"\n')
    assert "rankings[0].unit: 'iterations' is a count (the method's iterations), which has no unit" in str(err.value)


def test_a_count_column_without_unit_loads(tmp_path):
    load(tmp_path, TABLE.format(column="iterations", how="max")
         + '[[rankings]]\nprofile = "p"\nmetric = "nfev"\n')
