"""A ranking's ``unit`` and a study's ``length_unit`` never relabel lengths whose unit is known. Before: on data read
in mm, ``[[rankings]] unit = "um"`` and ``length_unit = "um"`` showed the mm values labelled µm (1000x too small) in
the ranking and in the study's default table and figure, and ``unit = "furlong"`` was taken as the unit of a
generator's lengths. Now a ranking converts lengths of a known unit (mm to µm: x 1000), names a generator's lengths
(R for unit circles, as the noise study declares), and anything else is refused when the study is loaded, in one
line; length_unit names a generator's lengths only."""
import json
import shutil

import pandas as pd
import pytest

from conftest import REPO
from experiments import config as configs
from experiments.render.rankings import collect
from experiments.study import ConfigError
from experiments.units import DATA_UNITS, length_unit_problem, metric_unit, ranking_unit

FILE = 'file = "trace.csv"\ntruth = { center = [120.0, 80.0], radius = 50.0 }'
GENERATOR = 'source = "circle"\nparams = { radius = 5.0, noise = 0.01, n = 12 }'


def toml(tmp_path, datasets=(FILE,), rankings=(), top=""):
    shutil.copy(REPO / "docs" / "examples" / "trace.csv", tmp_path / "trace.csv")
    text = f'name = "u"\ntitle = "t"\nseed = 1\nrepetitions = 1\n{top}\n'
    text += "".join(f"[[datasets]]\n{d}\n" for d in datasets)
    text += '[[methods]]\nid = "circle.kasa"\n[[methods]]\nid = "circle.taubin"\n'
    text += "".join(f'[[rankings]]\nprofile = "p{i}"\n{r}\n' for i, r in enumerate(rankings))
    path = tmp_path / "u.toml"
    path.write_text(text, encoding="utf-8")
    return str(path)


@pytest.mark.parametrize("datasets, rankings, top, message", [
    ((GENERATOR,), ('metric = "center_error"\nunit = "furlong"',), "",
     "rankings[0].unit: 'center_error' is a length, and 'furlong' is not a unit of length fitbench knows"),
    ((FILE,), ('metric = "form_error"\nunit = "R"',), "",
     "rankings[0].unit: 'form_error' is in mm (data read in mm), which cannot be shown in 'R'"),
    ((FILE, GENERATOR), ('metric = "form_error"\nunit = "um"',), "",
     "rankings[0].unit: unit 'um' would name the lengths of every data set of the study, and data set trace.csv "
     "(file) is read in mm"),
    ((GENERATOR,), ('metric = "form_error"\nunit = "R"', 'metric = "center_error"\nunit = "um"'), "",
     "the study's rankings name its lengths in R and um"),
    ((FILE,), (), 'length_unit = "um"',
     "length_unit: 'um' would relabel lengths that are in mm: data set trace.csv (file) is read in mm"),
    ((FILE, GENERATOR), (), 'length_unit = "R"', "length_unit: 'R' would relabel lengths that are in mm"),
    ((GENERATOR,), (), 'length_unit = "furlong"', "length_unit: 'furlong' is not a unit of length fitbench knows"),
    ((GENERATOR,), ('metric = "time_median_s"\nunit = "mm"',), "", "'time_median_s' is in s, not a length ('mm')"),
])
def test_a_unit_that_cannot_apply_is_refused_at_load(tmp_path, datasets, rankings, top, message):
    with pytest.raises(ConfigError) as err:
        configs.load(toml(tmp_path, datasets, rankings, top))
    assert message in str(err.value) and "\n" not in str(err.value), str(err.value)


@pytest.mark.parametrize("datasets, rankings, top", [
    ((FILE,), ('metric = "center_error"\nunit = "um"',), ""),                      # converted
    ((GENERATOR,), ('metric = "form_error"\nunit = "R"', 'metric = "center_error"\nunit = "R"'), ""),   # noise
    ((GENERATOR,), (), 'length_unit = "R"'),                                       # convergence
    ((GENERATOR,), ('metric = "form_error"\nunit = "um"',), 'length_unit = "mm"'),  # converted from mm
    ((FILE,), ('metric = "form_error"\nunit = "nm"',), 'length_unit = "mm"'),
])
def test_a_unit_that_applies_loads(tmp_path, datasets, rankings, top):
    configs.load(toml(tmp_path, datasets, rankings, top))


def rows_of(tmp_path, cfg, center_errors):
    folder = tmp_path / cfg["name"]
    folder.mkdir()
    pd.DataFrame([{"dataset": "trace", "data_stream": "0.0.0", "repetition": 0, "method": m, "params": "{}",
                   "status": "ok", "center_error": v} for m, v in center_errors.items()]).to_csv(
        folder / "results.csv", index=False)
    return cfg["name"], folder, {"config": cfg}


def test_a_ranking_in_um_of_mm_data_converts_and_leaves_the_default_table_in_mm(tmp_path):
    decl = {"profile": "p", "metric": "center_error", "unit": "um"}
    cfg = {"name": "rku", "datasets": [{"file": "trace.csv"}], "rankings": [decl]}
    r = collect([rows_of(tmp_path, cfg, {"circle.kasa": 4.583e-05, "circle.taubin": 9e-05})])["p"]
    assert r.unit == "um"
    assert r.table.loc["rku | trace | 0.0.0 | 0"].tolist() == pytest.approx([0.04583, 0.09])
    assert r.by_dataset.loc["rku: trace"].tolist() == pytest.approx([0.04583, 0.09])
    assert metric_unit(cfg, "center_error") == ("mm", "")   # the study's default table and figure


def test_a_generator_s_lengths_are_ranked_in_data_units_unless_named():
    """scaling (circle and ellipse generators, no unit): its costs were labelled mm in the report's median tables;
    the noise study names its unit circles R."""
    scaling = {"datasets": [{"source": "circle"}], "rankings": [{"metric": "form_error"}]}
    assert ranking_unit(scaling, "form_error", None) == (DATA_UNITS, 1.0)
    noise = {"datasets": [{"source": "circle"}], "rankings": [{"metric": "form_error", "unit": "R"}]}
    assert ranking_unit(noise, "form_error", "R") == ("R", 1.0) and metric_unit(noise, "form_error")[0] == "R"


def test_every_committed_study_keeps_its_units():
    """The committed studies' configs (noise: rankings in R on unit circles; convergence: length_unit R) load as
    before and keep the units their tables show."""
    seen = {}
    for meta in sorted((REPO / "results").glob("*/meta.json")):
        cfg = json.loads(meta.read_text(encoding="utf-8"))["config"]
        assert length_unit_problem(cfg) is None, meta
        seen[meta.parent.name] = [ranking_unit(cfg, d["metric"], d.get("unit")) for d in cfg.get("rankings") or []]
    assert seen["noise"] == [("R", 1.0), ("R", 1.0)] and seen["published"] == [("mm", 1.0), ("s", 1.0)]
