"""The manifest of the built-in methods (a cache in the user's cache folder): ``python -m methods list`` reads it
instead of importing the method families, and it is never a second source of truth: built from the registry by
the first listing, checked against it here, and used only while the digest of the ``methods`` sources it was
built from matches the files on disk. Adding a method is one new file: no regeneration step."""
import json
import re
import shutil
from dataclasses import asdict

import pytest

import methods
from conftest import REPO, run_python
from methods import _manifest
from fitbench.cli.commands import _jsonable

def test_the_manifest_is_the_registry(tmp_path, monkeypatch):
    monkeypatch.setenv("FITBENCH_CACHE_DIR", str(tmp_path))
    written = _manifest.write()
    assert written.parent == tmp_path and written.name.startswith("methods-manifest-")
    stored = json.loads(written.read_text(encoding="utf-8"))
    assert stored == _manifest.build()
    assert {m["id"] for m in stored["methods"]} == {s.id for s in methods.list_methods() if s.module.startswith("methods.")}
    assert [asdict(m) for m in _manifest.read()] == stored["methods"]


def registry_listing():
    return [{"id": s.id, "family": s.family, "kind": s.kind, "summary": s.summary, "reference": s.reference,
             "defaults": {k: _jsonable(v) for k, v in s.defaults.items()}} for s in methods.list_methods()]


@pytest.mark.parametrize("family", [None, "circle", "positioning"])
def test_list_from_the_manifest_equals_the_registry_and_imports_no_family(family, tmp_path, monkeypatch):
    monkeypatch.setenv("FITBENCH_CACHE_DIR", str(tmp_path))
    _manifest.write()
    probe = ("import json, sys, runpy\n"
             f"sys.argv = ['methods', 'list', '--json'] + {['--family', family] if family else []!r}\n"
             "try:\n    runpy.run_module('methods', run_name='__main__')\nexcept SystemExit:\n    pass\n"
             "print(json.dumps(sorted(m for m in sys.modules if m.startswith('methods.') and m.count('.') >= 2)))\n")
    out = run_python("-c", probe, FITBENCH_CACHE_DIR=str(tmp_path))
    assert out.returncode == 0, out.stderr
    listing, imported = out.stdout.rsplit("\n[", 1)
    families = {m.split(".")[1] for m in json.loads("[" + imported)}
    # the roundness package is imported by the CLI's parser itself (fitbench/cli/commands.py add_roundness builds the
    # 'roundness' subcommand from fitbench/cli/roundness.py); no other family may load for 'list'
    assert families <= {"roundness"}, f"list imported the method families {sorted(families)}"
    expected = [m for m in registry_listing() if family is None or m["family"] == family]
    assert json.loads(listing) == expected and expected


def test_a_manifest_of_other_sources_is_not_used(tmp_path, monkeypatch):
    monkeypatch.setenv("FITBENCH_CACHE_DIR", str(tmp_path / "cache"))
    stale = json.loads(_manifest.write().read_text(encoding="utf-8"))
    stale["methods"][0]["summary"] = "an old summary"
    stale["source_digest"] = "0" * 64
    path = tmp_path / "manifest.json"
    path.write_text(json.dumps(stale))
    assert _manifest.read(path) is None
    assert _manifest.read(tmp_path / "missing.json") is None
    current = _manifest.read()
    assert current is not None and [asdict(m) for m in current] == _manifest.build()["methods"]


def test_editing_a_method_without_regenerating_never_lists_stale_values(tmp_path):
    """A copy of the package whose kasa summary was edited but whose manifest was not regenerated: 'list'
    notices (the digest differs), imports the families and shows the edited summary."""
    copy = tmp_path / "repo"
    shutil.copytree(REPO / "methods", copy / "methods", ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    shutil.copytree(REPO / "fitbench", copy / "fitbench", ignore=shutil.ignore_patterns("__pycache__"))
    source = copy / "methods" / "circle" / "algebraic.py"
    text = source.read_text(encoding="utf-8")
    old = methods.get("circle.kasa").summary
    assert text.count(repr(old)[1:-1]) == 1
    source.write_text(text.replace(repr(old)[1:-1], "EDITED summary"), encoding="utf-8")
    out = run_python("-m", "methods", "list", "--json", "--family", "circle", cwd=copy, repo=copy)
    assert out.returncode == 0, out.stderr
    assert {m["id"]: m["summary"] for m in json.loads(out.stdout)}["circle.kasa"] == "EDITED summary"


def test_the_first_listing_fills_the_cache_and_the_next_one_reads_it(tmp_path):
    cache = tmp_path / "cache"
    first = run_python("-m", "methods", "list", "--json", FITBENCH_CACHE_DIR=str(cache))
    assert first.returncode == 0, first.stderr
    assert [p.name for p in cache.iterdir()] == [_manifest.path_for(_manifest.source_digest()).name]
    second = run_python("-m", "methods", "list", "--json", FITBENCH_CACHE_DIR=str(cache))
    assert second.returncode == 0 and json.loads(second.stdout) == json.loads(first.stdout)


METHOD_COPY = "gauss_newton_copy"


def readme_recipe():
    """(module code, its fitbench imports) of the README's "Add a method" recipe, as written there."""
    section = (REPO / "README.md").read_text(encoding="utf-8").split("\n## Add a method\n", 1)[1].split("\n## ", 1)[0]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    imports = "".join(line + "\n" for line in code.splitlines() if re.match(r"from methods[.\w]* import ", line))
    return code, imports


def readme_recipe_imports() -> str:
    code, imports = readme_recipe()
    assert "from methods.results import circle_result\n" in imports, imports
    return imports


def test_a_builtin_module_written_to_the_readme_recipe_loads(tmp_path):
    """The README's "Add a method" module, saved as written into the circle family of a copy of the package:
    ``import methods.results`` works first thing (no import circle through the family package), and ``list``
    shows the new method beside the built-ins."""
    code, _ = readme_recipe()
    readme_recipe_imports()
    copy = tmp_path / "repo"
    for part in ("methods", "fitbench"):
        shutil.copytree(REPO / part, copy / part, ignore=shutil.ignore_patterns("__pycache__", ".hypothesis"))
    (copy / "methods" / "circle" / "my_fit.py").write_text(code, encoding="utf-8")
    method_id = re.search(r'@register\("([\w.]+)"', code).group(1)
    env = {"FITBENCH_CACHE_DIR": str(tmp_path / "cache")}
    for first in ("import methods.results", "import methods.circle.my_fit", "import methods.circle.results"):
        out = run_python("-c", f"{first}; import methods; print(methods.get({method_id!r}).module)",
                         cwd=copy, repo=copy, **env)
        assert out.returncode == 0 and out.stdout.split() == ["methods.circle.my_fit"], (first, out.stderr)
    listing = run_python("-m", "methods", "list", "--json", cwd=copy, repo=copy, **env)
    assert listing.returncode == 0, listing.stderr
    ids = {m["id"] for m in json.loads(listing.stdout)}
    assert method_id in ids and {"circle.kasa", "ellipse.fitzgibbon", "roundness.iso12181"} <= ids


@pytest.mark.slow
def test_a_new_method_is_one_new_file(tmp_path):
    """Copy a circle method's module under a new name (its id renamed) into a copy of the repository: with no
    other edit it is registered, listed, and passes the registry-driven contract tests (exact data, similarity
    equivariance, the result interface)."""
    copy = tmp_path / "repo"
    for part in ("methods", "datasets", "experiments", "fitbench", "tests"):
        shutil.copytree(REPO / part, copy / part, ignore=shutil.ignore_patterns("__pycache__", ".hypothesis"))
    shutil.copy(REPO / "pyproject.toml", copy)
    source = (REPO / "methods" / "circle" / "gauss_newton.py").read_text(encoding="utf-8")
    assert source.count('@register("circle.gauss_newton"') == 1
    # the copy imports as the README's "Add a method" recipe says, exactly as written there
    imports = readme_recipe_imports()
    for private in ("from methods._registry import register\n", "from methods.circle.results import circle_result\n"):
        assert source.count(private) == 1
        source = source.replace(private, "")
    source = source.replace("from methods._frame import dot\n", "from methods._frame import dot\n" + imports, 1)
    (copy / "methods" / "circle" / f"{METHOD_COPY}.py").write_text(
        source.replace('"circle.gauss_newton"', f'"circle.{METHOD_COPY}"'), encoding="utf-8")
    env = {"FITBENCH_CACHE_DIR": str(tmp_path / "cache")}
    results = run_python("-c", "import methods.results", cwd=copy, repo=copy, **env)
    assert results.returncode == 0, results.stderr
    listing = run_python("-m", "methods", "list", "--json", "--family", "circle", cwd=copy, repo=copy, **env)
    assert listing.returncode == 0, listing.stderr
    assert f"circle.{METHOD_COPY}" in {m["id"] for m in json.loads(listing.stdout)}
    contract = run_python("-m", "pytest", "-q", "-p", "no:cacheprovider", "-k", METHOD_COPY,
                          "tests/test_circle_exact.py", "tests/test_properties.py", "tests/test_registry.py",
                          cwd=copy, repo=copy, timeout=600, **env)
    assert contract.returncode == 0, contract.stdout[-3000:] + contract.stderr[-2000:]
    passed = int(re.search(r"(\d+) passed", contract.stdout).group(1))
    assert passed >= 5 and "failed" not in contract.stdout, contract.stdout[-2000:]


def test_a_registry_lacking_a_built_in_is_never_stored(tmp_path, monkeypatch):
    """Whatever took a built-in method out of the registry (a plugin), the manifest cache is not written from it."""
    from methods import _registry
    methods.list_methods()
    monkeypatch.setenv("FITBENCH_CACHE_DIR", str(tmp_path))
    monkeypatch.delitem(_registry._REGISTRY, "circle.kasa")
    with pytest.raises(_manifest.IncompleteRegistryError, match="circle.kasa"):
        _manifest.write()
    assert "circle.kasa" not in {m.id for m in _manifest.describe_methods()}
    assert not list(tmp_path.iterdir())
