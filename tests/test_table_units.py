"""A declared table's ``unit`` converts its values from their own unit (a length in mm shown in µm is multiplied by
1000; radians shown in degrees by 180/π); a unit that cannot be reached (a length of a generator's data, in no known
unit, asked in µm) is refused when the study is loaded, in one line. A table declaring no unit carries its values'
own unit, as the default table does. Before: ``unit = "um"`` labelled the mm values µm (1000x wrong) and a table
without a unit showed lengths with none."""
import json
import math
import textwrap

import numpy as np
import pandas as pd
import pytest

from conftest import REPO
from experiments import config as configs
from experiments.study import ConfigError
from experiments.tables import declared_table
from experiments.units import DATA_UNITS

FILE_STUDY = {"name": "u", "datasets": [{"file": "trace.csv"}]}          # lengths in mm
GENERATOR_STUDY = {"name": "u", "datasets": [{"source": "circle"}]}     # lengths in the data's own unit


def rows() -> pd.DataFrame:
    rng = np.random.default_rng(3)
    out = []
    for method in ("circle.kasa", "circle.gauss_newton"):
        for arc in (360.0, 90.0):
            for rep in range(3):
                out.append({"method": method, "data_arc_deg": arc, "repetition": rep, "status": "ok",
                            "form_error": rng.uniform(0.001, 0.004), "center_error": rng.uniform(0, 1e-3),
                            "angle": rng.uniform(-1, 1)})
    out.append({"method": "circle.kasa", "data_arc_deg": 360.0, "repetition": 9, "status": "error",
                "form_error": np.nan, "center_error": np.nan, "angle": np.nan})
    return pd.DataFrame(out)


def table(**declared) -> dict:
    return {"caption": "c", "rows": "method", "values": "form_error", "aggregate": "mean", **declared}


@pytest.mark.parametrize("unit, per_mm", [("um", 1e3), ("µm", 1e3), ("nm", 1e6), ("m", 1e-3)])
def test_a_length_in_mm_is_converted_to_the_declared_unit(unit, per_mm):
    df = rows()
    got = declared_table(df, table(unit=unit), FILE_STUDY)
    assert got.unit == unit
    ok = df[df["status"] == "ok"]
    for method, g in ok.groupby("method"):
        cell = got.data.loc[got.data["method"] == method, "mean of form error"].item()
        assert cell == pytest.approx(g["form_error"].mean() * per_mm, rel=1e-12)


def test_the_column_s_own_unit_is_no_conversion():
    df = rows()
    plain = declared_table(df, table(), FILE_STUDY)
    assert plain.unit == "mm"     # no unit declared: the values' own, as the default table
    assert declared_table(df, table(unit="mm"), FILE_STUDY).data.equals(plain.data)


def test_a_pivot_and_an_angle_are_converted_too():
    df = rows()
    got = declared_table(df, {**table(unit="um", aggregate="rmse"), "columns": "data_arc_deg"}, FILE_STUDY)
    for (method, arc), g in df[df["status"] == "ok"].groupby(["method", "data_arc_deg"]):
        cell = got.data.loc[got.data["method"] == method, f"arc = {arc:g} °"].item()
        assert cell == pytest.approx(np.sqrt(np.mean(g["form_error"] ** 2)) * 1e3, rel=1e-12)
    # an angle column declared in rad (methods.results) shown in degrees
    from methods import results
    angle = next(name for name, col in results.row_columns().items() if col.unit == "rad")
    df = df.rename(columns={"angle": angle})
    deg = declared_table(df, table(values=angle, unit="deg", aggregate="max"), FILE_STUDY)
    rad = declared_table(df, table(values=angle, aggregate="max"), FILE_STUDY)
    assert rad.unit == "rad" and deg.unit == "deg"
    words = [c for c in deg.data.columns if c != "method"][0]
    assert np.allclose(deg.data[words], np.degrees(rad.data[words]), rtol=1e-12, atol=0)


def test_a_count_keeps_no_unit():
    got = declared_table(rows(), table(aggregate="count"), FILE_STUDY)
    assert got.unit == "" and set(got.data.iloc[:, 1]) == {6}


def test_lengths_of_a_generator_without_a_unit_are_in_data_units():
    got = declared_table(rows(), table(), GENERATOR_STUDY)
    assert got.unit == DATA_UNITS and got.caption.startswith("c. Lengths are in the unit of the data")
    assert "length_unit" in got.caption
    assert declared_table(rows(), table(), {**GENERATOR_STUDY, "length_unit": "R"}).unit == "R"


STUDY = '''\
name = "u"
title = "t"
seed = 1
repetitions = 1
{length_unit}
[[datasets]]
{data}
[[methods]]
id = "circle.kasa"
[[tables]]
caption = "c"
rows = "method"
values = "form_error"
unit = "{unit}"
'''
GENERATOR = 'source = "circle"\nparams = { radius = 5.0, noise = 0.01, n = 12 }'


@pytest.mark.parametrize("unit, length_unit, message", [
    ("um", "", "tables[0].unit: 'form_error' is in the unit of the data (a generator's lengths are those of its own "
               "radius and noise), which cannot be converted to 'um': name it with the study's length_unit "
               "(length_unit = \"mm\" if they are in mm, then a table may show them in um), or drop the table's unit"),
    ("R", "", "cannot be converted to 'R': name it with the study's length_unit (length_unit = \"R\")"),
    ("um", 'length_unit = "R"', "'form_error' is in R (the study's length_unit), which cannot be converted to 'um': "
                                "declare unit = 'R', or drop the table's unit"),
    ("deg", 'length_unit = "mm"', "'form_error' is a length in mm, not in 'deg'"),
])
def test_a_unit_that_cannot_be_reached_is_refused_at_load(tmp_path, unit, length_unit, message):
    path = tmp_path / "u.toml"
    path.write_text(STUDY.format(unit=unit, length_unit=length_unit, data=GENERATOR), encoding="utf-8")
    with pytest.raises(ConfigError) as err:
        configs.load(str(path))
    assert message in str(err.value) and "\n" not in str(err.value), str(err.value)


@pytest.mark.parametrize("unit, length_unit", [("um", 'length_unit = "mm"'), ("mm", ""), ("R", 'length_unit = "R"')])
def test_a_unit_that_can_be_reached_loads(tmp_path, unit, length_unit):
    path = tmp_path / "u.toml"
    path.write_text(STUDY.format(unit=unit, length_unit=length_unit, data=GENERATOR), encoding="utf-8")
    configs.load(str(path))


def kasa_form_error(path) -> float:
    """The form error (mm) of the Kåsa circle of an x, y file in mm, in plain NumPy: the least-squares solution of
    x² + y² = 2ax + 2by + c, then the span of the distances to (a, b)."""
    x, y = np.loadtxt(path, delimiter=",", skiprows=1).T
    sol = np.linalg.lstsq(np.column_stack([x, y, np.ones_like(x)]), x ** 2 + y ** 2, rcond=None)[0]
    r = np.hypot(x - sol[0] / 2, y - sol[1] / 2)
    return float(r.max() - r.min())


@pytest.mark.slow
def test_the_report_csv_and_json_show_the_form_error_in_micrometres(tmp_path):
    """The example trace (mm) with a table in µm, one in mm and one without a unit: the report (md, html, tex), the
    table CSV and report.json agree with the form error of an independent fit of the same file (methods.fit), x1000."""
    import shutil

    from experiments import run as runner
    shutil.copy(REPO / "docs" / "examples" / "trace.csv", tmp_path / "trace.csv")
    study = STUDY.format(unit="um", length_unit="", data='file = "trace.csv"') + textwrap.dedent('''\
        [[tables]]
        caption = "in mm"
        rows = "method"
        values = "form_error"
        unit = "mm"
        [[tables]]
        caption = "no unit"
        rows = "method"
        values = "form_error"
        ''')
    (tmp_path / "u.toml").write_text(study, encoding="utf-8")
    assert runner.main([str(tmp_path / "u.toml"), "--out", str(tmp_path / "out"), "--jobs", "1"]) == 0
    form_mm = kasa_form_error(tmp_path / "trace.csv")
    folder = tmp_path / "out" / "u"
    manifest = json.loads((folder / "report.json").read_text(encoding="utf-8"))
    assert [t["unit"] for t in manifest["tables"]] == ["um", "mm", "mm"]
    cells = [pd.read_csv(folder / t["file"])["mean of form error"].item() for t in manifest["tables"]]
    # the CSV keeps 10 digits; a fit of coordinates near 170 mm agrees to ~1e-11 mm whatever the solver
    assert cells[0] == pytest.approx(form_mm * 1e3, rel=1e-7) and cells[1] == cells[2] == pytest.approx(form_mm, rel=1e-7)
    shown_um, shown_mm = f"{form_mm * 1e3:.4g}", f"{form_mm:.4g}"
    assert math.isclose(float(shown_um), form_mm * 1e3, rel_tol=1e-3)
    paper = tmp_path / "out" / "paper"
    md = (paper / "report.md").read_text(encoding="utf-8")
    assert f"mean of form error \\[µm\\]" in md and md.count("mean of form error \\[mm\\]") == 2
    lines = [line for line in md.splitlines() if line.startswith("| circle.kasa")]
    assert [line.split("|")[2].strip() for line in lines] == [shown_um, shown_mm, shown_mm], lines
    html = (paper / "report.html").read_text(encoding="utf-8")
    assert "mean of form error [µm]" in html and html.count("mean of form error [mm]") == 2 and shown_um in html
    tex = (paper / "tables" / "table-1.tex").read_text(encoding="utf-8")
    assert r"\si{\micro\metre}" in tex and f"circle.kasa & {shown_um} \\\\" in tex
    assert r"\si{\milli\metre}" in (paper / "tables" / "table-3.tex").read_text(encoding="utf-8")
