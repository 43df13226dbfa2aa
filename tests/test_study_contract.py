"""The study contract: a study written only in TOML (a file source and a generator source, a declared
table and figure) runs from the command line into rows, a summary averaged over repetitions and a report
section; a plugin registers a method and a data source through entry points and both reach a study and
the report; the report shows a broken study with its reason and builds the rest."""
import json
import textwrap

import numpy as np
import pandas as pd
import pytest

from conftest import REPO, install_plugin, run_python

STUDY = """
name = "toml_only"
title = "A study written only in TOML"
kind = "grid"
seed = 5
repetitions = 3

[report]
section = "User studies"
findings = "{{n_rows}} rows."

[[datasets]]
label = "trace"
file = "data/trace.csv"

[[datasets]]
source = "circle"
params = {{ center = [0.0, 0.0], radius = 2.0, noise = 0.01, n = 25 }}
grid = {{ arc_deg = [360.0, 90.0] }}

[[methods]]
id = "circle.kasa"
[[methods]]
id = "{second}"

[[tables]]
caption = "Radius RMSE by arc: synthetic circles of radius 2 mm, noise 0.01 mm, 3 repetitions"
rows = ["method"]
columns = "data_arc_deg"
values = "radius_error"
aggregate = "rmse"
unit = "mm"

[[figures]]
plot = "bars"
x = "method"
y = "form_error"
aggregate = "median"
caption = "Median form error per method on all data sets [mm]"
"""


def write_study(folder, second="circle.gauss_newton"):
    (folder / "data").mkdir(parents=True, exist_ok=True)
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    pts = np.column_stack([10 + 3 * np.cos(t), -4 + 3 * np.sin(t)]) + 1e-3 * np.sin(7 * t)[:, None]
    pd.DataFrame(pts, columns=["x", "y"]).to_csv(folder / "data" / "trace.csv", index=False)
    path = folder / "toml_only.toml"
    path.write_text(STUDY.format(second=second))
    return path


def run(args, cwd, path_first=()):
    return run_python("-m", "experiments.run", *args, cwd=cwd, path_first=path_first)


def test_toml_only_study_from_the_command_line(tmp_path):
    study = write_study(tmp_path / "elsewhere")
    out = tmp_path / "out"
    (out / "toml_only").mkdir(parents=True)
    (out / "toml_only" / ".summary.csv.x1.tmp").write_text("left by a kill during an atomic write")
    proc = run([str(study), "--out", str(out), "--jobs", "1"], cwd=REPO)
    assert proc.returncode == 0, proc.stderr
    assert not list((out / "toml_only").glob("*.tmp")) and not list((out / "toml_only").glob(".*.tmp"))
    df = pd.read_csv(out / "toml_only" / "results.csv")
    # 1 file (one repetition) + 2 arcs x 3 repetitions, 2 methods each
    assert len(df) == (1 + 2 * 3) * 2 and set(df["status"]) == {"ok"}
    assert set(df["dataset"]) == {"trace", "circle"}
    summary = pd.read_csv(out / "toml_only" / "summary.csv")
    assert "data_stream" not in summary.columns
    circle = summary[summary["dataset"] == "circle"]
    assert len(circle) == 2 * 2 and (circle["runs"] == 3).all()  # averaged over the repetitions
    manifest = json.loads((out / "toml_only" / "report.json").read_text())
    assert manifest["section"] == "User studies" and manifest["findings"] == f"{len(df)} rows."
    table = pd.read_csv(out / "toml_only" / manifest["tables"][0]["file"])
    ok = df[(df["dataset"] == "circle") & (df["data_arc_deg"] == 90.0) & (df["method"] == "circle.kasa")]
    expected = float(np.sqrt(np.mean(ok["radius_error"] ** 2)))
    got = table.set_index("method").loc["circle.kasa", "arc = 90 °"]
    assert got == pytest.approx(expected, rel=1e-9)
    report = (out / "paper" / "report.md").read_text()
    assert "## User studies" in report and "*Table 1: Radius RMSE by arc" in report and "Unit: mm" in report
    assert "![Figure 1: Median form error per method" in report
    assert "[User studies](#user-studies)" in report  # contents with anchors
    assert "paper" not in [line.split("`")[1] for line in report.splitlines() if line.startswith("### ")]
    html = (out / "paper" / "report.html").read_text()
    assert '<h2 id="user-studies">' in html and 'href="#study-toml-only"' in html

    # one broken study does not take the report down; a truncated results.csv is noticed
    csv = out / "toml_only" / "results.csv"
    csv.write_text(csv.read_text()[: len(csv.read_text()) // 2])
    from experiments.report import build
    build(out, out / "paper2", log=lambda *a: None)
    report = (out / "paper2" / "report.md").read_text()
    assert "**Broken**: results.csv does not match meta.json" in report


PLUGIN = '''
"""A plugin: a robust-ish fitter and an outlier scenario, registered through entry points."""
import numpy as np
from methods import register
from methods.results import circle_result
from datasets.sources import register_source


@register("circle.median_radius", kind="closed form", summary="centroid and median distance (plugin test)",
          reference="fitbench plugin test")
def median_radius(points):
    c = np.median(points, axis=0)
    return circle_result(points, c, float(np.median(np.hypot(*(points - c).T))), converged=True, message="closed form")


@register_source("circle_outliers", random=True, summary="unit circle with gross outliers (plugin test)")
def circle_outliers(rng, *, n=40, share=0.1):
    t = rng.uniform(0, 2 * np.pi, n)
    r = np.where(rng.uniform(size=n) < share, 3.0, 1.0)
    return np.column_stack([r * np.cos(t), r * np.sin(t)]), {"family": "circle", "center": (0.0, 0.0), "radius": 1.0}
'''


def test_plugin_method_and_data_source_reach_a_study_and_the_report(tmp_path):
    site = install_plugin(tmp_path, "fitbench-outlier-plugin", {"fitbench_outlier_plugin": PLUGIN},
                          {"fitbench.methods": {"median_radius": "fitbench_outlier_plugin"},
                           "fitbench.datasets": {"circle_outliers": "fitbench_outlier_plugin"}}, version="0.3.1")
    study = tmp_path / "plug.toml"
    study.write_text(textwrap.dedent('''
        name = "plug"
        title = "Plugin method on plugin data"
        kind = "grid"
        seed = 2
        repetitions = 2
        [[datasets]]
        source = "circle_outliers"
        params = { n = 50, share = 0.2 }
        [[methods]]
        id = "circle.median_radius"
        [[methods]]
        id = "circle.kasa"
    '''))
    out = tmp_path / "out"
    proc = run([str(study), "--out", str(out), "--jobs", "1"], cwd=REPO,
               path_first=[site])
    assert proc.returncode == 0, proc.stderr
    df = pd.read_csv(out / "plug" / "results.csv")
    assert set(df["method"]) == {"circle.median_radius", "circle.kasa"} and set(df["status"]) == {"ok"}
    assert set(df["dataset"]) == {"circle_outliers"} and df["radius_error"].notna().all()
    meta = json.loads((out / "plug" / "meta.json").read_text())
    assert meta["plugins"] == {"fitbench-outlier-plugin": "0.3.1"}
    report = (out / "paper" / "report.md").read_text()
    assert "Plugin method on plugin data" in report and "circle.median_radius" in report
    assert "plugins: fitbench-outlier-plugin 0.3.1" in report


def test_every_default_study_declares_tables_with_captions_and_findings():
    """Static part of the contract (the quick runs in test_experiments check the rendered manifest): every default
    study either has an ``analyse`` (tables, figures, values, findings) or declares tables with captions and a
    findings template in its TOML; no study keeps the removed ``finalize``/``report_tables`` hooks."""
    from experiments import config as configs
    from experiments.run import default_studies
    from experiments.study import Study, study_of
    names = default_studies()
    assert len(names) >= 9
    for name in names:
        cfg = configs.load(name)
        study = study_of(cfg["kind"])
        assert not hasattr(study, "finalize") and not hasattr(study, "report_tables"), name
        if type(study).analyse is not Study.analyse:
            continue
        assert cfg.get("tables") and all(t.get("caption") for t in cfg["tables"]), name
        assert cfg.get("report", {}).get("findings"), name


def test_analyse_tables_have_captions_units_and_generated_findings(tmp_path_factory):
    """An ``analyse`` study run end to end on quick rows (noise: the smallest): each returned table has a caption
    naming its data, the findings quote numbers of the named values."""
    import json

    from conftest import quick_study
    target = quick_study(tmp_path_factory, "noise")
    manifest = json.loads((target / "report.json").read_text())
    assert manifest["tables"] and all("synthetic" in t["caption"] for t in manifest["tables"])
    v = manifest["values"]
    assert f"σ = {v['sigma']:g} R" in manifest["findings"]
    for arc, ok in v["within_10_percent_by_arc"].items():      # per arc: how many reach the bound, or none
        assert (f"{len(ok)} of" if ok else "none on the") in manifest["findings"] and arc in manifest["findings"]


JOINER = '''
import numpy as np
from methods import register
from methods.results import circle_result


@register("circle.joiner_median", kind="closed form", summary="centroid and median distance (plugin test)",
          reference="fitbench plugin test")
def joiner_median(points):
    c = np.median(points, axis=0)
    return circle_result(points, c, float(np.median(np.hypot(*(points - c).T))), converged=True, message="closed form")
'''


@pytest.mark.slow
def test_plugin_methods_a_family_wildcard_takes_are_named_first(tmp_path):
    """An installed plugin's circle method joins every study naming ``circle.*`` (the default noise study grew from
    28,800 to 50,400 rows with a reviewer's plugin, silently): the run's first line says which methods of which
    distribution join which study; for a shipped study, how to reproduce its committed results. Which methods run is
    unchanged."""
    site = install_plugin(tmp_path, "fitbench-joiner", {"fitbench_joiner": JOINER},
                          {"fitbench.methods": {"joiner": "fitbench_joiner"}}, version="0.2.0")
    study = tmp_path / "wild.toml"
    study.write_text(textwrap.dedent('''
        name = "wild"
        title = "Every circle method"
        seed = 2
        [[datasets]]
        source = "circle"
        params = { n = 12, noise = 0.01 }
        [[methods]]
        id = "circle.*"
    '''))
    proc = run([str(study), "--out", str(tmp_path / "out"), "--jobs", "1", "--no-report"], cwd=REPO, path_first=[site])
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.splitlines()[0] == ("experiments.run: note: wild: 1 plugin method joins circle.* "
                                           "(circle.joiner_median of fitbench-joiner 0.2.0)"), proc.stderr
    assert "circle.joiner_median" in set(pd.read_csv(tmp_path / "out" / "wild" / "results.csv")["method"])
    shipped = run_python("-c", "from experiments import config\nfor n in ('noise', 'convergence'):\n"
                               "    print(config.plugin_notes(config.load(n)))", cwd=REPO, path_first=[site])
    assert shipped.returncode == 0, shipped.stderr
    noise, convergence = shipped.stdout.splitlines()
    assert noise == str(["noise: 1 plugin method joins circle.* (circle.joiner_median of fitbench-joiner 0.2.0); the "
                         "committed results were made without plugins: to reproduce them exactly, run in an "
                         "environment without plugins (docs/experiments.md)"]), shipped.stdout
    assert convergence == "[]"   # names its methods: nothing joins
