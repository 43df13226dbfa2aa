"""The benchmark engine: a study config expands into tasks (one row each); tasks run on local
processes or Dask; every finished row is stored at once (SQLite, one transaction a row) under a
cache key, so an interrupted run resumes without redoing or duplicating rows.

A task is a plain dict (picklable, sent to workers):
``{"index", "key", "study", "kind", "dataset": {...}, "repetition", "stream", "seed", "method",
"params", "timing": {...} | None, ...study-specific keys}``.

Data sets in a config (``[[datasets]]``), from the data-source registry ``datasets.sources``:
* ``source = "circle"`` (or the older ``generator = "circle"``; any registered source, plugins included)
  with fixed ``params = {...}`` and an optional ``grid = {...}`` whose values are lists (the cartesian
  product is taken); a random source gets ``repetitions`` draws, a fixed one a single repetition;
* ``published = "roundness_set3"`` (optional ``variant = "drop_repeated_closing_point"``);
* ``file = "trace.csv"`` (relative to the TOML; optional ``truth = { center = [..], radius = .. }``).

Cache keys (``task_key``) hash the task and all code its row depends on (``experiments.codehash``).
Methods (``[[methods]]``): ``id`` (or ``family.*``), fixed ``params``, optional ``grid``, ``max_n``
(skip larger data sets) and ``on`` (only the data sets with these labels).

Randomness: the data of (data set entry i, grid point j, repetition r) come from
``SeedSequence(seed, spawn_key=(i, j, r))``: every method sees the same noise, whichever worker
runs it, so all non-timing columns are deterministic for a config and seed.
"""
from __future__ import annotations

import hashlib
import importlib
import inspect
import itertools
import json
import time
from pathlib import Path

import numpy as np

import datasets
import methods
from datasets import sources
from experiments.metrics import metrics
from experiments.timing import time_call
from methods import InvalidInputError

ENGINE_VERSION = 1
REPO = Path(__file__).resolve().parents[1]


class ConfigError(InvalidInputError):
    """A study config that cannot run; the message names the file, the key and the problem."""


# ---------------------------------------------------------------- config expansion

def _grid(fixed: dict, grid: dict, where: str) -> list[dict]:
    for k, v in grid.items():
        if not isinstance(v, list) or not v:
            raise ConfigError(f"{where}: grid.{k} must be a non-empty list of values, got {v!r}")
    keys = list(grid)
    return [{**fixed, **dict(zip(keys, combo))} for combo in itertools.product(*(grid[k] for k in keys))] or [dict(fixed)]


def _source_of(spec: dict) -> str:
    """The registered data source of an expanded data set spec."""
    if "published" in spec:
        return "published"
    if "file" in spec:
        return "file"
    return spec.get("source") or spec["generator"]


def expand_datasets(cfg: dict, where: str) -> list[dict]:
    """Data set specs: one per grid point of each [[datasets]] entry, with its index pair.

    An entry names its source with exactly one of ``source = "NAME"`` (any registered source,
    ``datasets.sources``), ``generator = "circle"`` (the same, kept for old configs), ``published = "set"``
    (with optional ``variant``) or ``file = "path"`` (relative to the TOML; optional ``truth`` table)."""
    sources.load_plugins()
    base_dir = Path(cfg.get("_dir", "."))
    out = []
    for i, entry in enumerate(cfg.get("datasets", [])):
        here = f"{where} datasets[{i}]"
        if not isinstance(entry, dict):
            raise ConfigError(f"{here}: each data set is a table with 'source', 'generator', 'published' or 'file', "
                              f"got {entry!r}")
        unknown = set(entry) - {"source", "generator", "published", "file", "truth", "variant", "params", "grid", "label"}
        if unknown:
            raise ConfigError(f"{here}: unknown key(s) {', '.join(sorted(unknown))}")
        given = [k for k in ("source", "generator", "published", "file") if k in entry]
        if len(given) != 1:
            raise ConfigError(f"{here}: give exactly one of 'source', 'generator', 'published' and 'file'")
        if "published" in entry:
            name = entry["published"]
            if name not in datasets.list():
                raise ConfigError(f"{here}: unknown published data set {name!r}; known: {', '.join(datasets.list())}")
            variant = entry.get("variant")
            if variant not in (None, "drop_repeated_closing_point"):
                raise ConfigError(f"{here}: unknown variant {variant!r} (known: drop_repeated_closing_point)")
            out.append({"entry": i, "point": 0, "published": name, "variant": variant,
                        "label": entry.get("label", name + (f":{variant}" if variant else ""))})
            continue
        if "file" in entry:
            if not isinstance(entry["file"], str) or not entry["file"]:
                raise ConfigError(f"{here}: file must be a path (relative to the TOML), got {entry['file']!r}")
            path = (base_dir / entry["file"]).resolve()
            if not path.is_file():
                raise ConfigError(f"{here}: no data file {path} (file = {entry['file']!r} is relative to the TOML)")
            truth = entry.get("truth")
            if truth is not None and not isinstance(truth, dict):
                raise ConfigError(f"{here}: truth must be a table (e.g. {{ center = [0, 0], radius = 1 }})")
            spec = {"entry": i, "point": 0, "file": str(path), "label": entry.get("label", Path(entry["file"]).stem)}
            if truth is not None:
                spec["truth"] = truth
            out.append(spec)
            continue
        gen = entry.get("source", entry.get("generator"))
        try:
            source = sources.get_source(gen)
        except KeyError:
            what = "generator" if "generator" in entry else "data source"
            known = ", ".join(s.name for s in sources.list_sources() if s.name not in ("published", "file"))
            raise ConfigError(f"{here}: unknown {what} {gen!r}; known: {known}") from None
        if gen in ("published", "file"):
            raise ConfigError(f"{here}: write {gen} = ... instead of source = {gen!r}")
        allowed = set(source.parameters)
        fixed, grid = dict(entry.get("params", {})), dict(entry.get("grid", {}))
        bad = (set(fixed) | set(grid)) - allowed
        if bad:
            raise ConfigError(f"{here}: {'generator' if 'generator' in entry else 'data source'} {gen!r} has no parameter(s) {', '.join(sorted(bad))}; "
                              f"its parameters are: {', '.join(sorted(allowed))}")
        key = "generator" if "generator" in entry else "source"
        for j, params in enumerate(_grid(fixed, grid, here)):
            out.append({"entry": i, "point": j, key: gen, "params": params, "label": entry.get("label", gen),
                        **({} if source.random else {"fixed": True})})
    return out


def expand_methods(cfg: dict, where: str) -> list[tuple[str, dict]]:
    out = []
    for i, entry in enumerate(cfg.get("methods", [])):
        here = f"{where} methods[{i}]"
        if isinstance(entry, str):
            entry = {"id": entry}
        if not isinstance(entry, dict) or "id" not in entry:
            raise ConfigError(f"{here}: each method is an id or a table with 'id', got {entry!r}")
        unknown = set(entry) - {"id", "params", "grid", "max_n", "on"}
        if unknown:
            raise ConfigError(f"{here}: unknown key(s) {', '.join(sorted(unknown))}")
        mid = entry["id"]
        if mid.endswith(".*"):
            ids = [s.id for s in methods.list_methods(mid[:-2])]
            if not ids:
                raise ConfigError(f"{here}: no registered methods in family {mid[:-2]!r}")
        else:
            try:
                ids = [methods.get(mid).id]
            except methods.UnknownMethodError as exc:
                raise ConfigError(f"{here}: {exc}") from None
        fixed, grid = dict(entry.get("params", {})), dict(entry.get("grid", {}))
        for m in ids:
            bad = (set(fixed) | set(grid)) - set(methods.get(m).defaults)
            if bad:
                raise ConfigError(f"{here}: {m} has no parameter(s) {', '.join(sorted(bad))}; its parameters are: "
                                  f"{', '.join(methods.get(m).defaults) or 'none'}")
            for params in _grid(fixed, grid, here):
                out.append((m, {"params": params, "max_n": entry.get("max_n"), "on": entry.get("on")}))
    unique: dict = {}
    for m, extra in out:  # a later entry for the same method and parameters overrides (e.g. its max_n)
        unique[(m, json.dumps(extra["params"], sort_keys=True))] = (m, extra)
    return list(unique.values())


# ---------------------------------------------------------------- cache keys

def task_code(task: dict) -> dict:
    """Hashes of all code (and data files) a task's row depends on (see ``experiments.codehash``): the
    method's module and its imports, the data source, the metrics and the study's own module."""
    from experiments import codehash
    study = f"experiments.studies.{task['kind']}"
    method = methods.get(task["method"]).module if task["method"] in _method_ids() else None
    return {"method": codehash.code_hash(method) if method else None,
            "source": source_hash(task["dataset"]) if _has_source(task["dataset"]) else None,
            "metrics": codehash.code_hash("experiments.metrics", "experiments.timing"),
            "study": codehash.code_hash(study)}


def _has_source(spec: dict) -> bool:
    """Specs built by a study's own ``tasks`` may carry no registered source (its code is the study's)."""
    try:
        sources.get_source(_source_of(spec))
    except KeyError:
        return False
    return True


def _method_ids() -> set[str]:
    return {s.id for s in methods.list_methods()}


def task_key(task: dict) -> str:
    ident = {k: task[k] for k in ("kind", "dataset", "stream", "seed", "method", "params", "timing")}
    ident.update(code=task_code(task), engine=ENGINE_VERSION,
                 extra={k: v for k, v in task.items() if k.startswith("x_")})
    return hashlib.sha256(json.dumps(ident, sort_keys=True, default=str).encode()).hexdigest()[:24]


def grid_tasks(cfg: dict, where: str) -> list[dict]:
    """The generic expansion: data sets x repetitions x methods (x method grid)."""
    specs = expand_datasets(cfg, where)
    runs = expand_methods(cfg, where)
    reps = cfg.get("repetitions", 1)
    if not isinstance(reps, int) or reps < 1:
        raise ConfigError(f"{where}: repetitions must be a positive integer, got {reps!r}")
    timing = cfg.get("timing") or None
    if timing is not None:
        bad = set(timing) - {"min_time_s", "rounds"}
        if bad:
            raise ConfigError(f"{where}: timing has unknown key(s) {', '.join(sorted(bad))} (min_time_s, rounds)")
    tasks = []
    for spec in specs:
        n_rep = 1 if ("published" in spec or "file" in spec or spec.get("fixed")) else reps
        for r in range(n_rep):
            for m, extra in runs:
                if extra["on"] is not None and spec["label"] not in extra["on"]:
                    continue
                n = spec.get("params", {}).get("n")
                if extra["max_n"] is not None and n is not None and n > extra["max_n"]:
                    continue
                tasks.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": spec, "repetition": r,
                              "stream": [spec["entry"], spec["point"], r], "seed": cfg["seed"], "method": m,
                              "params": extra["params"], "timing": timing})
    return tasks


# ---------------------------------------------------------------- running one task (in a worker)

def load_data(spec: dict, seed: int, stream: list[int]):
    """Data and truth of a data set spec, from its registered source (random sources draw from the
    spec's own seed stream)."""
    if "published" in spec:
        return sources.get_source("published").load(None, name=spec["published"], variant=spec.get("variant"))
    if "file" in spec:
        return sources.get_source("file").load(None, path=spec["file"], truth=spec.get("truth"))
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=tuple(stream)))
    return sources.get_source(_source_of(spec)).load(rng, **spec["params"])


def source_hash(spec: dict) -> str:
    """Hash of a data set's source code (with its imports) and of the data files it reads."""
    from experiments import codehash
    source = sources.get_source(_source_of(spec))
    parts = [codehash.code_hash(source.module)]
    if source.files is not None:
        if "published" in spec:
            files = source.files(spec["published"], spec.get("variant"))
        elif "file" in spec:
            files = source.files(spec["file"])
        else:
            files = source.files(**spec["params"])
        parts += [codehash.file_hash(str(f)) for f in files]
    return ":".join(parts)


def base_row(task: dict) -> dict:
    spec = task["dataset"]
    row = {"study": task["study"], "dataset": spec["label"], "repetition": task["repetition"], "seed": task["seed"],
           "data_stream": ".".join(map(str, task["stream"])), "method": task["method"],
           "params": json.dumps(task["params"], sort_keys=True)}
    for k, v in spec.get("params", {}).items():
        row[f"data_{k}"] = v if np.isscalar(v) else json.dumps(v)
    for k, v in task["params"].items():
        row[f"param_{k}"] = v if np.isscalar(v) or v is None else json.dumps(v)
    return row


#: columns a generic row may have besides those of base_row (status, counts, every metric, timing)
RESULT_COLUMNS = ("status", "message", "converged", "iterations", "nfev", "form_error", "residual_rms", "center_x",
                  "center_y", "radius", "semi_axis_a", "semi_axis_b", "angle", "inner_radius", "outer_radius",
                  "center_error_x", "center_error_y", "center_error", "radius_error", "semi_axis_a_error",
                  "semi_axis_b_error", "angle_error", "task_index")


def fit_row(task: dict, points, truth) -> dict:
    """Fit, measure, time: the generic row of a task (exceptions become status 'error')."""
    row = base_row(task)
    try:
        res = methods.fit(task["method"], points, **task["params"])
    except InvalidInputError as exc:
        return {**row, "status": "skipped", "message": str(exc)}
    except Exception as exc:  # a method's bug: recorded, retried on the next run
        return {**row, "status": "error", "message": f"{type(exc).__name__}: {exc}"}
    row.update(status="ok" if res.converged else "not converged", message=res.message, converged=res.converged,
               iterations=res.iterations, nfev=res.nfev, **metrics(res, truth))
    if task.get("timing"):
        t = task["timing"]
        row.update(time_call(lambda: methods.fit(task["method"], points, **task["params"]),
                             min_time_s=t.get("min_time_s", 0.02), rounds=t.get("rounds", 5)))
    return row


def run_task(task: dict) -> dict:
    """Worker entry point: the study module's ``execute`` if it has one, else the generic fit."""
    study = importlib.import_module(f"experiments.studies.{task['kind']}")
    try:
        if hasattr(study, "execute"):
            row = study.execute(task)
        else:
            points, truth = load_data(task["dataset"], task["seed"], task["stream"])
            row = fit_row(task, points, truth)
    except Exception as exc:
        row = {**base_row(task), "status": "error", "message": f"{type(exc).__name__}: {exc}"}
    row["task_index"] = task["index"]
    return _plain(row)


def _plain(row: dict) -> dict:
    out = {}
    for k, v in row.items():
        if isinstance(v, np.generic):
            v = v.item()
        if isinstance(v, float) and not np.isfinite(v):
            v = None
        out[k] = v
    return out


# Row store and executors live in their own modules (re-exported here).
from experiments.store import RowStore  # noqa: E402,F401
from experiments.executors import BLAS_THREAD_VARS, _one_blas_thread_per_worker, execute  # noqa: E402,F401


def prepare(tasks: list[dict]) -> list[dict]:
    for i, t in enumerate(tasks):
        t["index"] = i
        t["key"] = task_key(t)
    return tasks


def run(tasks: list[dict], store: RowStore, *, force: bool, jobs: int, executor: str, scheduler: str | None,
        desc: str, log=print) -> tuple[list[dict], dict]:
    """Run what is not stored yet (and stored errors again); return the rows in task order."""
    keys = [t["key"] for t in tasks]
    if force:
        store.forget(keys)
    status = store.done(keys)
    todo = [t for t in tasks if status.get(t["key"]) in (None, "error")]
    counts = {"tasks": len(tasks), "stored": len(tasks) - len(todo), "to_run": len(todo),
              "retried_errors": sum(status.get(t["key"]) == "error" for t in tasks)}
    log(f"   {counts['tasks']} rows: {counts['stored']} already stored, {counts['to_run']} to run"
        + (f" ({counts['retried_errors']} failed before, retried)" if counts["retried_errors"] else ""))
    t0 = time.perf_counter()
    execute(todo, store, work=run_task, jobs=jobs, executor=executor, scheduler=scheduler, desc=desc)
    counts["wall_s"] = time.perf_counter() - t0
    stored = store.get_by_key(keys)
    # the order of the rows is the order of the tasks of this config, whatever order they were stored in
    rows = [{**stored[t["key"]], "task_index": t["index"]} for t in tasks if t["key"] in stored]
    return rows, counts
