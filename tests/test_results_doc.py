"""docs/results.md documents every status a row can have (and which run again) and every column of a fit row."""
import re

from conftest import REPO
from experiments import engine, report, rows
from experiments.timing import time_call
from methods import results
from methods.result_base import family_modules, result_classes

DOC = (REPO / "docs" / "results.md").read_text(encoding="utf-8")


def _section(title: str) -> str:
    return DOC.split(f"## {title}\n", 1)[1].split("\n## ", 1)[0]


def test_every_status_is_documented_with_whether_it_runs_again():
    table = {m.group(1): [c.strip() for c in m.group(2).split("|")]
             for m in re.finditer(r"^\| `([a-z ]+)` \|(.*)\|$", _section("Statuses"), re.M)}
    statuses = {"ok", *report.LEFT_OUT, *rows.RERUN_STATUSES, *rows.ENVIRONMENT_STATUSES}
    assert set(table) == statuses
    for status, cells in table.items():
        assert cells[-1].startswith("yes") == (status in rows.RERUN_STATUSES), (status, cells[-1])


def test_every_column_of_a_fit_row_is_documented():
    task = {"study": "s", "dataset": {"label": "d", "params": {"n": 10}}, "repetition": 0, "seed": 0,
            "stream": [0, 0, 0], "method": "circle.kasa", "params": {"xtol": 1e-9}}
    # engine.result_columns() holds every result class's columns: a plugin's (a test module's class) is not fitbench's
    # to document
    own = {c.name for cls in result_classes() if cls.__module__ in {"methods.result_base", *family_modules()}
           for c in cls.COLUMNS}
    plugins = {c.name for cls in result_classes() for c in cls.COLUMNS} - own
    columns = set(rows.base_row(task)) | (set(engine.result_columns()) - {"task_index"} - plugins)  # task_index: never written
    columns |= {c.name for family in ("circle", "ellipse") for c in results.contract(family).COLUMNS}
    columns |= set(time_call(lambda: None, min_time_s=1e-6, rounds=1))
    documented = set(re.findall(r"`([a-z_A-Z]+)`", _section("Columns of a fit row")))
    named = {"data_KEY" if c.startswith("data_") and c != "data_stream" else "param_KEY" if c.startswith("param_")
             else c for c in columns}
    assert named - documented == set()
