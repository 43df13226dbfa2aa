"""The manifest of the built-in methods: what ``python -m methods list`` shows, without importing the
method families (start-up time). It is a cache of the registry, never a file to edit or commit: it records
a digest of the source files it was built from (the modules of the ``methods`` package) and lives in the
user's cache folder (``$FITBENCH_CACHE_DIR``, else ``$XDG_CACHE_HOME/fitbench``, else ``~/.cache/fitbench``)
under that digest. :func:`describe_methods` reads it while the digest matches the files on disk; otherwise it
imports the families, reads the registry and stores the manifest for the next call (when the cache folder is
not writable, every call imports the families: slower, the same listing). Adding a method module therefore
needs no regeneration step.
"""
from __future__ import annotations

import hashlib
import json
import os
import sys
from dataclasses import asdict, fields
from pathlib import Path

from methods import _registry
from methods._registry import MethodInfo
from methods.files import write_atomic

_PACKAGE_DIR = Path(__file__).parent


def cache_dir() -> Path:
    """The folder of the manifest cache: ``$FITBENCH_CACHE_DIR``, ``$XDG_CACHE_HOME/fitbench`` or
    ``~/.cache/fitbench``."""
    if os.environ.get("FITBENCH_CACHE_DIR"):
        return Path(os.environ["FITBENCH_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "fitbench"


def path_for(digest: str) -> Path:
    """Where the manifest of the sources with ``digest`` is cached."""
    return cache_dir() / f"methods-manifest-{digest[:32]}.json"


#: modules of the package that no built-in method imports (the command line, this module): not hashed
_NOT_SOURCES = {"__main__.py", "_manifest.py", "files.py"}


def source_files() -> list[Path]:
    """The files whose code can decide the manifest: every module of the ``methods`` package (the built-in
    families, the registry and the helpers they import), except :data:`_NOT_SOURCES`."""
    return sorted(p for p in _PACKAGE_DIR.rglob("*.py") if p.relative_to(_PACKAGE_DIR).as_posix() not in _NOT_SOURCES)


def source_digest() -> str:
    h = hashlib.sha256()
    for path in source_files():
        h.update(path.relative_to(_PACKAGE_DIR).as_posix().encode() + b"\0")
        h.update(path.read_bytes() + b"\0")
    return h.hexdigest()


def info_of(spec: MethodInfo) -> MethodInfo:
    """The :class:`MethodInfo` part of a registered :class:`methods._registry.MethodSpec`."""
    return MethodInfo(**{f.name: getattr(spec, f.name) for f in fields(MethodInfo)})


class IncompleteRegistryError(RuntimeError):
    """The registry lacks built-in methods it had (taken out after loading): it is never stored as the manifest."""


def build() -> dict:
    """The manifest of the registry's built-in methods (imports the families); plugins are never in it. Raises
    :class:`IncompleteRegistryError` when a built-in method registered by :func:`methods._registry.load_builtins`
    is no longer in the registry."""
    _registry.load_builtins()
    missing = sorted(_registry.BUILTIN_IDS - set(_registry._REGISTRY))
    if missing:
        raise IncompleteRegistryError(f"the registry lacks the built-in methods {', '.join(missing)}; "
                                      f"the manifest is not stored")
    infos = [asdict(info_of(s)) for k, s in sorted(_registry._REGISTRY.items())
             if k in _registry.BUILTIN_IDS]
    return {"generated_by": "methods._manifest", "source_digest": source_digest(), "methods": infos}


def write(path: Path | None = None) -> Path:
    """Write :func:`build` atomically to ``path`` (default: the cache file of the current sources)."""
    manifest = build()
    path = path or path_for(manifest["source_digest"])
    write_atomic(path, json.dumps(manifest, indent=1, ensure_ascii=False) + "\n", fsync=False)
    return path


def read(path: Path | None = None) -> list[MethodInfo] | None:
    """The stored built-in methods, or None when there is no manifest or it was built from other sources."""
    digest = source_digest()
    try:
        stored = json.loads((path or path_for(digest)).read_text(encoding="utf-8"))
        if stored.get("source_digest") != digest:
            return None
        return [MethodInfo(**m) for m in stored["methods"]]
    except (OSError, ValueError, TypeError, KeyError):
        return None


def describe_methods(family: str | None = None) -> list[MethodInfo]:
    """Every method (built-in and plugin) as :class:`MethodInfo`, sorted by id, optionally of one family.
    The built-in ones come from the manifest while the families are not imported and the manifest is
    current, else from the registry (the same values: tests/test_manifest.py)."""
    _registry.load_plugins()
    stored = None if _registry.builtins_loaded() else read()
    if stored is None:
        _registry.load_builtins()
        stored = []
        try:
            write()
        except (OSError, IncompleteRegistryError):
            pass  # a read-only cache folder (the next call imports the families again, documented above), or a
            # registry a plugin took built-ins out of: never stored as the manifest; the listing shows the registry
    infos = {m.id: m for m in stored}
    infos.update((k, info_of(s)) for k, s in _registry._REGISTRY.items())
    return [m for k, m in sorted(infos.items()) if family is None or m.family == family]


if __name__ == "__main__":
    print(f"wrote {write()}", file=sys.stderr)  # fills the cache ahead of the first listing
