"""Every config problem refused before a row runs, in one line naming file, key and problem."""
from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import pytest
from pydantic import Field

from experiments import config as configs
from experiments import run as runner
from experiments.study import ConfigError
from plugin_methods import sources_registered

GOOD = '''name = "{name}"
title = "a small study"
kind = "grid"
seed = 3
repetitions = 2
summary_by = ["data_n", "method"]

[[datasets]]
generator = "circle"
params = {{ center = [1.0, 2.0], radius = 5.0, noise = 0.01 }}
grid = {{ n = [10, 20] }}

[[methods]]
id = "circle.kasa"
[[methods]]
id = "circle.gauss_newton"
'''


def write(tmp_path, text, name="study"):
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_good_config_loads_and_every_shipped_config_is_valid(tmp_path):
    cfg = configs.load(str(write(tmp_path, GOOD.format(name="study"))))
    assert cfg["repetitions"] == 2 and configs.count_rows(cfg) == 2 * 2 * 2
    for name in configs.available():
        for quick in (False, True):
            configs.load(name, quick=quick)


def _sub(old, new):
    text = GOOD.format(name="study")
    assert old in text
    return text.replace(old, new, 1)


BAD = [
    ("top-level typo", _sub("repetitions = 2", "repetitons = 2"), "repetitons"),
    ("repetitions bool", _sub("repetitions = 2", "repetitions = true"), "repetitions"),
    ("repetitions float", _sub("repetitions = 2", "repetitions = 1e9"), "repetitions"),
    ("negative seed", _sub("seed = 3", "seed = -1"), "seed"),
    ("params as list", _sub("params = {", "params = [1, 2]\nx = {"), "datasets[0]"),
    ("methods = 5", GOOD.format(name="study").split("[[methods]]")[0] + "methods = 5\n", "methods"),
    ("id = 5", _sub('id = "circle.kasa"', "id = 5"), "methods[0]"),
    ("summary_by = 5", _sub('summary_by = ["data_n", "method"]', "summary_by = 5"), "summary_by"),
    ("no datasets", GOOD.format(name="study").replace("[[datasets]]", "[unused]").replace(
        'generator = "circle"\nparams', "# x\nx"), "datasets"),
    ("no methods", GOOD.format(name="study").split("[[methods]]")[0], "methods"),
    ("timing rounds 0", GOOD.format(name="study") + "[timing]\nrounds = 0\n", "timing.rounds"),
    ("n string", _sub("grid = { n = [10, 20] }", 'grid = { n = ["12"] }'), "n = '12'"),
    ("n negative", _sub("grid = { n = [10, 20] }", "grid = { n = [-5] }"), "n = -5"),
    ("noise negative", _sub("noise = 0.01", "noise = -0.01"), "noise = -0.01"),
    ("radius inf", _sub("radius = 5.0", "radius = inf"), "radius"),
    ("center string", _sub("center = [1.0, 2.0]", 'center = "here"'), "center = 'here'"),
    ("xtol negative", _sub('id = "circle.gauss_newton"', 'id = "circle.gauss_newton"\nparams = { xtol = -1 }'), "xtol=-1"),
    ("method grid bad", _sub('id = "circle.gauss_newton"', 'id = "circle.gauss_newton"\ngrid = { max_iter = [10, 2.5] }'),
     "max_iter=2.5"),
    ("unknown generator param", _sub("noise = 0.01", "nois = 0.01"), "nois"),
    ("quick overrides name", GOOD.format(name="study") + '[quick]\nname = "../../escape"\n', "quick"),
    ("quick wrong type", GOOD.format(name="study") + "[quick]\nrepetitions = 0\n", "quick.repetitions"),
    ("two sources", _sub('generator = "circle"', 'generator = "circle"\npublished = "roundness_set1"'), "exactly one"),
]


@pytest.mark.parametrize("case,text,key", BAD, ids=[c[0] for c in BAD])
def test_bad_config_is_refused_in_one_line_naming_file_and_key(tmp_path, case, text, key):
    with pytest.raises(ConfigError) as info:
        cfg = configs.load(str(write(tmp_path, text)), quick=True)
        configs.check_rows(cfg, configs.count_rows(cfg), configs.MAX_ROWS)
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith("study.toml: "), msg
    assert key in msg, msg


def test_non_utf8_and_directory_configs(tmp_path):
    (tmp_path / "bin.toml").write_bytes(b'name = "bin"\ntitle = "\xff\xfe"\n')
    with pytest.raises(ConfigError, match="bin.toml: not UTF-8"):
        configs.load(str(tmp_path / "bin.toml"))
    (tmp_path / "dir.toml").mkdir()
    with pytest.raises(ConfigError, match="dir.toml: is a directory"):
        configs.load(str(tmp_path / "dir.toml"))


def test_output_paths_are_confined_to_out(tmp_path):
    assert runner.confined(tmp_path, "noise") == tmp_path / "noise"
    for name in ("../escape", "/abs/path", "..", "a/b"):
        with pytest.raises(runner.InvalidInputError, match="outside --out"):
            runner.confined(tmp_path, name)


def test_grid_size_is_counted_before_expansion(tmp_path, capsys):
    text = _sub('summary_by = ["data_n", "method"]', "").replace(", noise = 0.01", "").replace(
        "grid = { n = [10, 20] }", "grid = { n = [%s], noise = [%s] }" % (
            ", ".join(str(10 + i) for i in range(1000)), ", ".join(f"0.{i + 1}" for i in range(9))))
    path = write(tmp_path, text.replace("repetitions = 2", "repetitions = 1000000000"))
    cfg = configs.load(str(path))
    assert configs.count_rows(cfg) == 1000 * 9 * 1000000000 * 2
    code = runner.main([str(path), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "more than the limit" in err and "--max-rows" in err and "\n" not in err
    assert not (tmp_path / "out" / "study").exists()
    # --max-rows lowers or raises the limit
    small = write(tmp_path, GOOD.format(name="small"), name="small")
    assert runner.main([str(small), "--out", str(tmp_path / "out"), "--max-rows", "7"]) == 2
    assert "8 rows" in capsys.readouterr().err


def test_unknown_summary_by_column_refused_before_any_row(tmp_path, capsys):
    path = write(tmp_path, _sub('summary_by = ["data_n", "method"]', 'summary_by = ["data_nn", "method"]'))
    code = runner.main([str(path), "--out", str(tmp_path / "out"), "--jobs", "1"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "study.toml: summary_by" in err and "data_nn" in err and "\n" not in err
    assert not (tmp_path / "out" / "study" / "rows.sqlite").exists()  # nothing ran


def test_method_registry_parameter_hook():
    import methods
    spec = methods.get("circle.gauss_newton")
    spec.check_params({"xtol": 1e-9, "max_iter": 50})
    for bad in ({"xtol": -1}, {"xtol": "1e-9"}, {"max_iter": 2.5}, {"max_iter": True}, {"xtol": float("nan")}):
        with pytest.raises(methods.InvalidInputError, match="circle.gauss_newton: parameter"):
            spec.check_params(bad)
    for m in methods.list_methods():  # every method's defaults pass its own checks
        m.check_params(dict(m.defaults))


def test_a_study_declares_its_own_config_keys(tmp_path, monkeypatch):
    """A new study kind adds its own top-level key in its class (``config_schema``), with no edit under
    experiments/ elsewhere; the key is typed by that schema, and another kind still refuses it."""
    from experiments import schema
    from experiments.study import Study
    from study_kinds import plant

    class OwnKey(Study):
        config_schema = {"lobes": {"type": "array", "minItems": 1, "items": {"type": "integer", "minimum": 2}}}
    plant(monkeypatch, "study_with_own_key", OwnKey=OwnKey)
    own = GOOD.format(name="study").replace('kind = "grid"', 'kind = "study_with_own_key"\nlobes = [3, 5]')
    assert configs.load(str(write(tmp_path, own)))["lobes"] == [3, 5]
    with pytest.raises(ConfigError, match=r"study\.toml: lobes\[1\]: .*1.*minimum|study\.toml: lobes"):
        configs.load(str(write(tmp_path, own.replace("lobes = [3, 5]", "lobes = [3, 1]"))))
    with pytest.raises(ConfigError, match="lobes"):  # the generic grid does not know the key
        configs.load(str(write(tmp_path, GOOD.format(name="study").replace("seed = 3", "seed = 3\nlobes = [3]"))))
    for key in ("rounding", "scenarios", "cutoffs", "positions_per_test"):  # no study key is common any more
        assert key not in schema.TOP_LEVEL
    with pytest.raises(ValueError, match="redefines the common key"):
        schema.config_schema({"seed": {"type": "string"}})


MAGNIFICATION = (Path(__file__).resolve().parents[1] / "experiments" / "configs" / "magnification.toml").read_text()


@pytest.mark.parametrize("old,new,key", [
    ('method = "magnify.nearest"', 'method = "magnify.nearst"', "variants[0]"),
    ('params = { selection = "same_side", delta_emax = 2.0 }', 'params = { selection = "same_side", delt = 2.0 }',
     "variants[2]"),
    ('times_eta = ["delta_emax"]', 'times_eta = ["delta"]', "variants[4]"),
    ('label = "offset same side, delta = 2 e_max"', 'label = "nearest (conventional)"', "unique"),
    ('example = "corner_inside_convex"', 'example = "corner_nowhere"', "trajectories[0]"),
    ('box = [15.0, 16.6, 1.9, 3.0]', 'box = [15.0, 16.6]', "box"),
])
def test_magnification_variants_are_checked(tmp_path, old, new, key):
    """The magnification study's algorithm variants and drawn trajectories are data (its TOML), checked on load."""
    assert old in MAGNIFICATION
    path = tmp_path / "magnification.toml"
    path.write_text(MAGNIFICATION.replace(old, new, 1))
    with pytest.raises(ConfigError) as info:
        configs.load(str(path), quick=True)
    msg = str(info.value)
    assert "\n" not in msg and key in msg, msg


CONFIGS = Path(__file__).resolve().parents[1] / "experiments" / "configs"


@pytest.mark.parametrize("config,old,new,key", [
    ("published", 'MIC = "circle.max_inscribed"', 'MIC = "circle.max_inscrbed"', "published_columns.'MIC'"),
    ("published", 'MCC = "circle.min_circumscribed"', 'MCC = 5', "published_columns"),
    ("positioning", 'example_band = "GLS cubic (paper)"', 'example_band = "GLS quintic"', "example_band"),
])
def test_study_data_in_its_toml_is_checked(tmp_path, config, old, new, key):
    """What a study once named in its code (the published table's columns and their methods, the band of the
    positioning example) is declared in its TOML and checked on load, in one line naming the key."""
    text = (CONFIGS / f"{config}.toml").read_text()
    assert old in text
    path = tmp_path / f"{config}.toml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ConfigError) as info:
        configs.load(str(path), quick=True)
    msg = str(info.value)
    assert "\n" not in msg and key in msg, msg


SOURCE_STUDY = '''name = "study"
title = "t"
seed = 1
repetitions = 5
[[datasets]]
source = "{source}"
params = {{ {params} }}
{grid}
[[methods]]
id = "circle.kasa"
'''


@pytest.mark.parametrize("params, grid, key, expected", [
    ("radius = 5.0, noise = 0.01, n = 30.5", "", "params.n = 30.5", "an integer"),
    ('radius = 5.0, arc_deg = "90", noise = 0.01, n = 30', "", "params.arc_deg = '90'", "a number"),
    ('radius = 5.0, center = "0,0", noise = 0.01, n = 30', "", "params.center = '0,0'", "a list of 2 numbers"),
    ('radius = 5.0, noise = "0.01", n = 30', "grid = { arc_deg = [360.0, 90.0] }", "params.noise = '0.01'",
     "a number"),
    ('radius = "5", noise = 0.01, n = 30', "", "params.radius = '5'", "a number"),
    ("radius = 5.0, noise = 0.01", "grid = { n = [30, 40.0] }", "grid.n = 40.0", "an integer"),
    ('radius = 5.0, n = 30, noise_model = "gaussian"', "", "params.noise_model = 'gaussian'", "'radial'"),
])
def test_data_source_parameter_types_are_checked_before_any_row(tmp_path, capsys, params, grid, key, expected):
    """A ``source = ...`` data set's parameters are checked against the types the source declares before any row
    runs (a string is refused where a number is expected, never coerced): one line naming the file, the data set,
    the key and the expected type, exit 2, nothing stored."""
    path = write(tmp_path, SOURCE_STUDY.format(source="circle", params=params, grid=grid))
    code = runner.main([str(path), "--out", str(tmp_path / "out"), "--jobs", "1", "--no-report"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err, err
    assert "study.toml: datasets[0] (source 'circle'): " in err and key in err and expected in err, err
    assert not (tmp_path / "out" / "study" / "rows.sqlite").exists()


@pytest.fixture
def plugin_scene():
    """A data source registered as a plugin registers it (``register_source``), with and without annotations."""

    def scene(rng, *, n=40, share=0.1, mode: Literal["inside", "outside"] = "inside", scale: float = 1,
              offset=(0.0, 0.0), tag=None):
        t = np.linspace(0, 2 * np.pi, n, endpoint=False)
        return np.column_stack([scale * np.cos(t), scale * np.sin(t)]), None

    def needs_name(rng, *, name: str):
        return np.zeros((3, 2)), None

    def unresolvable(rng, *, x: "NoSuchType" = 1):  # noqa: F821
        return np.zeros((3, 2)), None

    with sources_registered({"test_scene": scene, "test_needs_name": needs_name, "test_unresolvable": unresolvable},
                            random=True, summary="plugin test source"):
        yield


@pytest.mark.parametrize("source, params, problem", [
    ("test_scene", "n = 40.5", "params.n = 40.5 must be an integer"),  # typed by its default
    ("test_scene", 'share = "0.2"', "params.share = '0.2' must be a number"),
    ("test_scene", 'mode = "around"', "params.mode = 'around' must be one of 'inside', 'outside'"),  # annotated
    ("test_scene", 'scale = "2"', "params.scale = '2' must be a number"),
    ("test_scene", 'offset = [1.0, "x"]', "params.offset = [1.0, 'x'] must be a list of numbers"),
    ("test_scene", "shape = 1", "data source 'test_scene' has no parameter 'shape'"),
    ("test_needs_name", "", "needs the parameter(s) name"),
    ("test_needs_name", "name = 3", "params.name = 3 must be a string"),
    ("test_unresolvable", "x = 1", "its parameter annotations cannot be resolved"),
])
def test_a_plugin_data_source_gets_the_same_parameter_check(tmp_path, plugin_scene, source, params, problem):
    path = write(tmp_path, SOURCE_STUDY.format(source=source, params=params, grid=""))
    with pytest.raises(ConfigError) as info:
        configs.load(str(path))
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith(f"study.toml: datasets[0] (source '{source}'): "), msg
    assert problem in msg, msg


def test_a_plugin_data_source_takes_values_of_its_declared_types(tmp_path, plugin_scene):
    """An int where a float is declared is a number; an untyped parameter (default None) takes anything."""
    path = write(tmp_path, SOURCE_STUDY.format(source="test_scene", grid='grid = { share = [0, 0.5] }', params=(
        'n = 12, mode = "outside", scale = 2, offset = [1, 2.5], tag = { any = "thing" }')))
    assert configs.load(str(path))["datasets"][0]["params"]["scale"] == 2


def test_a_built_in_simulator_refuses_a_name_it_does_not_know(tmp_path):
    """The contouring source's ``example`` is one of the examples it has (was a KeyError in every row)."""
    from datasets import contouring
    text = SOURCE_STUDY.format(source="contouring", params='example = "nope"', grid="").replace(
        'id = "circle.kasa"', 'id = "magnify.nearest"')  # the methods that take its data
    with pytest.raises(ConfigError, match=r"datasets\[0\] \(source 'contouring'\): params.example = 'nope' must be one "
                                          r"of 'corner_inside_convex'"):
        configs.load(str(write(tmp_path, text)))
    configs.load(str(write(tmp_path, text.replace("nope", next(iter(contouring.EXAMPLES))))))


WRONG_DATA = """name = "study"
title = "t"
seed = 1
repetitions = 2
[[datasets]]
source = "circle"
params = { radius = 5.0, noise = 0.01, n = 30 }
[[datasets]]
source = "positioning"
label = "axis"
[[methods]]
id = "circle.kasa"
on = ["circle"]
[[methods]]
id = "ellipse.fitzgibbon"
on = ["circle"]
any_family = true   # an ellipse fit on a circle's points: asked for (tests/test_family_pairing.py)
[[methods]]
id = "positioning.iso230_2"
"""


def test_a_method_that_cannot_take_a_data_set_is_refused_before_any_row(tmp_path, capsys):
    """A positioning method on the points of a circle source (it ran into 'skipped' rows, exit 0): one line naming
    the method, the data set and what each side takes, exit 2, nothing run; ``on`` that leaves the data set out
    passes."""
    path = write(tmp_path, WRONG_DATA)
    code = runner.main([str(path), "--out", str(tmp_path / "out"), "--jobs", "1", "--no-report"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "Traceback" not in err, err
    assert ("study.toml: methods[2]: positioning.iso230_2 cannot take the data of datasets[0] (source 'circle'): "
            "the source gives points (an (N, 2) array), positioning.iso230_2 takes PositioningData") in err, err
    assert not (tmp_path / "out" / "study" / "rows.sqlite").exists()
    configs.load(str(write(tmp_path, WRONG_DATA + 'on = ["axis"]\n')))   # each method on the data it takes
    with pytest.raises(ConfigError, match=r"methods\[0\]: circle.kasa cannot take the data of datasets\[1\] "
                                          r"\(source 'positioning'\): the source gives PositioningData"):
        configs.load(str(write(tmp_path, WRONG_DATA.replace('on = ["circle"]\n', "", 1) + 'on = ["axis"]\n')))
    with pytest.raises(ConfigError, match=r"methods\[0\] \(magnify\.\*\): magnify.nearest cannot take the data of "
                                          r"datasets\[0\] \(source 'circle'\)"):
        configs.load(str(write(tmp_path, WRONG_DATA.replace('id = "circle.kasa"', 'id = "magnify.*"'))))


def test_a_plugin_data_source_declares_what_it_gives(tmp_path):
    """The check is the sources' and the families' declarations, not a list of names: a plugin source that gives
    the magnify family's input is refused for a circle method and taken by a magnify method; one that declares
    nothing is not checked."""
    from datasets import sources
    from methods.magnify import MagnifyInput

    def trajectory(rng, *, n=20):
        t = np.linspace(0, 1, n)
        return MagnifyInput(np.column_stack([t, t]), np.column_stack([t, t + 1e-3])), None
    try:
        sources.register_source("test_trajectory", random=False, summary="plugin test", gives=MagnifyInput)(trajectory)
        sources.register_source("test_undeclared", random=False, summary="plugin test")(trajectory)
        text = SOURCE_STUDY.format(source="test_trajectory", params="n = 10", grid="")
        with pytest.raises(ConfigError, match=r"circle.kasa cannot take the data of datasets\[0\] \(source "
                                              r"'test_trajectory'\): the source gives MagnifyInput, circle.kasa takes "
                                              r"points"):
            configs.load(str(write(tmp_path, text)))
        configs.load(str(write(tmp_path, text.replace("circle.kasa", "magnify.offset"))))
        configs.load(str(write(tmp_path, text.replace("test_trajectory", "test_undeclared"))))
        with pytest.raises(ValueError, match="gives must be a type"):
            sources.register_source("test_bad_gives", random=False, summary="t", gives="points")
    finally:
        for name in ("test_trajectory", "test_undeclared"):
            sources._REGISTRY.pop(name, None)


@pytest.mark.parametrize("where, key, problem", [
    ("methods", 'summary_by = ["method"]', "methods[1]: unknown key 'summary_by' (known: any_family, grid, id, max_n, on, params); "
     "'summary_by' is a top-level key, and a key written after [[methods]] belongs to that table in TOML: move it "
     "above the first [...] or [[...]]"),
    ("methods", "repetitons = 3", "methods[1]: unknown key 'repetitons' (known: any_family, grid, id, max_n, on, params); did you "
     "mean the top-level key 'repetitions'? a key written after [[methods]]"),
    ("datasets", "seed = 4", "datasets[0]: unknown key 'seed' (known: generator, grid, label, params); 'seed' is a "
     "top-level key, and a key written after [[datasets]] belongs to that table"),
    ("report", "seed = 4", "report: unknown key 'seed' (known: findings, order, section); 'seed' is a top-level key, "
     "and a key written after [report] belongs to that table"),
    ("quick", "repetitons = 1", "quick: unknown key 'repetitons' (known: "),   # a key of [quick] itself: ...
    ("top", "repetitons = 1", "(top level): unknown key 'repetitons' (known: "),
])
def test_a_top_level_key_written_after_a_table_is_named_with_its_likely_cause(tmp_path, where, key, problem):
    """TOML's slip: a key written after ``[[methods]]`` (or any table) belongs to that table. The message names the
    key and the cause (it named the whole table: 'must be a method id, or a table with ..., got {...}')."""
    text = GOOD.format(name="study")
    if where == "datasets":
        text = text.replace("grid = { n = [10, 20] }", "grid = { n = [10, 20] }\n" + key)
    elif where == "top":
        text = key + "\n" + text
    else:
        text += {"methods": "", "report": '[report]\nsection = "s"\n', "quick": "[quick]\n"}[where] + key + "\n"
    with pytest.raises(ConfigError) as info:
        configs.load(str(write(tmp_path, text)))
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith(f"study.toml: {problem}"), msg
    if where in ("quick", "top"):   # a typo of the table's (or the file's) own key: its close match, no slip
        assert msg.endswith("; did you mean 'repetitions'?") and "written after" not in msg, msg


RANKED = GOOD.format(name="study") + '''[[rankings]]
profile = "p"
metric = "radius_error"
methods = "circle.*"
'''


@pytest.mark.parametrize("old, new, problem", [
    ('metric = "radius_error"', 'metric = "radius_eror"',
     "rankings[0].metric: no row will have the column 'radius_eror'; did you mean 'radius_error'?"),
    ('metric = "radius_error"', 'metric = "method"', "rankings[0].metric: 'method' is not a number"),
    ('methods = "circle.*"', 'methods = "cirle.*"', "rankings[0].methods: 'cirle.*' matches none of the study's "
                                                      "methods (circle.kasa, circle.gauss_newton)"),
    ('methods = "circle.*"', 'methods = "circle.*"\nproblem = ["dataset", "repetiton"]',
     "rankings[0].problem: no row will have the column 'repetiton'; did you mean 'repetition'?"),
    ('methods = "circle.*"', 'methods = "circle.*"\nwhere = { data_nn = 10 }',
     "rankings[0].where: no row will have the column 'data_nn'"),
])
def test_a_ranking_declaration_is_checked_before_any_row(tmp_path, capsys, old, new, problem):
    """``[[rankings]]`` are checked with the config as tables and figures are (a misspelt metric was found only by
    the report, after every row had run)."""
    path = write(tmp_path, RANKED.replace(old, new, 1))
    code = runner.main([str(path), "--out", str(tmp_path / "out"), "--jobs", "1", "--no-report"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and f"study.toml: {problem}" in err, err
    assert not (tmp_path / "out" / "study" / "rows.sqlite").exists()
    assert configs.load(str(write(tmp_path, RANKED)))["rankings"][0]["metric"] == "radius_error"   # as written: fine


def test_a_data_source_count_is_bounded_with_the_config(tmp_path, capsys):
    """n = 10^9 points tried to allocate 16 GB in the row (a MemoryError row, exit 0): a data source's integer
    parameter without a declared bound is at most MAX_COUNT, checked with the config; a source declares a larger
    bound by annotation."""
    from experiments import schema
    path = write(tmp_path, SOURCE_STUDY.format(source="circle", params="radius = 5.0, noise = 0.01", grid=(
        f"grid = {{ n = [30, {schema.MAX_COUNT + 1}] }}")))
    code = runner.main([str(path), "--out", str(tmp_path / "out"), "--jobs", "1", "--no-report"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err, err
    assert (f"study.toml: datasets[0] (source 'circle'): grid.n = {schema.MAX_COUNT + 1} must be an integer >= 1 and "
            f"<= {schema.MAX_COUNT} (the bound of a data source's integer parameters that declare none") in err, err
    assert not (tmp_path / "out" / "study" / "rows.sqlite").exists()
    configs.load(str(write(tmp_path, SOURCE_STUDY.format(source="circle", params=f"n = {schema.MAX_COUNT}", grid=""))))

    def big(rng, *, n: Annotated[int, Field(ge=1, le=10 ** 9)] = 10, k=3):
        return np.zeros((n, 2)), None
    with sources_registered({"test_big": big}, random=True, summary="plugin test", gives=np.ndarray):
        configs.load(str(write(tmp_path, SOURCE_STUDY.format(source="test_big", params="n = 100000000", grid=""))))
        with pytest.raises(ConfigError, match=r"params.k = 100000000 must be an integer <= 10000000 \(the bound"):
            configs.load(str(write(tmp_path, SOURCE_STUDY.format(source="test_big", params="k = 100000000", grid=""))))


def _collinear_study(folder, extra=""):
    (folder / "line.csv").write_text("x,y\n" + "".join(f"{i},{2 * i}\n" for i in range(10)))
    arc = "".join(f"{np.cos(t):.17g},{np.sin(t):.17g}\n" for t in np.linspace(0, 3, 9))
    (folder / "arc.csv").write_text("x,y\n" + arc)
    return write(folder, 'name = "study"\ntitle = "t"\nseed = 1\n[[datasets]]\nfile = "line.csv"\n' + extra +
                 '[[methods]]\nid = "circle.kasa"\n[[methods]]\nid = "circle.gauss_newton"\n')


def test_a_study_none_of_whose_rows_has_a_result_exits_1(tmp_path, capsys):
    """Every row failed (here skipped: the points of the file lie on a line): the outputs are written, the run ends
    with one line naming the count, the statuses and the most frequent reason, exit 1 (it exited 0), also when
    the rows are served from the store; one row with a result is a run that worked (exit 0)."""
    path = _collinear_study(tmp_path)
    args = [str(path), "--out", str(tmp_path / "out"), "--jobs", "1", "--no-report"]
    for _ in range(2):   # run, then served from the store
        code = runner.main(args)
        err = capsys.readouterr().err.strip()
        assert code == 1 and "\n" not in err and "Traceback" not in err, err
        assert err.startswith("experiments.run: error: study.toml: 2 of 2 rows failed (2 skipped), none has a result; "
                              "most often skipped: circle."), err
        assert "lie on one straight line" in err and err.endswith("the rows and their messages are in results.csv")
        assert (tmp_path / "out" / "study" / "results.csv").is_file()
    path = _collinear_study(tmp_path, '[[datasets]]\nfile = "arc.csv"\n')
    assert runner.main(args) == 0 and capsys.readouterr().err == ""
