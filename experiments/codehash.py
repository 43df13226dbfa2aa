"""Hashes of the code a benchmark row depends on, for the engine's cache keys.

A row depends on: the method's module, the data source's code, ``experiments.metrics``, the study's own
module (``experiments.studies.<kind>``) and, for each of these, every module it imports. The import
closure is found **statically**: each module file is parsed with :mod:`ast` and every ``import`` /
``from ... import`` statement anywhere in it (also inside functions, so lazy imports count) is resolved
with :func:`importlib.util.find_spec`; parent packages' ``__init__.py`` are added because Python runs them.
The closure follows fitbench's own packages (``methods``, ``datasets``, ``experiments``) and the
package the start module belongs to. A static scan is used rather than ``sys.modules`` after an import
because it needs no fresh interpreter per module, sees imports inside functions that a run has not
executed yet, and is deterministic. Beside the modules of the repository's packages, every file that is not a Python
module is hashed too: the data a module reads from its folder, the C sources of the compiled kernels.

**Libraries** (numpy, scipy, shapely, finufft, a plugin's dependencies) are keyed by their installed version, not their
files (:func:`libraries_of`): each top-level module the closure imports and that is neither the standard library nor
fitbench's own, by an import statement or by a call that names it as a literal (``lazy_module("shapely")``,
``importlib.import_module("finufft")``), with the version of its distribution; and the requirements a plugin's
distribution declares. Upgrading one recomputes the rows whose code imports it.

A module outside the repository (a plugin) is hashed with **its whole installed distribution**
(:func:`importlib.metadata.packages_distributions`; every file the distribution records, except the
installer's bookkeeping files ``RECORD``, ``INSTALLER``, ``REQUESTED``, ``direct_url.json`` and
byte code), so that editing any helper module of a plugin recomputes its rows. A plugin whose record does not hold its
module (an editable install, ``pip install -e``: the record holds a path hook; a package found on ``PYTHONPATH``) is
hashed with **every file of its package's folder** (byte code, compiled extensions and hidden files excepted), so
that its data files and the helpers it imports by a computed name are keyed as they are edited; a single-file module of
an editable install with every file beside it. A single-file module without distribution metadata (a script's helper beside
it) is hashed with its static closure.

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


@lru_cache(maxsize=None)
def _origin(name: str) -> Path | None:
    """The source file of module ``name`` (None: not found, built in, or a namespace package). A module of fitbench's
    own packages is found by its path under its package's folder, without importing its parent packages; the running
    program's ``__main__`` by its file (:func:`main_file`: code a script registers is keyed by the script). Found once
    a process (the closures of a run's modules share most of their names; ``codekeys.reset_caches`` forgets it)."""
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
    spec = _spec(name)
    if spec is None or not spec.origin or not spec.has_location:
        return None
    path = Path(spec.origin)
    return path if path.suffix == ".py" and path.exists() else None


def _spec(name: str):
    """The module spec of ``name`` found without running any code of it or of its parent packages (what
    ``importlib.util.find_spec`` does for a dotted name by importing the parents: a package whose ``__init__`` exits,
    hangs or fails would act during the hashing of a key); None when not found."""
    import sys
    spec, path = None, None
    parts = name.split(".")
    for i in range(len(parts)):
        full = ".".join(parts[:i + 1])
        module = sys.modules.get(full)
        spec = getattr(module, "__spec__", None) if module is not None else None
        if spec is None:
            for finder in sys.meta_path:
                find = getattr(finder, "find_spec", None)
                try:
                    spec = find(full, path) if find is not None else None
                except Exception:  # a finder that cannot look there (a plugin's own finder): not found by it
                    spec = None
                if spec is not None:
                    break
        if spec is None:
            return None
        path = getattr(module, "__path__", None) if module is not None else spec.submodule_search_locations
        if path is None and i < len(parts) - 1:  # a module, not a package: nothing below it
            return None
    return spec


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


def _imported_names(path: Path, module: str, by_name: dict[str, str] | None = None, dynamic: set | None = None) -> set[str]:
    """Every module name an import statement in ``path`` (module ``module``) may load, and the module of every
    method id in ``by_name`` that the file names in a string constant (a call by name); the modules it imports by a
    call with a literal name are added to ``dynamic``."""
    imports, strings, called = _scan(path, module)
    if dynamic is not None:
        dynamic.update(called)
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
_SCAN_VERSION = 2
#: (one file per format: checkouts of two versions of fitbench on one machine do not overwrite each other's)
SCAN_CACHE = (Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "fitbench"
              / f"import-scan-{_SCAN_VERSION}.json")
_SCANNED: dict = {}
_SCAN_STATE = {"loaded": False, "new": 0}


#: calls that import the module their first argument names: ``importlib.import_module("shapely")``,
#: ``lazy_module("shapely")`` (``methods._lazy``), ``__import__("x")``
_IMPORT_CALLS = frozenset({"import_module", "lazy_module", "__import__"})


def _scan(path: Path, module: str) -> tuple[list[str], list[str], list[str]]:
    """(module names the import statements of ``path`` name, its string constants that may be method ids, the module
    names its calls of :data:`_IMPORT_CALLS` give as a literal) of module ``module``, parsed with :mod:`ast` or taken
    from :data:`SCAN_CACHE` (keyed by the module's name and the file's bytes)."""
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
        return hit[0], hit[1], hit[2]
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    imports: set[str] = set()
    strings: set[str] = set()
    dynamic: set[str] = set()
    for node in ast.walk(ast.parse(data, filename=str(path))):
        if isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant) \
                and isinstance(node.args[0].value, str) and node.args[0].value \
                and getattr(node.func, "attr", getattr(node.func, "id", None)) in _IMPORT_CALLS:
            dynamic.add(node.args[0].value.lstrip("."))
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
    _SCANNED[key] = (sorted(imports), sorted(strings), sorted(dynamic))
    _SCAN_STATE["new"] += 1
    return _SCANNED[key]


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


#: fitbench's packages that draw and write a study's outputs (figures, the report), never its rows: the closure of a
#: row's code does not enter them, although a study module imports them for its figures, so that a new matplotlib or
#: an edited figure style redraws the figures and recomputes no row. The outputs' own hash enters them
#: (``outputs=True``: ``experiments.engine.outputs_code``); tests/test_layers.py checks that the code every row runs
#: (``experiments.rows``, the metrics, the methods, the data sources) imports none of them.
OUTPUT_PACKAGES = ("experiments.render",)


def _output_module(name: str) -> bool:
    return any(name == p or name.startswith(p + ".") for p in OUTPUT_PACKAGES)


def module_closure(module: str, outputs: bool = False) -> tuple[tuple[str, Path], ...]:
    """(module name, file) of ``module`` and every module of fitbench or of its own top-level package
    that it imports, directly or not (sorted by name); without ``outputs``, none of :data:`OUTPUT_PACKAGES`."""
    return _walk(module, outputs)[0]


@lru_cache(maxsize=None)
def _walk(module: str, outputs: bool = False) -> tuple[tuple[tuple[str, Path], ...], frozenset]:
    """(:func:`module_closure`, the top-level names of the modules outside it that its modules import, by a statement
    or a call of :data:`_IMPORT_CALLS` with a literal name: the libraries, :func:`libraries_of`)."""
    follow = set(FITBENCH_PACKAGES) | {module.split(".")[0]}
    by_name = _method_modules()
    follow |= {m.split(".")[0] for m in by_name.values()}
    if module == "__main__" and main_file() is not None:  # a script's own modules beside it
        follow |= {n.split(".")[0] for n in _imported_names(main_file(), module, by_name)
                   if _beside(n.split(".")[0], main_file().parent)}
    seen: dict[str, Path] = {}
    outside: set[str] = set()
    dynamic: set[str] = set()
    todo = [p for p in _imported_names_of_parents(module)]
    while todo:
        name = todo.pop()
        if name in seen or (not outputs and _output_module(name)):
            continue
        if name.split(".")[0] not in follow:
            outside.add(name.split(".")[0])
            continue
        path = _origin(name)
        if path is None:
            continue
        seen[name] = path
        todo.extend(_imported_names(path, name, by_name, dynamic) - set(seen))
    _save_scans()
    outside.update(n.split(".")[0] for n in dynamic)
    return tuple(sorted(seen.items())), frozenset(outside - follow)


module_closure.cache_clear = _walk.cache_clear  # type: ignore[attr-defined]


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


#: files of a folder that are not a module's code or data: byte code, compiled extensions (their C source is hashed)
_NOT_CODE = (".pyc", ".pyo", ".so", ".pyd", ".dll", ".dylib")


def _plugin_files(module: str, path: Path) -> list[Path]:
    """The files a module outside the repository is keyed by: the files its installed distribution records when they
    hold the module's own file (a regular install ships what the package reads); otherwise (an editable install,
    ``pip install -e``, whose record holds only a path hook; a package on ``PYTHONPATH``) every file of the folder of
    its outermost package (:func:`_package_files`: its data files and the helpers it imports by a computed name), and
    of a single-file module of an editable install, every file beside it."""
    recorded = _distribution_files(module)
    if recorded and path.resolve() in {p.resolve() for p in recorded}:
        return recorded
    folder = _package_folder(path)  # (an editable install's record, its path hook, names this machine's folders)
    if folder is not None:
        return _package_files(folder, recursive=True)
    if recorded:  # a single-file module of an editable install: its project's files beside it
        return _package_files(path.parent, recursive=False)
    return [path]


def _package_folder(path: Path) -> Path | None:
    """The folder of the outermost regular package (with an ``__init__.py``) that holds the module file ``path``, None
    for a top-level module (a file of its own)."""
    folder = None
    parent = path.parent
    while (parent / "__init__.py").is_file():
        folder, parent = parent, parent.parent
    return folder


def _package_files(folder: Path, *, recursive: bool) -> list[Path]:
    """The regular files of ``folder`` (and of its sub-folders when ``recursive``), but byte code, compiled extensions
    and hidden files or folders (``.git``, an editor's ``.swp``)."""
    out = []
    for root, dirs, names in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if recursive and not d.startswith(".") and d != "__pycache__")
        out.extend(Path(root, n) for n in names
                   if not n.startswith(".") and not n.endswith(_NOT_CODE) and os.path.isfile(os.path.join(root, n)))
    return sorted(out)


def _in_repo(path: Path) -> bool:
    return _in_repo_text(str(path))


@lru_cache(maxsize=None)
def _in_repo_text(path: str) -> bool:
    """Whether ``path`` is the repository's own code: under its folder, and not in an installation of Python or of
    libraries made there (a virtual environment in the checkout, ``.venv`` as ``.ci/run`` makes it: its NumPy is a
    library, keyed by its version, not code of the repository)."""
    p = Path(path).resolve()
    if REPO not in p.parents:
        return False
    if any(part in ("site-packages", "dist-packages") for part in p.relative_to(REPO).parts):
        return False
    return not any(root in p.parents for root in _environments_in_repo())


@lru_cache(maxsize=None)
def _environments_in_repo() -> tuple[Path, ...]:
    """The folders of the running Python's installation (``sys.prefix``: a virtual environment) that lie in the
    repository."""
    roots = {Path(sys.prefix).resolve(), Path(sys.exec_prefix).resolve()}
    return tuple(r for r in roots if REPO in r.parents)


def files_of(module: str, outputs: bool = False) -> list[Path]:
    """Every file the code of ``module`` depends on (see the module docstring; ``outputs``: :func:`module_closure`)."""
    files = {path for _, path in module_closure(module, outputs)}
    for name, path in module_closure(module, outputs):
        if not _in_repo(path):
            files.update(_plugin_files(name, path))
    files.update(_data_beside(files))
    return sorted(files)


def _data_beside(files) -> set[Path]:
    """The files beside the repository's package modules in ``files`` that are not Python modules (these are keyed by
    the import closure): data a module reads from its folder, and the C sources of the compiled kernels (a family loads
    its ``_ckernels`` by name through ``methods/_compiled.py``, which no import statement shows) with ``setup.py``,
    which holds their compile flags."""
    folders = {Path(f).parent for f in files if _in_repo(f) and Path(f).parent != REPO}
    data = {p for folder in folders for p in _package_files(folder, recursive=False) if p.suffix != ".py"}
    if any(p.suffix == ".c" for p in data) and (REPO / "setup.py").is_file():
        data.add(REPO / "setup.py")
    return data


def _digest(files, libraries: dict | None = None) -> str:
    h = hashlib.sha256()
    if libraries:
        h.update(json.dumps(libraries, sort_keys=True).encode())
    for f in sorted(set(files)):
        p = Path(f).resolve()
        h.update((str(p.relative_to(REPO)) if _in_repo(p) else p.name).encode())
        h.update(b"\0")
        h.update(p.read_bytes())
        h.update(b"\0")
    return h.hexdigest()[:16]


@lru_cache(maxsize=None)
def code_hash(*modules: str, outputs: bool = False) -> str:
    """One hash over every file the given modules depend on and the versions of the libraries they import
    (:func:`libraries_of`); ``outputs``: also :data:`OUTPUT_PACKAGES` (the code of a study's outputs, not of a row)."""
    files = set()
    for m in modules:
        files.update(files_of(m, outputs))
    return _digest(files, libraries_of(*modules, outputs=outputs))


@lru_cache(maxsize=None)
def libraries_of(*modules: str, outputs: bool = False) -> dict[str, str | None]:
    """{distribution: version} of the libraries the code of ``modules`` imports (by a statement anywhere in a module
    of their closure, or a call of :data:`_IMPORT_CALLS` with a literal name: ``lazy_module("shapely")``), and of the
    requirements a plugin's distribution declares (``Requires-Dist``); None for a library that is not installed (an
    optional import). The standard library and fitbench's own packages are not libraries. (Remembered: do not change
    the dict it returns.)"""
    out: dict = {}
    for m in modules:
        closure, outside = _walk(m, outputs)
        for top in outside:
            out.update(_library(top))
        for name, path in closure:
            if not _in_repo(path):
                for dist_name in _packages_distributions().get(name.split(".")[0], []):
                    out.update(_requirements(dist_name))
    return dict(sorted(out.items()))


def _version(dist_name: str) -> str | None:
    try:
        return metadata.version(dist_name)
    except metadata.PackageNotFoundError:
        return None


@lru_cache(maxsize=None)
def _library(top: str) -> dict:
    """{distribution: version} of the top-level module ``top``, {} for the standard library and fitbench's own code.
    Found by the distribution of the module's name first (numpy, shapely, finufft), else by the records of the
    distributions in the module's folder (:func:`_distribution_in`), else by
    :func:`importlib.metadata.packages_distributions` (which reads every installed distribution: 0.3 s)."""
    if top in sys.stdlib_module_names or top in sys.builtin_module_names or top == "__main__":
        return {}
    try:
        spec = importlib.util.find_spec(top)
    except (ImportError, ValueError, AttributeError):
        spec = None
    if spec is None:
        return {top: None}   # not installed: an optional import (installing it changes the key)
    where = spec.origin if spec.has_location and spec.origin else next(iter(spec.submodule_search_locations or []), None)
    if where and _in_repo(Path(where)):
        return {}
    version = _version(top)
    if version is not None:
        return {top: version}
    if where:
        base = Path(where).parent.parent if Path(where).name == "__init__.py" else Path(where).parent
        found = _distribution_in(base, top)
        if found:
            return {found: _version(found)}
    dists = _packages_distributions().get(top) or []
    return {d: _version(d) for d in sorted(set(dists))} or {top: None}


def _distribution_in(folder: Path, top: str) -> str | None:
    """The name of the distribution installed in ``folder`` (a site-packages) whose record holds the top-level module
    ``top`` (``markdown_it`` of ``markdown-it-py``): the distributions whose name starts as the module's does are read
    first, each record once (a few ms, where :func:`importlib.metadata.packages_distributions` reads every
    distribution of every folder of the path: 0.3 s)."""
    try:
        infos = [p for p in folder.iterdir() if p.name.endswith(".dist-info")]
    except OSError:
        return None
    stem = top.lower().replace("-", "_")
    infos.sort(key=lambda p: (not p.name.lower().startswith(stem), p.name))
    for info in infos:
        try:
            record = (info / "RECORD").read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        if record.startswith((f"{top}/", f"{top}.py,")) or f"\n{top}/" in record or f"\n{top}.py," in record:
            return info.name[:-len(".dist-info")].rpartition("-")[0] or None
    return None


@lru_cache(maxsize=None)
def _requirements(dist_name: str) -> dict:
    """{distribution: version} of what a plugin's distribution requires (its ``Requires-Dist``, extras excepted), as
    installed (None: not installed)."""
    out = {}
    try:
        requires = metadata.distribution(dist_name).requires or []
    except metadata.PackageNotFoundError:  # named by packages_distributions, its metadata gone since: nothing declared
        requires = []
    for req in requires:
        name, _, marker = req.partition(";")
        if "extra" in marker:
            continue
        name = name.strip().split("[")[0]
        for sep in "<>=!~ (":
            name = name.split(sep)[0]
        if name:
            out[name] = _version(name)
    return out


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
