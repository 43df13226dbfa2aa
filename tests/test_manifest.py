"""The manifest of the built-in methods (methods/_manifest.json, issue 20 start-up): ``python -m methods list``
reads it instead of importing the method families, and it is never a second source of truth: generated from
the registry (``python -m methods._manifest``), checked against it here, and used only while the digest of the
``methods`` sources it was built from matches the files on disk."""
import json
import shutil
from dataclasses import asdict

import pytest

import methods
from conftest import REPO, run_python
from methods import _manifest
from methods.cli import _jsonable

REGENERATE = "the manifest is out of date: run 'python -m methods._manifest' and commit methods/_manifest.json"


def test_committed_manifest_is_the_registry():
    stored = json.loads(_manifest.PATH.read_text(encoding="utf-8"))
    built = _manifest.build()
    assert stored["methods"] == built["methods"], REGENERATE
    assert stored["source_digest"] == built["source_digest"], REGENERATE
    assert {m["id"] for m in stored["methods"]} == {s.id for s in methods.list_methods() if s.module.startswith("methods.")}


def registry_listing():
    return [{"id": s.id, "family": s.family, "kind": s.kind, "summary": s.summary, "reference": s.reference,
             "defaults": {k: _jsonable(v) for k, v in s.defaults.items()}} for s in methods.list_methods()]


@pytest.mark.parametrize("family", [None, "circle", "positioning"])
def test_list_from_the_manifest_equals_the_registry_and_imports_no_family(family):
    probe = ("import json, sys, runpy\n"
             f"sys.argv = ['methods', 'list', '--json'] + {['--family', family] if family else []!r}\n"
             "try:\n    runpy.run_module('methods', run_name='__main__')\nexcept SystemExit:\n    pass\n"
             "print(json.dumps(sorted(m for m in sys.modules if m.startswith('methods.') and m.count('.') >= 2)))\n")
    out = run_python("-c", probe)
    assert out.returncode == 0, out.stderr
    listing, imported = out.stdout.rsplit("\n[", 1)
    families = {m.split(".")[1] for m in json.loads("[" + imported)}
    # the roundness package is imported by the CLI's parser itself (methods/cli.py add_roundness builds the
    # 'roundness' subcommand from methods/roundness/cli.py); no other family may load for 'list'
    assert families <= {"roundness"}, f"list imported the method families {sorted(families)}"
    expected = [m for m in registry_listing() if family is None or m["family"] == family]
    assert json.loads(listing) == expected and expected


def test_a_manifest_of_other_sources_is_not_used(tmp_path):
    stale = json.loads(_manifest.PATH.read_text(encoding="utf-8"))
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
