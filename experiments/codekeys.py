"""The cache key's code part of a row: hashes of the code (and data files) a task's row depends on, and the
environment that changes numbers (``experiments.engine`` keys the rows with them; a Dask worker compares its own
with the run's, ``experiments.dask_executor.check_code``). Kept apart from the engine so that a worker imports
no more than it needs."""
from __future__ import annotations

import json
import sys

import methods
from datasets import sources
from experiments.rows import source_of

#: the libraries in every row's key: NumPy makes every row's data (its generators) and its BLAS is named beside it.
#: The other libraries a row's code imports (SciPy, Clarabel, NLopt, shapely, finufft, a plugin's dependencies) are
#: keyed with that code, by its imports (``experiments.codehash.libraries_of``), not by a list kept by hand.
NUMBER_PACKAGES = ("numpy",)
_CODE: dict = {}
_LIBRARIES: dict = {}
_ENV: dict = {}


def environment() -> dict:
    """What changes numbers besides the code and its libraries (computed once per process): the kernel backend
    (``FITBENCH_KERNELS``: compiled or numpy), Python's version, those of :data:`NUMBER_PACKAGES` and the BLAS NumPy
    calls (``numpy.show_config``: a NumPy of one version links OpenBLAS from PyPI, MKL from conda)."""
    if not _ENV:
        from importlib import metadata

        from methods import kernel_path
        versions = {"python": ".".join(map(str, sys.version_info[:3]))}
        for pkg in NUMBER_PACKAGES:
            try:
                versions[pkg] = metadata.version(pkg)
            except metadata.PackageNotFoundError:
                versions[pkg] = None
        _ENV.update(kernels=kernel_path(), versions=versions, blas=blas())
    return _ENV


def blas() -> str:
    """The BLAS library NumPy calls, as ``numpy.show_config`` names it ("unknown" where its format differs)."""
    try:
        import numpy as np
        cfg = np.show_config(mode="dicts")
        found = cfg.get("Build Dependencies", {}).get("blas", {})
        return f"{found.get('name', '?')} {found.get('version', '')}".strip()
    except Exception:  # numpy's config format is not a stable API
        return "unknown"


def forget_data_hashes() -> None:
    """Forget the code hashes of the data sets (a run of a process that ran studies before: the data files it reads
    may have changed since; the code it runs has not, its modules are the ones loaded), and the libraries of the
    tasks keyed so far (:func:`libraries`: those of the study that starts)."""
    _CODE.clear()
    _LIBRARIES.clear()


def libraries() -> dict:
    """{distribution: version} of the libraries the code of the tasks keyed since :func:`forget_data_hashes` imports (a
    study's rows: ``meta.json``'s ``libraries``), as their keys hold them (``experiments.codehash.libraries_of``)."""
    out: dict = {}
    for libs in _LIBRARIES.values():
        out.update(libs)
    return dict(sorted(out.items()))


def reset_caches() -> None:
    """Forget the code hashes and the environment (a test that edits code in the same process)."""
    from experiments import codehash
    _CODE.clear()
    _LIBRARIES.clear()
    _ENV.clear()
    codehash.code_hash.cache_clear()
    codehash.libraries_of.cache_clear()
    codehash.module_closure.cache_clear()
    codehash._origin.cache_clear()
    codehash._file_hash.cache_clear()
    codehash._packages_distributions.cache_clear()
    codehash._library.cache_clear()
    codehash._requirements.cache_clear()


def task_code(task: dict) -> dict:
    """Hashes of all code (and data files) a task's row depends on (see ``experiments.codehash``): the
    method's module and its imports, the data source, the metrics, the row runner (``experiments.rows``: the generic
    fit row, the data from the seed stream) and the study's own module. Computed once
    per (method, study kind, data set) in a run: the files are hashed once, not per row."""
    spec = task["dataset"]
    memo = (task["method"], task["kind"], json.dumps(spec, sort_keys=True, default=str))
    code = _CODE.get(memo)
    if code is None:
        from experiments import codehash
        study = f"experiments.studies.{task['kind']}"
        method = methods.get(task["method"]).module if task["method"] in _method_ids() else None
        has_source = _has_source(spec)
        code = {"method": module_code(method) if method else None,
                "source": source_hash(spec) if has_source else None,
                "metrics": codehash.code_hash("experiments.metrics", "experiments.timing"),
                "rows": codehash.code_hash("experiments.rows", "experiments.chunkrows"),
                "study": codehash.code_hash(study)}
        _CODE[memo] = code
        source = sources.get_source(source_of(spec)).module if has_source else None
        _LIBRARIES[memo] = codehash.libraries_of(*(m for m in (method, source) if m), "experiments.metrics",
                                                 "experiments.timing", "experiments.rows", "experiments.chunkrows",
                                                 study)
    return code


#: the stand-in code hash of a program without a file (``python -c``, an interactive session), one per process: the
#: rows of methods or data sources it registers are keyed by it, so that no later run takes them for its own
_UNKEYED: list = []


def module_code(module: str) -> str:
    """The code hash of a method's or data source's module (``experiments.codehash``). The running program's own
    ``__main__`` is keyed by its file; without one (``python -c``, a notebook) its rows cannot be keyed by their code
    and get a key of this process alone: they are computed again by every run, never reused."""
    from experiments import codehash
    if module == "__main__" and codehash.main_file() is None:
        if not _UNKEYED:
            import uuid
            _UNKEYED.append(f"no-file-{uuid.uuid4().hex}")
        return _UNKEYED[0]
    return codehash.code_hash(module)


def _has_source(spec: dict) -> bool:
    """Specs built by a study's own ``tasks`` may carry no registered source (its code is the study's)."""
    try:
        sources.get_source(source_of(spec))
    except KeyError:
        return False
    return True


def _method_ids() -> set[str]:
    return {s.id for s in methods.list_methods()}


def data_files(spec: dict) -> list:
    """The data files a data set's source reads (none for a generated set)."""
    source = sources.get_source(source_of(spec))
    if source.files is None:
        return []
    if "published" in spec:
        return list(source.files(spec["published"], spec.get("variant")))
    if "file" in spec:
        return list(source.files(spec["file"]))
    return list(source.files(**spec["params"]))


def source_hash(spec: dict) -> str:
    """Hash of a data set's source code (with its imports) and of the data files it reads."""
    from experiments import codehash
    source = sources.get_source(source_of(spec))
    return ":".join([module_code(source.module), *(codehash.file_hash(str(f)) for f in data_files(spec))])
