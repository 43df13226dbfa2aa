"""The code hash finds a module's source without running any of it: a dotted name's parent packages are not imported
(``importlib.util.find_spec`` imports them), so a package whose ``__init__`` exits or fails cannot act while a row's
key is computed."""
from __future__ import annotations

import sys

from experiments import codehash


def test_a_submodule_is_found_without_running_its_package(tmp_path, monkeypatch):
    pkg = tmp_path / "exits_on_import"
    (pkg / "inner").mkdir(parents=True)
    (pkg / "__init__.py").write_text("raise SystemExit(3)\n")
    (pkg / "inner" / "__init__.py").write_text("raise RuntimeError('inner ran')\n")
    (pkg / "inner" / "deep.py").write_text("X = 1\n")
    (pkg / "mod.py").write_text("Y = 2\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert codehash._origin("exits_on_import.mod") == pkg / "mod.py"
    assert codehash._origin("exits_on_import.inner.deep") == pkg / "inner" / "deep.py"
    assert codehash._origin("exits_on_import.mod.nothing") is None   # a module has nothing below it
    assert codehash._origin("exits_on_import.missing") is None
    assert "exits_on_import" not in sys.modules and "exits_on_import.inner" not in sys.modules


def test_an_imported_package_s_submodule_is_found_as_before():
    import methods.circle
    assert codehash._origin("methods.circle.results").name == "results.py"
    import email.mime
    assert codehash._origin("email.mime.text").name == "text.py"
