"""The benchmark engine: a study config expands into tasks (one row each); tasks run on local
processes or Dask; every finished row is stored at once (SQLite, one transaction a row) under a
cache key, so an interrupted run resumes without redoing or duplicating rows.

A task is a plain dict (picklable, sent to workers):
``{"index", "key", "study", "kind", "dataset": {...}, "repetition", "stream", "seed", "method",
"params", "timing": {...} | None, ...study-specific keys}``.

Data sets in a config (``[[datasets]]``):
* ``generator = "circle"`` with fixed ``params = {...}`` and an optional ``grid = {...}`` whose
  values are lists (the cartesian product is taken); synthetic data get ``repetitions`` noise draws;
* ``published = "roundness_set3"`` (optional ``variant = "drop_repeated_closing_point"``).
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
from datasets.synthetic import GENERATORS, generate
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


def expand_datasets(cfg: dict, where: str) -> list[dict]:
    """Data set specs: one per grid point of each [[datasets]] entry, with its index pair."""
    out = []
    for i, entry in enumerate(cfg.get("datasets", [])):
        here = f"{where} datasets[{i}]"
        if not isinstance(entry, dict):
            raise ConfigError(f"{here}: each data set is a table with 'generator' or 'published', got {entry!r}")
        unknown = set(entry) - {"generator", "published", "variant", "params", "grid", "label"}
        if unknown:
            raise ConfigError(f"{here}: unknown key(s) {', '.join(sorted(unknown))}")
        if ("generator" in entry) == ("published" in entry):
            raise ConfigError(f"{here}: give exactly one of 'generator' and 'published'")
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
        gen = entry["generator"]
        if gen not in GENERATORS:
            raise ConfigError(f"{here}: unknown generator {gen!r}; known: {', '.join(GENERATORS)}")
        allowed = set(inspect.signature(GENERATORS[gen]).parameters) - {"rng"}
        fixed, grid = dict(entry.get("params", {})), dict(entry.get("grid", {}))
        bad = (set(fixed) | set(grid)) - allowed
        if bad:
            raise ConfigError(f"{here}: generator {gen!r} has no parameter(s) {', '.join(sorted(bad))}; "
                              f"its parameters are: {', '.join(sorted(allowed))}")
        for j, params in enumerate(_grid(fixed, grid, here)):
            out.append({"entry": i, "point": j, "generator": gen, "params": params, "label": entry.get("label", gen)})
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

_code_hashes: dict[str, str] = {}


def code_hash(method_id: str) -> str:
    """Hash of the code a method runs: its family package (or plugin module) and fitbench's core."""
    module = methods.get(method_id).module
    if module in _code_hashes:
        return _code_hashes[module]
    path = Path(inspect.getfile(importlib.import_module(module))).resolve()
    builtin = REPO / "methods" in path.parents
    files = sorted(path.parent.glob("*.py")) if builtin else [path]  # the family package, or the plugin
    files += sorted((REPO / "methods").glob("_*.py"))
    h = hashlib.sha256()
    for f in files:
        h.update(f.name.encode())
        h.update(f.read_bytes())
    _code_hashes[module] = h.hexdigest()[:16]
    return _code_hashes[module]


def task_key(task: dict) -> str:
    ident = {k: task[k] for k in ("kind", "dataset", "stream", "seed", "method", "params", "timing")}
    method = task["method"]
    study = importlib.import_module(f"experiments.studies.{task['kind']}")
    if hasattr(study, "task_key_method"):  # tasks whose 'method' is not a registry id name the code they run
        method = study.task_key_method(task)
    ident.update(code=code_hash(method), engine=ENGINE_VERSION,
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
        n_rep = 1 if "published" in spec else reps
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
    """Points and truth of a data set spec (synthetic data from its own seed stream)."""
    if "published" in spec:
        ds = datasets.load(spec["published"], drop_repeated_closing_point=spec.get("variant") == "drop_repeated_closing_point")
        return ds.points, None
    if "file" in spec:
        return datasets.read_points(spec["file"]), spec.get("truth")
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=tuple(stream)))
    return generate(spec["generator"], rng, **spec["params"])


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
    execute(todo, store, jobs=jobs, executor=executor, scheduler=scheduler, desc=desc)
    counts["wall_s"] = time.perf_counter() - t0
    stored = store.get_by_key(keys)
    # the order of the rows is the order of the tasks of this config, whatever order they were stored in
    rows = [{**stored[t["key"]], "task_index": t["index"]} for t in tasks if t["key"] in stored]
    return rows, counts
