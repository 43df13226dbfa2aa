"""What a plugin author edits or upgrades is in the key: an editable install's data files and the helpers it imports by
a computed name, a data file beside a method of this repository, and the versions of the libraries a row's code
imports (a plugin's dependencies, shapely, finufft). Each case: the resumed run recomputes the rows instead of
serving the old ones as up to date."""
import json
import textwrap

import pytest

from conftest import REPO, install_plugin, run_python
from pip_target import pip_install, write_pyproject
from test_cache_key import STUDY, append, computed_then_served, repo_copy, run  # noqa: F401  (repo_copy: a fixture)

pytestmark = pytest.mark.slow  # each case installs a plugin or copies the repository and runs a study several times

FIT = '''
"""A plugin fitter that reads its scale from a data file beside it and its factor from a helper module imported by a
computed name (neither is an import statement)."""
import importlib
import json
from pathlib import Path

import numpy as np
from methods import register
from methods.results import circle_result

SCALE = json.loads((Path(__file__).parent / "data" / "coeffs.json").read_text())["scale"]


@register("circle.keyed_editable", kind="closed form", summary="scaled centroid fit (cache-key test)",
          reference="fitbench cache-key test")
def keyed_editable(points):
    helper = importlib.import_module(__name__.rpartition(".")[0] + "." + "helper")
    c = points.mean(axis=0)
    r = float(np.hypot(*(points - c).T).mean()) * SCALE * helper.FACTOR
    return circle_result(points, c, r, converged=True, message="closed form")
'''


def editable_plugin(tmp_path):
    """``pip install -e`` of a package ``fb_keyed_edit``: the distribution records only its path hook; the package is
    found in its source folder (put first on the path, as the hook would)."""
    src = tmp_path / "src"
    pkg = src / "fb_keyed_edit"
    (pkg / "data").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "fit.py").write_text(textwrap.dedent(FIT))
    (pkg / "helper.py").write_text("FACTOR = 1.0\n")
    (pkg / "data" / "coeffs.json").write_text('{"scale": 1.0}\n')
    write_pyproject(src, "fb-keyed-edit", '[project.entry-points."fitbench.methods"]\nkeyed = "fb_keyed_edit.fit"\n'
                                          '[tool.setuptools]\npackages = ["fb_keyed_edit"]\n')
    site = pip_install(src, tmp_path / "site", editable=True)
    assert not [p for p in site.rglob("*.py") if "fb_keyed_edit" in p.parts]  # editable: the code stays in src
    return site, src, pkg


def test_an_editable_plugins_data_file_and_dynamic_helper_are_keyed(tmp_path):
    site, src, pkg = editable_plugin(tmp_path)
    study, out = computed_then_served(REPO, tmp_path, "circle.keyed_editable", [site, src])
    (src / "README.md").write_text("not the package's\n")  # beside the package, not in it
    assert run(REPO, study, out, [site, src]) == (2, 0)
    (pkg / "data" / "coeffs.json").write_text('{"scale": 2.0}\n')
    assert run(REPO, study, out, [site, src]) == (2, 2), "an edited data file of the package must recompute its rows"
    append(pkg / "helper.py", "FACTOR = 3.0\n")
    assert run(REPO, study, out, [site, src]) == (2, 2), "an edited helper imported by a computed name must too"
    (pkg / "__pycache__").mkdir(exist_ok=True)
    (pkg / "__pycache__" / "helper.cpython-311.pyc").write_bytes(b"byte code is not code")
    assert run(REPO, study, out, [site, src]) == (2, 0)


def test_a_data_file_beside_a_repository_module_is_keyed(repo_copy):  # noqa: F811
    """A method of this repository that reads a file beside its module (the README's recipe, methods/circle/my_fit.py)
    is keyed by it; a Python module beside it is keyed only by the import closure (editing it recomputes nothing)."""
    code = ("from experiments import codehash\n"
            "print(sorted(str(p.relative_to(codehash.REPO)) for p in codehash.files_of('methods.circle.algebraic')))\n")

    def files():
        proc = run_python("-c", code, cwd=repo_copy, repo=repo_copy, timeout=120)
        assert proc.returncode == 0, proc.stderr
        return proc.stdout
    before = files()
    assert "methods/circle/_ckernels.c" in before and "setup.py" in before and "_ckernels.cpython" not in before
    (repo_copy / "methods" / "circle" / "my_fit_table.json").write_text("[1, 2]\n")
    assert "methods/circle/my_fit_table.json" in files()


FAKEDEP = '''
def scale():
    return {scale}
'''

DEP_PLUGIN = '''
"""A plugin fitter whose numbers come from another distribution (fakedep_keyed)."""
import numpy as np
import fakedep_keyed
from methods import register
from methods.results import circle_result


@register("circle.keyed_dep", kind="closed form", summary="uses a library (cache-key test)",
          reference="fitbench cache-key test")
def keyed_dep(points):
    c = points.mean(axis=0)
    return circle_result(points, c, float(np.hypot(*(points - c).T).mean()) * fakedep_keyed.scale(), converged=True,
                         message="closed form")
'''


def upgraded(tmp_path, plugin, library: str, method: str, what: str):
    """A study of ``method`` (its plugin installed in ``plugin``) run twice with version 1.0 of ``library`` (the
    second run serves every row) and once with 2.0, which must recompute them (``what`` was upgraded);
    (study, out folder, the site of 2.0)."""
    module = library.replace("-", "_")
    old = install_plugin(tmp_path / "old", library, {module: FAKEDEP.format(scale=1.0)}, {}, "1.0")
    new = install_plugin(tmp_path / "new", library, {module: FAKEDEP.format(scale=2.0)}, {}, "2.0")
    study, out = computed_then_served(REPO, tmp_path, method, [plugin, old])
    assert run(REPO, study, out, [plugin, new]) == (2, 2), f"an upgraded {what} must recompute the rows"
    return study, out, new


def test_the_version_of_a_library_the_method_imports_is_keyed(tmp_path):
    plugin = install_plugin(tmp_path / "plugin", "fb-keyed-dep", {"fb_keyed_dep": DEP_PLUGIN},
                            {"fitbench.methods": {"keyed_dep": "fb_keyed_dep"}})
    study, out, new = upgraded(tmp_path, plugin, "fakedep-keyed", "circle.keyed_dep", "library")
    # meta.json names the libraries of each study's rows: a study run after it in the same command has its own
    builtin = tmp_path / "builtin.toml"
    builtin.write_text(STUDY.format(kind="grid", method="circle.kasa").replace('name = "keyed"', 'name = "builtin"'))
    both = run_python("-m", "experiments.run", study, builtin, "--out", out, "--jobs", "1", "--no-report",
                      path_first=[plugin, new], timeout=300)
    assert both.returncode == 0, both.stderr
    keyed = json.loads((out / "keyed" / "meta.json").read_text())["libraries"]
    alone = json.loads((out / "builtin" / "meta.json").read_text())["libraries"]
    assert keyed["fakedep_keyed"] == "2.0" and keyed["numpy"] and alone["numpy"] and "fakedep_keyed" not in alone


def test_the_libraries_of_the_built_in_methods_are_found_by_their_imports():
    """Imports by a statement and by ``lazy_module("shapely")``; a method that imports neither is not keyed by them."""
    from experiments import codehash
    import methods
    magnify = codehash.libraries_of(methods.get("magnify.nearest").module)
    roundness = codehash.libraries_of(methods.get("roundness.iso12181").module)
    kasa = codehash.libraries_of(methods.get("circle.kasa").module)
    assert magnify["shapely"] and magnify["numpy"] and roundness["finufft"] and kasa["numpy"]
    assert "shapely" not in kasa and "finufft" not in kasa and not {"os", "math", "methods", "experiments"} & set(kasa)


REQ_PLUGIN = '''
"""A plugin fitter whose library is reached through a name (a registry of another library), never imported here."""
import importlib

import numpy as np
from methods import register
from methods.results import circle_result

LIBRARY = "fakedep" + "_declared"


@register("circle.keyed_req", kind="closed form", summary="a library by a computed name (cache-key test)",
          reference="fitbench cache-key test")
def keyed_req(points):
    c = points.mean(axis=0)
    scale = importlib.import_module(LIBRARY).scale()
    return circle_result(points, c, float(np.hypot(*(points - c).T).mean()) * scale, converged=True,
                         message="closed form")
'''


def test_the_version_of_a_declared_requirement_is_keyed(tmp_path):
    """A library the plugin's code never names in an import is keyed by its distribution's ``dependencies``."""
    src = tmp_path / "req_src"
    src.mkdir()
    (src / "fb_keyed_req.py").write_text(textwrap.dedent(REQ_PLUGIN))
    write_pyproject(src, "fb-keyed-req", 'dependencies = ["fakedep-declared>=1.0"]\n'
                                         '[project.entry-points."fitbench.methods"]\nkeyed = "fb_keyed_req"\n'
                                         '[tool.setuptools]\npy-modules = ["fb_keyed_req"]\n')
    plugin = pip_install(src, tmp_path / "plugin_site")
    upgraded(tmp_path, plugin, "fakedep-declared", "circle.keyed_req", "requirement")


def test_a_virtual_environment_inside_the_checkout_holds_libraries_not_repository_code(monkeypatch):
    """.ci/run makes its virtual environment in the checkout (.venv): NumPy there is a library keyed by its version
    (its files were taken for the repository's own code: no library was keyed, and CI failed on it)."""
    import sys

    from experiments import codehash
    monkeypatch.setattr(sys, "prefix", str(codehash.REPO / ".venv"))
    monkeypatch.setattr(sys, "exec_prefix", str(codehash.REPO / ".venv"))
    codehash._in_repo_text.cache_clear()
    codehash._environments_in_repo.cache_clear()
    try:
        lib = codehash.REPO / ".venv" / "lib" / "python3.11" / "site-packages" / "numpy" / "__init__.py"
        assert not codehash._in_repo(lib)
        assert not codehash._in_repo(codehash.REPO / ".venv" / "bin" / "tool.py")  # the environment's own files
        assert not codehash._in_repo(codehash.REPO / "other-env" / "lib" / "site-packages" / "x.py")
        assert codehash._in_repo(codehash.REPO / "methods" / "circle" / "algebraic.py")
        assert not codehash._in_repo(codehash.REPO.parent / "elsewhere.py")
    finally:
        codehash._in_repo_text.cache_clear()
        codehash._environments_in_repo.cache_clear()
