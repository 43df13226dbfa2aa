"""A study kind is a class: each module of experiments/studies/ defines one subclass of experiments.study.Study,
every hook has a default, a TOML without ``kind`` runs the base, and an old-style module (functions, no class)
is refused in one line that says what to write instead."""
from __future__ import annotations

import ast
import pickle
from pathlib import Path

import pandas as pd
import pytest

from experiments import config as configs
from experiments.run import run_study
from experiments.study import Analysis, ConfigError, ConfigTable, Study, study_of
from study_kinds import plant, small_study

REPO = Path(__file__).resolve().parents[1]


def write(tmp_path, name="study", kind=""):
    path = tmp_path / f"{name}.toml"
    path.write_text(small_study(name, "a small study", kind), encoding="utf-8")
    return path


def test_every_study_module_defines_one_study_class():
    for path in sorted((REPO / "experiments" / "studies").glob("*.py")):
        if path.stem == "__init__":
            continue
        study = study_of(path.stem)
        assert isinstance(study, Study) and study.kind == path.stem
        assert type(study).__module__ == f"experiments.studies.{path.stem}"


def test_a_toml_without_kind_runs_the_base_study(tmp_path):
    cfg = configs.load(str(write(tmp_path)))
    assert cfg["kind"] == "grid" and type(study_of(cfg["kind"])).__mro__[1] is Study
    target = run_study(str(write(tmp_path)), tmp_path / "out", jobs=1, log=lambda *a: None)
    df = pd.read_csv(target / "results.csv")
    assert len(df) == 2 and set(df["status"]) == {"ok"}
    assert (target / "figure_1_bars.png").is_file()  # the default figure of a study that declares none


def test_a_subclass_overrides_only_what_differs(tmp_path, monkeypatch):
    """A class that overrides analyse alone keeps the generic tasks and rows; one with its own rows says its
    columns are known only after the run (declarations naming its columns are then checked after the run)."""
    class OnlyAnalysis(Study):
        values = ("mean_radius",)

        def analyse(self, rows, cfg, target, log):
            return Analysis(values={"mean_radius": float(rows["radius"].mean())})

    class OwnRows(Study):
        def execute(self, task):
            return {"status": "ok", "message": "", "answer": 42}

    plant(monkeypatch, "only_analysis", OnlyAnalysis=OnlyAnalysis)
    plant(monkeypatch, "own_rows", OwnRows=OwnRows)
    path = write(tmp_path, kind="only_analysis")
    path.write_text(path.read_text() + '[report]\nfindings = "mean radius {mean_radius:.3f} mm"\n')
    cfg = configs.load(str(path))
    study = study_of("only_analysis")
    assert not study.own_rows and "radius" in study.row_columns(cfg)
    assert len(list(study.prepared_tasks(cfg))) == 2
    with pytest.raises(ConfigError, match=r"study\.toml: report\.findings: unknown value\(s\) mean_radiu "):
        path.write_text(path.read_text().replace("{mean_radius:", "{mean_radiu:"))
        configs.load(str(path))
    assert study_of("own_rows").own_rows and study_of("own_rows").row_columns(cfg) is None


def test_an_old_style_study_module_is_refused_in_one_line(tmp_path, monkeypatch):
    def analyse(df, cfg, target, log):
        return Analysis()
    plant(monkeypatch, "old_style", analyse=analyse, CONFIG_SCHEMA={})
    with pytest.raises(ConfigError) as err:
        configs.load(str(write(tmp_path, kind="old_style")))
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("study.toml: kind: experiments/studies/old_style.py must define one "
                                              "subclass of experiments.study.Study")
    assert "module-level analyse, CONFIG_SCHEMA" in msg and "docs/experiments.md" in msg


def test_the_framework_probes_no_study_module():
    """The runner, the config loader, the engine and the contract call the study's methods; none asks a study
    module what it has (hasattr/getattr on a module)."""
    for name in ("run", "config", "engine", "study", "schema"):
        tree = ast.parse((REPO / "experiments" / f"{name}.py").read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) in ("hasattr", "getattr"):
                target = ast.unparse(node.args[0])
                assert "study" not in target and "module" not in target, f"experiments/{name}.py: {ast.unparse(node)}"


def test_no_study_figure_in_render():
    """A study's figures live beside it (experiments/studies/KIND.py); experiments/render/ holds only what every
    study shares (style, generic plots): no function there is named after a study kind or reads its results."""
    kinds = [p.stem for p in (REPO / "experiments" / "studies").glob("*.py") if p.stem not in ("__init__", "grid")]
    for path in sorted((REPO / "experiments" / "render").glob("*.py")):
        tree = ast.parse(path.read_text())
        names = [n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)]
        assert not [n for n in names if any(n.startswith(k) for k in kinds)], path.name
        assert "experiments.studies" not in path.read_text(), path.name


def test_a_loaded_config_keeps_its_origin_as_typed_attributes(tmp_path):
    """Where a config came from is typed attributes of the loaded config, not keys of its mapping (meta.json
    records the mapping); a changed copy and a pickled one keep them."""
    cfg = configs.load(str(write(tmp_path)), quick=True)
    assert not [k for k in cfg if k.startswith("_")]
    assert cfg.where == "study.toml" and cfg.folder == tmp_path.resolve() and cfg.quick is True
    again = pickle.loads(pickle.dumps(cfg.replace(repetitions=1)))
    assert again["repetitions"] == 1 and cfg["repetitions"] == 2
    assert (again.where, again.folder, again.quick) == (cfg.where, cfg.folder, cfg.quick)


def test_the_outputs_fingerprint_tells_a_quick_config_from_a_full_one(tmp_path):
    """The same keys loaded with and without --quick: the outputs' fingerprint reads the config's quick attribute
    (it read a private key that a loaded config no longer has, so both hashed alike)."""
    from experiments import engine
    cfg = configs.load(str(write(tmp_path)))
    quick = configs.StudyConfig(dict(cfg), where=cfg.where, folder=cfg.folder, quick=True)
    assert engine.outputs_code(cfg) != engine.outputs_code(quick)
    assert engine.outputs_code(cfg) == engine.outputs_code(cfg.replace())


def test_the_config_schema_is_generated_from_the_typed_config():
    """The JSON Schema every config is checked against is generated from the pydantic models (plain JSON Schema:
    no reference, no null alternative, so each error names its key); every shipped config is an instance of the
    typed config (its keys common to all studies), and a key the models lack is refused by the schema."""
    import json

    from experiments import schema
    text = json.dumps(schema.config_schema())
    assert "$ref" not in text and '"null"' not in text
    assert set(schema.TOP_LEVEL) == set(schema.StudyConfigModel.model_fields)
    assert set(schema.DATASET_SOURCES["file"]) == set(schema.FileEntry.model_fields)
    for name in configs.available():
        cfg = configs.load(name)
        common = {k: v for k, v in cfg.items() if k in schema.StudyConfigModel.model_fields}
        typed = schema.StudyConfigModel.model_validate(common)
        assert typed.name == name and typed.kind == cfg["kind"] and typed.seed == cfg["seed"]


def test_a_new_common_key_is_a_field_of_the_typed_config(monkeypatch, tmp_path):
    from pydantic import Field
    from typing import Annotated

    from experiments import schema

    class WithOwner(schema.StudyConfigModel):
        owner: Annotated[str, Field(min_length=1)] = None
    monkeypatch.setattr(schema, "TOP_LEVEL", {**schema.TOP_LEVEL, "owner": schema.properties(WithOwner)["owner"]})
    path = write(tmp_path)
    path.write_text(path.read_text().replace("seed = 3", 'seed = 3\nowner = "lab 2"'))
    assert configs.load(str(path))["owner"] == "lab 2"
    path.write_text(path.read_text().replace('owner = "lab 2"', 'owner = ""'))
    with pytest.raises(ConfigError, match=r"^study\.toml: owner: "):
        configs.load(str(path))


def test_a_study_declares_the_tolerances_of_its_own_columns():
    """verify reads the tolerance of a column a study computes itself from the study's class, not from a list in
    experiments/metrics.py."""
    from experiments import compare, metrics
    from experiments.studies.circular_test import CircularTestStudy
    from experiments.studies.roundness import RoundnessStudy
    assert compare.tolerance("RONt_mzci_um", "roundness") == RoundnessStudy.tolerances["RONt_mzci_um"]
    assert compare.tolerance("diag_squareness_u", "circular_test") == CircularTestStudy.tolerances["diag_squareness_u"]
    assert compare.tolerance("station_deltas_um", "multilateration") is None  # declared: not compared
    own = {c for kind in ("roundness", "circular_test", "multilateration") for c in study_of(kind).tolerances}
    assert own and not own & set(metrics.TOLERANCES)


def test_a_study_declares_its_own_keys_as_a_typed_model():
    """A study kind's own config keys are a pydantic model (experiments.study.ConfigTable) the schema is generated
    from; every shipped config's own keys are an instance of its kind's model."""
    from experiments import schema
    checked = 0
    for name in configs.available():
        cfg = configs.load(name)
        model = study_of(cfg["kind"]).config_schema
        if not model:
            continue
        assert isinstance(model, type) and issubclass(model, ConfigTable), cfg["kind"]
        own = {k: cfg[k] for k in model.model_fields if k in cfg}
        assert own and model.model_validate(own) is not None
        assert set(schema.config_schema(model)["properties"]) >= set(model.model_fields)
        checked += 1
    assert checked >= 7


@pytest.mark.parametrize("study,key", [("convergence", "start_directions"), ("positioning", "bands"),
                                       ("roundness", "cutoffs"), ("published", "published_columns")])
def test_a_key_the_study_model_requires_is_refused_missing_by_the_schema(study, key):
    """A field of a study's model without a default is a required key of its configs: refused in one line by the
    generated schema (the study's validate no longer checks presence and types again)."""
    import tomllib

    from experiments import schema
    cfg = tomllib.loads((REPO / "experiments" / "configs" / f"{study}.toml").read_text(encoding="utf-8"))
    model = study_of(cfg["kind"]).config_schema
    schema.check_structure(dict(cfg), f"{study}.toml", model)  # as shipped: fine
    del cfg[key]
    with pytest.raises(ConfigError) as err:
        schema.check_structure(cfg, f"{study}.toml", model)
    assert str(err.value) == f"{study}.toml: (top level): missing required key '{key}'"
