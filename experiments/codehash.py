"""Hashes of the code a benchmark row depends on, for the engine's cache keys.

A row depends on: the method's module, the data source's code, ``experiments.metrics``, the study's own
module (``experiments.studies.<kind>``) and, for each of these, every module it imports. The import
closure is found **statically**: each module file is parsed with :mod:`ast` and every ``import`` /
``from ... import`` statement anywhere in it (also inside functions, so lazy imports count) is resolved
with :func:`importlib.util.find_spec`; parent packages' ``__init__.py`` are added because Python runs them.
The closure follows fitbench's own packages (``methods``, ``datasets``, ``experiments``) and the
package the start module belongs to; third-party libraries (numpy, scipy, ...) are recorded in
``meta.json`` by version instead. A static scan is used rather than ``sys.modules`` after an import
because it needs no fresh interpreter per module, sees imports inside functions that a run has not
executed yet, and is deterministic.

A module outside the repository (a plugin) is hashed with **its whole installed distribution**
(:func:`importlib.metadata.packages_distributions`; every file the distribution records, except the
installer's bookkeeping files ``RECORD``, ``INSTALLER``, ``REQUESTED``, ``direct_url.json`` and
byte code), so that editing any helper module of a plugin recomputes its rows. A plugin module found
without distribution metadata (a plain file on ``PYTHONPATH``) is hashed with its static closure.

A method called **by name** (``methods.fit("circle.minimum_zone", ...)``: the roundness evaluation's reference
circles, the circular test's fits) is a dependency no import statement shows: every string constant in a
scanned module that is a registered method id adds that method's module (and its closure), so editing the
minimum zone recomputes the roundness rows that use it.

A built-in method's closure is its own import graph: ``methods/__init__.py`` does not import the
families (the registry loads them by name on first use), so editing one family recomputes only the rows
of the methods whose modules import it (``circle.kasa``: the circle family and the shared helpers).
"""
from __future__ import annotations

import ast
import contextlib
import hashlib
import importlib.util
import json
import os
import sys
import tempfile
from functools import lru_cache
from importlib import metadata
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FITBENCH_PACKAGES = ("methods", "datasets", "experiments")
_BOOKKEEPING = {"RECORD", "INSTALLER", "REQUESTED", "direct_url.json"}


def main_file() -> Path | None:
    """The file of the program that runs (``__main__``: a script, or a module run with ``python -m``), None when it
    has none (``python -c``, an interactive session, a notebook)."""
    path = getattr(sys.modules.get("__main__"), "__file__", None)
    if not path or not str(path).endswith(".py"):
        return None
    path = Path(path).resolve()
    return path if path.is_file() else None


def _origin(name: str) -> Path | None:
    """The source file of module ``name`` (None: not found, built in, or a namespace package). A module of fitbench's
    own packages is found by its path under its package's folder, without importing its parent packages; the running
    program's ``__main__`` by its file (:func:`main_file`: code a script registers is keyed by the script)."""
    if name == "__main__":
        return main_file()
    top, _, rest = name.partition(".")
    if rest and top in FITBENCH_PACKAGES:
        base = _package_dir(top)
        if base is not None:
            stem = base.joinpath(*rest.split("."))
            for path in (stem.with_name(stem.name + ".py"), stem / "__init__.py"):
                if path.is_file():
                    return path
            return None
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError, AttributeError):
        return None
    if spec is None or not spec.origin or not spec.has_location:
        return None
    path = Path(spec.origin)
    return path if path.suffix == ".py" and path.exists() else None


@lru_cache(maxsize=None)
def _package_dir(top: str) -> Path | None:
    """The folder of one of fitbench's own packages (a regular package: its ``__init__.py`` beside its modules)."""
    try:
        spec = importlib.util.find_spec(top)
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.origin or not spec.origin.endswith("__init__.py"):
        return None
    return Path(spec.origin).parent


def _method_modules() -> dict[str, str]:
    """{registered method id: its module}: built-in methods and installed plugins."""
    import methods
    return {spec.id: spec.module for spec in methods.list_methods()}


def _imported_names(path: Path, module: str, by_name: dict[str, str] | None = None) -> set[str]:
    """Every module name an import statement in ``path`` (module ``module``) may load, and the module of every
    method id in ``by_name`` that the file names in a string constant (a call by name)."""
    imports, strings = _scan(path, module)
    names = set(imports)
    if by_name:
        names.update(by_name[s] for s in strings if s in by_name)
    out = set()
    for name in names:  # importing a.b.c runs a/__init__ and a/b/__init__ too
        parts = name.split(".")
        out.update(".".join(parts[:k]) for k in range(1, len(parts) + 1))
    return out


#: the file of :func:`_scan`'s results of earlier runs, by the SHA-256 of the module's name and bytes (a changed file is
#: parsed again; the cache only saves the parsing, ~0.5 s for the closure of experiments.run)
SCAN_CACHE = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "fitbench" / "import-scan.json"
_SCANNED: dict = {}
_SCAN_STATE = {"loaded": False, "new": 0}


def _scan(path: Path, module: str) -> tuple[list[str], list[str]]:
    """(module names the import statements of ``path`` name, its string constants that may be method ids) of module
    ``module``, parsed with :mod:`ast` or taken from :data:`SCAN_CACHE` (keyed by the module's name and the file's bytes)."""
    data = path.read_bytes()
    key = hashlib.sha256(f"{module}\0{path.name}\0".encode() + data).hexdigest()
    if not _SCAN_STATE["loaded"]:
        _SCAN_STATE["loaded"] = True
        try:
            cached = json.loads(SCAN_CACHE.read_text(encoding="utf-8"))
            if isinstance(cached, dict) and cached.get("version") == _SCAN_VERSION:
                _SCANNED.update(cached["entries"])
        except (OSError, ValueError, KeyError, TypeError):
            pass
    hit = _SCANNED.get(key)
    if hit is not None:
        return hit[0], hit[1]
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    imports: set[str] = set()
    strings: set[str] = set()
    for node in ast.walk(ast.parse(data, filename=str(path))):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value.count(".") == 1 \
                and len(node.value) <= 200 and "" not in node.value.split("."):  # 'family.name', as a method id is
            strings.add(node.value)
        if isinstance(node, ast.Import):
            imports.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1]) if node.level <= len(parts) else ""
                base = ".".join(p for p in (base, node.module or "") if p)
            else:
                base = node.module or ""
            if base:
                imports.add(base)
                imports.update(f"{base}.{a.name}" for a in node.names if a.name != "*")
    _SCANNED[key] = (sorted(imports), sorted(strings))
    _SCAN_STATE["new"] += 1
    return _SCANNED[key]


_SCAN_VERSION = 1


def _save_scans() -> None:
    """Write :data:`SCAN_CACHE` when this process parsed files it did not hold (atomically; a cache that cannot be
    written is not used: the hashes are the same, computed more slowly)."""
    if not _SCAN_STATE["new"]:
        return
    _SCAN_STATE["new"] = 0
    entries = _SCANNED if len(_SCANNED) <= 20000 else {}
    try:
        SCAN_CACHE.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=SCAN_CACHE.parent, prefix=".import-scan-", suffix=".tmp")
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump({"version": _SCAN_VERSION, "entries": entries}, fh)
        os.replace(tmp, SCAN_CACHE)
    except OSError:
        with contextlib.suppress(OSError, UnboundLocalError):
            os.unlink(tmp)


@lru_cache(maxsize=None)
def module_closure(module: str) -> tuple[tuple[str, Path], ...]:
    """(module name, file) of ``module`` and every module of fitbench or of its own top-level package
    that it imports, directly or not (sorted by name)."""
    follow = set(FITBENCH_PACKAGES) | {module.split(".")[0]}
    by_name = _method_modules()
    follow |= {m.split(".")[0] for m in by_name.values()}
    if module == "__main__" and main_file() is not None:  # a script's own modules beside it
        follow |= {n.split(".")[0] for n in _imported_names(main_file(), module, by_name)
                   if _beside(n.split(".")[0], main_file().parent)}
    seen: dict[str, Path] = {}
    todo = [p for p in _imported_names_of_parents(module)]
    while todo:
        name = todo.pop()
        if name in seen or name.split(".")[0] not in follow:
            continue
        path = _origin(name)
        if path is None:
            continue
        seen[name] = path
        todo.extend(_imported_names(path, name, by_name) - set(seen))
    _save_scans()
    return tuple(sorted(seen.items()))


def _beside(top: str, folder: Path) -> bool:
    """Whether the top-level module ``top`` is a file or package of ``folder`` (or below it)."""
    path = _origin(top)
    return path is not None and folder in path.parents


def _imported_names_of_parents(module: str) -> list[str]:
    parts = module.split(".")
    return [".".join(parts[:k]) for k in range(1, len(parts) + 1)]


@lru_cache(maxsize=None)
def _packages_distributions() -> dict:
    """:func:`importlib.metadata.packages_distributions` once per process (it reads every installed distribution's
    metadata: 0.25 s here)."""
    return metadata.packages_distributions()


def _distribution_files(module: str) -> list[Path] | None:
    """The files of the installed distribution that provides ``module`` (None: no distribution)."""
    top = module.split(".")[0]
    dists = _packages_distributions().get(top)
    if not dists:
        return None
    files = []
    for dist_name in sorted(set(dists)):
        dist = metadata.distribution(dist_name)
        for f in dist.files or []:
            if f.name in _BOOKKEEPING or f.suffix == ".pyc" or "__pycache__" in f.parts:
                continue
            p = Path(dist.locate_file(f))
            if p.is_file():
                files.append(p)
    return sorted(files) or None


def _in_repo(path: Path) -> bool:
    return REPO in path.resolve().parents


def files_of(module: str) -> list[Path]:
    """Every file the code of ``module`` depends on (see the module docstring)."""
    files = {path for _, path in module_closure(module)}
    for name, path in module_closure(module):
        if not _in_repo(path):
            files.update(_distribution_files(name) or [path])
    files.update(_compiled_sources(files))
    return sorted(files)


def _compiled_sources(files) -> set[Path]:
    """The C sources of the compiled kernels beside the repository's modules in ``files`` (a family loads
    its ``_ckernels`` by name through ``methods/_compiled.py``, which no import statement shows), and
    ``setup.py``, which holds their compile flags."""
    sources = {c for f in files if _in_repo(f) for c in Path(f).parent.glob("*.c")}
    if sources and (REPO / "setup.py").is_file():
        sources.add(REPO / "setup.py")
    return sources


def _digest(files) -> str:
    h = hashlib.sha256()
    for f in sorted(set(files)):
        p = Path(f).resolve()
        h.update((str(p.relative_to(REPO)) if _in_repo(p) else p.name).encode())
        h.update(b"\0")
        h.update(p.read_bytes())
        h.update(b"\0")
    return h.hexdigest()[:16]


@lru_cache(maxsize=None)
def code_hash(*modules: str) -> str:
    """One hash over every file the given modules depend on."""
    files = set()
    for m in modules:
        files.update(files_of(m))
    return _digest(files)


def file_hash(path: str) -> str:
    """Hash of one data file's bytes (a ``file`` data source, a published set's CSV and JSON), as the file is now: a
    data file is read again by every run, so a second run in one process after an edit must not reuse the first
    one's hash (it is remembered by the file's size and time stamp)."""
    try:
        st = os.stat(path)
    except OSError:
        return _file_hash(path, None, None)  # the read says what is wrong
    return _file_hash(path, st.st_mtime_ns, st.st_size)


@lru_cache(maxsize=None)
def _file_hash(path: str, mtime_ns, size) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]


def distributions_of(modules) -> dict[str, str]:
    """{distribution name: version} of the modules that do not belong to this repository (plugins)."""
    out = {}
    for m in modules:
        path = _origin(m)
        if path is None or _in_repo(path):
            continue
        for dist_name in _packages_distributions().get(m.split(".")[0], []):
            out[dist_name] = metadata.version(dist_name)
    return out
