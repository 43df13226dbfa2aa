"""docs/plugins.md's new-family example (`SquareFit` and its method), run as written: its module becomes an
installed plugin (a distribution with a `fitbench.methods` entry point, on the path; offline), `fitbench fit`
prints its geometry with units and calls it converged, and a study runs it into `ok` rows.

The example was refused by the result gate (its result left `form_error` at its NaN default) and its geometry was
never printed (`fitbench fit` prints `report_lines`, which the example did not define)."""
import ast
import json
import re
import textwrap

import numpy as np
import pandas as pd
import pytest

from conftest import REPO, run_python

FIRST_LINE = "# my_package/square.py"


def example() -> str:
    """The docs' new-family module: the Python block of docs/plugins.md that starts with ``FIRST_LINE``."""
    text = (REPO / "docs" / "plugins.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    found = [b for b in blocks if b.startswith(FIRST_LINE)]
    assert len(found) == 1, f"docs/plugins.md has no Python block starting with {FIRST_LINE!r}"
    return found[0]


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    """(site folder holding the example as the installed distribution `docs-square` 0.1, the method id, a file of
    points on the outline of a square of side 3 mm centred at (10, -4) mm)."""
    root = tmp_path_factory.mktemp("docsquare")
    site = root / "site"
    package = site / "docs_square"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "square.py").write_text(example(), encoding="utf-8")
    info = site / "docs_square-0.1.dist-info"     # what pip writes: found by importlib.metadata on the path
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: docs-square\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[fitbench.methods]\nsquare = docs_square.square\n")
    (info / "top_level.txt").write_text("docs_square\n")
    rng = np.random.default_rng(7)
    t, one, edge = rng.uniform(-1.0, 1.0, 400), np.ones(400), np.arange(400) % 4   # 100 points on each edge
    unit_square = np.choose(edge[:, None], [np.c_[one, t], np.c_[t, one], np.c_[-one, t], np.c_[t, -one]])
    points = unit_square * 1.5 + np.array([10.0, -4.0])
    data = root / "square.csv"
    pd.DataFrame({"x [mm]": points[:, 0], "y [mm]": points[:, 1]}).to_csv(data, index=False)
    method = re.search(r'@register\("([\w.]+)"', example()).group(1)
    return site, method, data


def test_the_example_imports_only_public_names():
    imported = []
    for node in ast.walk(ast.parse(example())):
        if isinstance(node, ast.Import):
            imported += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            imported += [node.module, *(f"{node.module}.{a.name}" for a in node.names)]
    assert "methods.results.FitResult" in imported and "methods.register" in imported
    assert not [n for n in imported if any(part.startswith("_") for part in n.split("."))], imported


def test_fit_prints_the_new_familys_geometry_with_units_and_converges(plugin):
    site, method, data = plugin
    proc = run_python("-m", "fitbench", "fit", method, data, path_first=[site], timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    lines = dict(re.split(r"\s{2,}", ln.strip(), maxsplit=1) for ln in proc.stdout.splitlines()
                 if re.match(r"\S.*?\s{2,}\S", ln))
    assert lines["converged"] == "yes", proc.stdout
    points = pd.read_csv(data).to_numpy()
    lo, hi = points.min(axis=0), points.max(axis=0)
    for label, want in (("center x", (lo + hi)[0] / 2), ("center y", (lo + hi)[1] / 2), ("side", (hi - lo).mean())):
        value, unit = lines[label].split()
        assert unit == "mm" and float(value) == pytest.approx(want, abs=1e-9), (label, lines[label])
    value, unit = lines["form error"].split()
    assert unit == "mm" and 0 <= float(value) < 1e-9          # the points lie on the outline


@pytest.mark.slow
def test_a_study_runs_the_new_family_into_ok_rows_attributed_to_its_distribution(plugin, tmp_path):
    site, method, data = plugin
    study = tmp_path / "squares.toml"
    study.write_text(textwrap.dedent(f'''
        name = "squares"
        title = "The docs' square family on a measured outline"
        kind = "grid"
        seed = 1
        [[datasets]]
        file = "{data.as_posix()}"
        [[methods]]
        id = "{method}"
    '''), encoding="utf-8")
    out = tmp_path / "out"
    proc = run_python("-m", "experiments.run", study, "--jobs", "1", "--out", out, "--no-report", path_first=[site],
                      timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = pd.read_csv(out / "squares" / "results.csv")
    assert list(rows["status"]) == ["ok"] and rows.loc[0, "side"] == pytest.approx(3.0, abs=1e-9)
    assert (rows.loc[0, "center_x"], rows.loc[0, "center_y"]) == pytest.approx((10.0, -4.0), abs=1e-9)
    assert json.loads((out / "squares" / "meta.json").read_text(encoding="utf-8"))["plugins"] == {"docs-square": "0.1"}
