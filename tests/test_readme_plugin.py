"""The README's plugin recipe ("Add a method"), run as written: its module and its entry-point table become an
installed package (offline), which imports no private module of fitbench, and whose method is run by a
study naming ``circle.*`` and reaches the report's cross-study rankings."""
import ast
import re
import textwrap

import pandas as pd
import pytest

from conftest import REPO, run_python
from pip_target import pip_install, write_pyproject


def recipe():
    """(module path, module code, entry-point TOML) from the README's "Add a method" section."""
    text = (REPO / "README.md").read_text()
    section = text.split("\n## Add a method\n", 1)[1].split("\n## ", 1)[0]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    toml = re.search(r"```toml\n(.*?)```", section, re.S).group(1)
    path = code.splitlines()[0].lstrip("# ").split()[0]
    return path, code, toml


def test_the_recipe_imports_only_public_names():
    _, code, _ = recipe()
    imported = []
    for node in ast.walk(ast.parse(code)):
        if isinstance(node, ast.Import):
            imported += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            imported.append(node.module)
            imported += [f"{node.module}.{a.name}" for a in node.names]
    assert "methods.results" in imported and "methods.register" in imported
    private = [name for name in imported if any(part.startswith("_") for part in name.split("."))]
    assert not private, private


@pytest.mark.slow
def test_the_recipe_installs_runs_and_reaches_the_rankings(tmp_path):
    path, code, toml = recipe()
    src = tmp_path / "src"
    module = src / path
    module.parent.mkdir(parents=True)
    (module.parent / "__init__.py").write_text("")
    module.write_text(code)
    package = module.parent.name
    write_pyproject(src, "readme-recipe", f'{toml}\n[tool.setuptools]\npackages = ["{package}"]\n')
    site = pip_install(src, tmp_path / "site")
    method_id = re.search(r'@register\("([\w.]+)"', code).group(1)
    # loading the plugin imports no private module the recipe did not already need (the registry's own)
    probe = textwrap.dedent(f'''
        import sys, methods
        before = set(sys.modules)
        methods.get("{method_id}")
        plugin = sys.modules["{package}.{module.stem}"]
        print(sorted(n for n in vars(plugin).values() if getattr(n, "__name__", "").startswith("methods._")))
    ''')
    proc = run_python("-c", probe, path_first=[site])
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"
    study = tmp_path / "mine.toml"
    study.write_text(textwrap.dedent('''
        name = "mine"
        title = "My method against the built-ins on the published profiles"
        kind = "grid"
        seed = 1
        [[datasets]]
        published = "roundness_set1"
        [[datasets]]
        published = "roundness_set2"
        [[methods]]
        id = "circle.kasa"
        [[methods]]
        id = "circle.gauss_newton"
        [[methods]]
        id = "%s"
        [[rankings]]
        profile = "circularity (form error; the minimum zone is the ISO 1101 value)"
        metric = "form_error"
        methods = "circle.*"
    ''' % method_id))
    results = tmp_path / "out"
    proc = run_python("-m", "experiments.run", study, "--jobs", "1", "--out", results, path_first=[site])
    assert proc.returncode == 0, proc.stderr
    rows = pd.read_csv(results / "mine" / "results.csv")
    assert set(rows[rows["method"] == method_id]["status"]) == {"ok"}
    report = (results / "paper" / "report.md").read_text()
    rankings = report.split("## Rankings across data sets", 1)[1]
    assert method_id in rankings
