"""The cache key covers all code a row depends on: edit a copy of the repository (or of a plugin) and
the resumed run recomputes the rows, instead of serving stale ones; an edit elsewhere recomputes nothing."""
import json
import re
import shutil

import pytest

from conftest import REPO, install_plugin, run_python

pytestmark = pytest.mark.slow  # each case runs a study several times in a copy of the repository

STUDY = """
name = "keyed"
title = "cache key test"
kind = "{kind}"
seed = 3
repetitions = 2

# a declared table and a figure given as a file: no plot is drawn (the rows and their keys are what this file checks)
[[tables]]
caption = "form error"
rows = "method"
values = "form_error"

[[figures]]
caption = "not drawn"
file = "none.png"

[[datasets]]
generator = "circle"
params = {{ center = [1.0, 2.0], radius = 3.0, noise = 0.01, n = 15 }}

[[methods]]
id = "{method}"
"""


@pytest.fixture
def repo_copy(tmp_path):
    dst = tmp_path / "repo"
    for part in ("methods", "datasets", "experiments", "fitbench"):
        shutil.copytree(REPO / part, dst / part, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    shutil.copy(REPO / "pyproject.toml", dst)
    shutil.copy(REPO / "setup.py", dst)
    return dst


def run(repo, study, out, extra_path=()):
    proc = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "1", "--no-report", cwd=repo,
                      path_first=extra_path, repo=repo, timeout=300)
    assert proc.returncode == 0, proc.stderr
    m = re.search(r"(\d+) rows: (\d+) already stored, (\d+) to run", proc.stdout)
    assert m, proc.stdout
    return int(m.group(1)), int(m.group(3))


def append(path, text="\n# edited by the cache-key test\n"):
    path.write_text(path.read_text() + text)


def computed_then_served(repo, tmp_path, method, extra_path=()):
    """The keyed study of ``method`` (``tmp_path/keyed.toml``) run twice in ``repo``: its 2 rows computed, then served
    (the resumed run has nothing to do); (study, out folder)."""
    study = tmp_path / "keyed.toml"
    study.write_text(STUDY.format(kind="grid", method=method))
    out = tmp_path / "out"
    assert run(repo, study, out, extra_path) == (2, 2)
    assert run(repo, study, out, extra_path) == (2, 0)
    return study, out


#: code every row of a Kåsa grid study depends on: each edit alone must recompute the rows
ROW_CODE = ["experiments/metrics.py", "experiments/rows.py", "experiments/chunkrows.py", "datasets/synthetic.py",
            "experiments/studies/grid.py",
            "methods/circle/algebraic.py", "methods/circle/results.py", "methods/result_base.py",
            "methods/circle/_ckernels.c", "setup.py"]

#: ``python -c EDITS STUDY OUT FILE...`` in a copy of the repository: each FILE edited in turn, then the keyed study
#: run again (``experiments.run.main``) in this one interpreter, the code hashes forgotten first
#: (``codekeys.reset_caches``: a new process starts without them); one JSON line per FILE: [FILE, exit status,
#: rows, rows to run]. One interpreter for every edit, not one per edit: 13 starts of experiments.run were 9 s of CPU.
EDITS = """
import contextlib, io, json, re, sys
from pathlib import Path
from experiments import codekeys, run
study, out, *edited = sys.argv[1:]
for path in edited:
    Path(path).write_text(Path(path).read_text() + "\\n# edited by the cache-key test\\n")
    codekeys.reset_caches()
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = run.main([study, "--out", out, "--jobs", "1", "--no-report"])
    m = re.search(r"(\\d+) rows: (\\d+) already stored, (\\d+) to run", printed.getvalue())
    print(json.dumps([path, code, *(map(int, m.group(1, 3)) if m else [printed.getvalue()])]), flush=True)
"""


def test_editing_code_a_row_depends_on_recomputes_it(repo_copy, tmp_path):
    """One copy of the repository, edited one file at a time: after each edit the resumed run recomputes both rows
    (and stores them under the new key), so each file is checked on its own; an edit of code no row runs recomputes
    nothing. An edited C kernel source is refused until its kernel is rebuilt (rows of the old binary would be stored
    under the new source's key): that run starts a new process (a process checks its kernels once)."""
    study, out = computed_then_served(repo_copy, tmp_path, "circle.kasa")
    python_files = [f for f in ROW_CODE if not f.endswith(".c")]
    proc = run_python("-c", EDITS, study, out, "experiments/report.py", *python_files, cwd=repo_copy, repo=repo_copy,
                      timeout=600)
    assert proc.returncode == 0, proc.stderr
    runs = [json.loads(line) for line in proc.stdout.splitlines()]
    assert runs[0] == ["experiments/report.py", 0, 2, 0]  # not code of any row
    assert runs[1:] == [[edited, 0, 2, 2] for edited in python_files], "each edit must recompute the rows"
    for kernel in [f for f in ROW_CODE if f.endswith(".c")]:  # its binary is refused until rebuilt, then the rows run
        append(repo_copy / kernel, "\n/* edited by the cache-key test */\n")
        stale = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "1", "--no-report",
                           cwd=repo_copy, repo=repo_copy, timeout=300)
        assert stale.returncode == 2 and "is stale" in stale.stderr and "Traceback" not in stale.stderr, stale.stderr
        built = run_python("setup.py", "build_ext", "--inplace", "-q", cwd=repo_copy, repo=repo_copy, timeout=600)
        assert built.returncode == 0, built.stderr
        assert run(repo_copy, study, out) == (2, 2), f"editing {kernel} must recompute the rows"


def test_editing_a_file_source_recomputes(repo_copy, tmp_path):
    (tmp_path / "pts.csv").write_text("x,y\n1,0\n0,1\n-1,0\n0,-1.001\n")
    study = tmp_path / "keyed.toml"
    study.write_text(STUDY.format(kind="grid", method="circle.kasa").split("[[datasets]]")[0]
                     + '[[datasets]]\nfile = "pts.csv"\n\n[[methods]]\nid = "circle.kasa"\n')
    out = tmp_path / "out"
    assert run(repo_copy, study, out) == (1, 1)
    assert run(repo_copy, study, out) == (1, 0)
    (tmp_path / "pts.csv").write_text("x,y\n1,0\n0,1\n-1,0\n0,-1.002\n")
    assert run(repo_copy, study, out) == (1, 1)


PLUGIN = '''
"""A plugin fitter whose radius rule lives in a helper module of the same distribution."""
import numpy as np
from methods import register
from methods.results import circle_result
from fitbench_keyed_helper import radius_of


@register("circle.keyed_plugin", kind="closed form", summary="centroid, helper radius (cache-key test)",
          reference="fitbench cache-key test")
def keyed(points):
    c = points.mean(axis=0)
    return circle_result(points, c, radius_of(points, c), converged=True, message="closed form")
'''

HELPER = '''
import numpy as np


def radius_of(points, c):
    return float(np.hypot(*(points - c).T).mean())
'''


def test_editing_a_plugin_helper_module_recomputes(repo_copy, tmp_path):
    site = install_plugin(tmp_path, "fitbench-keyed-plugin",
                          {"fitbench_keyed_plugin": PLUGIN, "fitbench_keyed_helper": HELPER},
                          {"fitbench.methods": {"keyed": "fitbench_keyed_plugin"}})
    study, out = computed_then_served(repo_copy, tmp_path, "circle.keyed_plugin", [site])
    append(site / "fitbench_keyed_helper.py")  # the plugin module itself is unchanged
    assert run(repo_copy, study, out, [site]) == (2, 2)


def test_study_code_of_a_custom_study_is_keyed(repo_copy, tmp_path):
    """A study module with its own analysis code (here: positioning's quick grid) is keyed on it and on the
    simulator it imports, without any per-study workaround."""
    from experiments import codehash
    files = {str(p.relative_to(REPO)) for p in codehash.files_of("experiments.studies.positioning")}
    assert {"experiments/studies/positioning.py", "datasets/positioning.py", "methods/positioning/model.py"} <= files
    files = {str(p.relative_to(REPO)) for p in codehash.files_of("experiments.studies.multilateration")}
    assert "datasets/multilateration.py" in files
    metrics = {str(p.relative_to(REPO)) for p in codehash.files_of("experiments.metrics")}
    assert {"experiments/__init__.py", "experiments/metrics.py", "methods/result_base.py"} <= metrics
    # the metrics depend on the result contract (methods.result_base), never on a family's code or the report
    assert not [f for f in metrics if f.startswith(("experiments/render/",)) or f == "experiments/report.py"
                or f.count("/") > 1 and f.startswith("methods/")], metrics


BY_NAME = '''
"""A plugin fitter that calls a built-in method by its id (no import statement shows the dependency)."""
import methods
from methods import register


@register("circle.keyed_by_name", kind="closed form", summary="Kasa's circle by name (cache-key test)",
          reference="fitbench cache-key test")
def keyed_by_name(points):
    return methods.fit("circle.kasa", points)
'''


def test_a_method_called_by_name_is_keyed(repo_copy, tmp_path):
    """The roundness evaluation fits its reference circles with ``methods.fit("circle.minimum_zone", ...)``: the
    rows of a method that calls another by name are recomputed when that method's code changes (they were
    served stale before: the minimum zone's certificate changed and the committed roundness rows did not)."""
    from experiments import codehash
    import methods
    files = {str(p.relative_to(REPO)) for p in codehash.files_of(methods.get("roundness.iso12181").module)}
    assert {"methods/circle/minimum_zone.py", "methods/circle/_global.py", "methods/circle/gauss_newton.py"} <= files
    files = {str(p.relative_to(REPO)) for p in codehash.files_of(methods.get("circle.kasa").module)}
    assert not any(f.startswith("methods/roundness/") for f in files)
    site = install_plugin(tmp_path, "fitbench-keyed-by-name", {"fitbench_keyed_by_name": BY_NAME},
                          {"fitbench.methods": {"keyed_by_name": "fitbench_keyed_by_name"}})
    study, out = computed_then_served(repo_copy, tmp_path, "circle.keyed_by_name", [site])
    append(repo_copy / "methods/circle/algebraic.py")  # circle.kasa's module; the plugin is unchanged
    assert run(repo_copy, study, out, [site]) == (2, 2)
