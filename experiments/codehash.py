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
import hashlib
import importlib.util
from functools import lru_cache
from importlib import metadata
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FITBENCH_PACKAGES = ("methods", "datasets", "experiments")
_BOOKKEEPING = {"RECORD", "INSTALLER", "REQUESTED", "direct_url.json"}


def _origin(name: str) -> Path | None:
    """The source file of module ``name`` (None: not found, built in, or a namespace package)."""
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError, AttributeError):
        return None
    if spec is None or not spec.origin or not spec.has_location:
        return None
    path = Path(spec.origin)
    return path if path.suffix == ".py" and path.exists() else None


def _method_modules() -> dict[str, str]:
    """{registered method id: its module}: built-in methods and installed plugins."""
    import methods
    return {spec.id: spec.module for spec in methods.list_methods()}


def _imported_names(path: Path, module: str, by_name: dict[str, str] | None = None) -> set[str]:
    """Every module name an import statement in ``path`` (module ``module``) may load, and the module of every
    method id in ``by_name`` that the file names in a string constant (a call by name)."""
    is_package = path.name == "__init__.py"
    package = module if is_package else module.rpartition(".")[0]
    names: set[str] = set()
    tree = ast.parse(path.read_bytes(), filename=str(path))
    for node in ast.walk(tree):
        if by_name and isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in by_name:
            names.add(by_name[node.value])
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1]) if node.level <= len(parts) else ""
                base = ".".join(p for p in (base, node.module or "") if p)
            else:
                base = node.module or ""
            if base:
                names.add(base)
                names.update(f"{base}.{a.name}" for a in node.names if a.name != "*")
    out = set()
    for name in names:  # importing a.b.c runs a/__init__ and a/b/__init__ too
        parts = name.split(".")
        out.update(".".join(parts[:k]) for k in range(1, len(parts) + 1))
    return out


@lru_cache(maxsize=None)
def module_closure(module: str) -> tuple[tuple[str, Path], ...]:
    """(module name, file) of ``module`` and every module of fitbench or of its own top-level package
    that it imports, directly or not (sorted by name)."""
    follow = set(FITBENCH_PACKAGES) | {module.split(".")[0]}
    by_name = _method_modules()
    follow |= {m.split(".")[0] for m in by_name.values()}
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
    return tuple(sorted(seen.items()))


def _imported_names_of_parents(module: str) -> list[str]:
    parts = module.split(".")
    return [".".join(parts[:k]) for k in range(1, len(parts) + 1)]


def _distribution_files(module: str) -> list[Path] | None:
    """The files of the installed distribution that provides ``module`` (None: no distribution)."""
    top = module.split(".")[0]
    dists = metadata.packages_distributions().get(top)
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


@lru_cache(maxsize=None)
def file_hash(path: str) -> str:
    """Hash of one data file's bytes (a ``file`` data source, a published set's CSV and JSON)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]


def distributions_of(modules) -> dict[str, str]:
    """{distribution name: version} of the modules that do not belong to this repository (plugins)."""
    out = {}
    for m in modules:
        path = _origin(m)
        if path is None or _in_repo(path):
            continue
        for dist_name in metadata.packages_distributions().get(m.split(".")[0], []):
            out[dist_name] = metadata.version(dist_name)
    return out
