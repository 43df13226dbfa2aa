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
import itertools
import json
import re
import time
from pathlib import Path

import datasets
import methods
from datasets import sources
from experiments.executors import execute
from experiments.jsontext import json_value
from experiments.rowframe import MissingRows, RowFrame
from experiments.codekeys import _method_ids, environment, task_code
from experiments.chunkrows import run_chunk
from experiments.rows import RERUN_STATUSES, raise_if_signalled, row_from_json, source_of
from experiments.store import RowStore
from experiments.study import ConfigError
from methods import InvalidInputError
from methods.files import check_regular
from methods.plugins import failed as plugin_failed

ENGINE_VERSION = 2
REPO = Path(__file__).resolve().parents[1]


# ---------------------------------------------------------------- config expansion

def _grid(fixed: dict, grid: dict, where: str) -> list[dict]:
    for k, v in grid.items():
        if not isinstance(v, list) or not v:
            raise ConfigError(f"{where}: grid.{k} must be a non-empty list of values, got {v!r}")
        seen: dict = {}
        for value in v:  # a value twice runs its rows twice, and the summary pools them
            same = ("number", float(value)) if type(value) in (int, float) else json.dumps(value, sort_keys=True, default=str)
            if same in seen:
                twice = f"{value!r} appears twice" if repr(seen[same]) == repr(value) else \
                    f"{seen[same]!r} and {value!r} are the same value"
                raise ConfigError(f"{where}: grid.{k}: {twice}; give each value once (a typo?)")
            seen[same] = value
    keys = list(grid)
    return [{**fixed, **dict(zip(keys, combo))} for combo in itertools.product(*(grid[k] for k in keys))] or [dict(fixed)]


def expand_datasets(cfg: dict, where: str) -> list[dict]:
    """Data set specs: one per grid point of each [[datasets]] entry, with its index pair.

    An entry names its source with exactly one of ``source = "NAME"`` (any registered source,
    ``datasets.sources``), ``generator = "circle"`` (the same, kept for old configs), ``published = "set"``
    (with optional ``variant``) or ``file = "path"`` (relative to the TOML; optional ``truth`` table)."""
    sources.load_plugins()
    base_dir = Path(getattr(cfg, "folder", "."))  # a loaded config (experiments.config.StudyConfig) knows its folder
    out = []
    for i, entry in enumerate(cfg.get("datasets", [])):
        here = f"{where} datasets[{i}]"
        if not isinstance(entry, dict):
            raise ConfigError(f"{here}: each data set is a table with 'source', 'generator', 'published' or 'file', "
                              f"got {entry!r}")
        unknown = set(entry) - {"source", "generator", "published", "file", "truth", "variant", "params", "grid", "label",
                                *FILE_READING}
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
            if not path.exists():
                raise ConfigError(f"{here}: no data file {path} (file = {entry['file']!r} is relative to the TOML)")
            try:   # a device, FIFO or folder: said so (not "no data file"), without opening it
                check_regular(path)
            except InvalidInputError as exc:
                raise ConfigError(f"{here}: {exc}") from None
            truth = entry.get("truth")
            if truth is not None and not isinstance(truth, dict):
                raise ConfigError(f"{here}: truth must be a table (e.g. {{ center = [0, 0], radius = 1 }})")
            spec = {"entry": i, "point": 0, "file": str(path), "label": entry.get("label", Path(entry["file"]).stem)}
            if truth is not None:
                spec["truth"] = truth
            reading = {k: entry[k] for k in FILE_READING if k in entry}
            if reading:
                spec["read"] = reading
            check_file(spec, here)
            out.append(spec)
            continue
        if set(entry) & set(FILE_READING):
            raise ConfigError(f"{here}: {', '.join(sorted(set(entry) & set(FILE_READING)))} belong(s) to a file = ... "
                              f"data set")
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


#: the keys of a ``file = ...`` data set that say how to read it (``datasets.read_points``' options)
FILE_READING = ("columns", "plane", "unit", "skip_rows")
_FILES_READ: dict = {}


def check_file(spec: dict, where: str) -> None:
    """Read a ``file`` data set once (per file version and reading options) when its config is expanded: a file the
    rows could not read is refused before any row runs, with the reader's message in the config's words."""
    path = Path(spec["file"])
    try:
        stat = path.stat()
    except OSError as exc:
        raise ConfigError(f"{where}: cannot read {path}: {exc.strerror}") from None
    memo = (str(path), stat.st_size, stat.st_mtime_ns, json.dumps(spec.get("read", {}), sort_keys=True))
    if memo in _FILES_READ:
        return
    try:
        sources.get_source("file").load(None, path=str(path), **spec.get("read", {}))
    except InvalidInputError as exc:
        raise ConfigError(f"{where}: {_in_config_words(str(exc))}") from None
    if len(_FILES_READ) > 256:
        _FILES_READ.clear()
    _FILES_READ[memo] = True


#: the reader's command-line options in a message, as the keys of a ``file = ...`` data set
_CONFIG_WORDS = (("--columns NAME NAME", 'columns = ["X", "Y"]'), ("--columns 0 1", "columns = [0, 1]"),
                 ("--plane xy|yz|zx", 'plane = "xy", "yz" or "zx"'), ("--columns", "columns"),
                 ("--skip-rows ", "skip_rows = "), ("--unit", "unit"))


def _in_config_words(text: str) -> str:
    """A reader's message in the words of a study's TOML (its options are keys of the data set there)."""
    for option, key in _CONFIG_WORDS:
        text = text.replace(option, key)
    return re.sub(r"--plane (xy|yz|zx)\b", r'plane = "\1"', text)


def expand_methods(cfg: dict, where: str) -> list[tuple[str, dict]]:
    out = []
    for i, entry in enumerate(cfg.get("methods", [])):
        here = f"{where} methods[{i}]"
        if isinstance(entry, str):
            entry = {"id": entry}
        if not isinstance(entry, dict) or "id" not in entry:
            raise ConfigError(f"{here}: each method is an id or a table with 'id', got {entry!r}")
        unknown = set(entry) - {"id", "params", "grid", "max_n", "on", "any_family"}
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

def script_code(used) -> list[str]:
    """The method ids and source names among ``used`` ((method id, source name) pairs) that the running program's
    ``__main__`` registers: worker processes do not import it, so they would not know them."""
    found = []
    known = _method_ids()
    for method, source in sorted(used, key=str):
        if method in known and methods.get(method).module == "__main__" and method not in found:
            found.append(method)
        if source is not None:
            try:
                spec = sources.get_source(source)
            except KeyError:
                continue
            if spec.module == "__main__" and source not in found:
                found.append(source)
    return found


def _source_name(spec) -> str | None:
    """The registered source a data set spec names, if any."""
    if isinstance(spec, dict) and any(k in spec for k in ("published", "file", "source", "generator")):
        return source_of(spec)
    return None


def runs_plugin_code(used) -> bool:
    """Whether rows of these (method id, source name) pairs run an installed plugin's code: a method or data source
    of a distribution other than fitbench (such rows always run in a worker process, which a plugin that ends its
    process cannot take the run down with). Code registered by the calling program itself (a script, a test) is
    not a plugin: worker processes would not know it."""
    from methods.plugins import distributions_of
    known = _method_ids()
    modules = set()
    for method, source in used:
        if method in known and not methods.get(method).builtin:
            modules.add(methods.get(method).module)
        if source is not None:
            try:
                spec = sources.get_source(source)
            except KeyError:
                continue
            if not spec.builtin:
                modules.add(spec.module)
    return bool(modules) and bool(distributions_of(sorted(modules)))


def _ident(task: dict) -> str:
    """Everything a row depends on except its seed stream, as canonical JSON."""
    ident = {k: task[k] for k in ("kind", "dataset", "seed", "method", "params", "timing")}
    ident.update(code=task_code(task), engine=ENGINE_VERSION, env=environment(),
                 extra={k: v for k, v in task.items() if k.startswith("x_")})
    return json.dumps(ident, sort_keys=True, default=str)


def _key(ident: str, stream) -> str:
    return hashlib.sha256(f"{ident}|{stream}".encode()).hexdigest()[:24]


def task_key(task: dict) -> str:
    """The row's cache key: its identity, the code it depends on, the environment that changes numbers."""
    return _key(_ident(task), task["stream"])


def _grid_parts(cfg: dict, where: str):
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
    return specs, runs, reps, timing


def _repetitions(spec: dict, reps: int) -> int:
    """The repetitions of a data set: one for data read or fixed, else the study's."""
    return 1 if ("published" in spec or "file" in spec or spec.get("fixed")) else reps


def _pairs(spec: dict, runs: list) -> list[tuple[str, dict]]:
    """(method id, params) of the method runs on a data set (its ``on`` labels and ``max_n``)."""
    n = spec.get("params", {}).get("n")
    return [(m, extra["params"]) for m, extra in runs
            if (extra["on"] is None or spec["label"] in extra["on"])
            and (extra["max_n"] is None or n is None or n <= extra["max_n"])]


def grid_rows(cfg: dict, where: str) -> int:
    """The number of rows of the generic grid (:func:`iter_grid_tasks`), counted without making its tasks: each
    data set's repetitions x the method runs its ``on`` and ``max_n`` leave it."""
    specs, runs, reps, _ = _grid_parts(cfg, where)
    return sum(_repetitions(spec, reps) * len(_pairs(spec, runs)) for spec in specs)


def why_no_rows(cfg: dict, where: str) -> str:
    """Why the generic grid has no rows, in the TOML's words: its methods' ``on`` and ``max_n`` against its data
    sets' labels and sizes (for the one-line refusal of a study without rows)."""
    specs, runs, _, _ = _grid_parts(cfg, where)
    sizes: dict = {}
    for spec in specs:
        sizes.setdefault(spec["label"], []).append(spec.get("params", {}).get("n"))
    data = [f"{label}" + (f" (n = {', '.join(str(n) for n in dict.fromkeys(ns) if n is not None)})"
                          if any(n is not None for n in ns) else "") for label, ns in sizes.items()]
    ways = [f"{m}" + "".join(f" {k} = {json.dumps(extra[k])}" for k in ("on", "max_n") if extra[k] is not None)
            for m, extra in runs]
    ways = list(dict.fromkeys(ways))
    return (f"no method runs on a data set: their on = [...] and max_n leave out every one (the data sets: "
            f"{'; '.join(data[:5])}{' ...' if len(data) > 5 else ''}; the methods: {'; '.join(ways[:5])}"
            f"{' ...' if len(ways) > 5 else ''}); widen on or max_n")


def iter_grid_tasks(cfg: dict, where: str, *, keyed: bool = False):
    """The generic expansion, lazily: data sets x repetitions x methods (x method grid), in row order.
    With ``keyed`` each task also gets its ``index`` and cache ``key`` (the identity of each (data set,
    method) pair is serialised once, not per repetition)."""
    specs, runs, reps, timing = _grid_parts(cfg, where)
    index = 0
    study, kind, seed = cfg["name"], cfg["kind"], cfg["seed"]
    for spec in specs:
        n_rep = _repetitions(spec, reps)
        pairs = _pairs(spec, runs)
        prefixes = [None] * len(pairs)  # per pair, the hash state after its identity: a key hashes only its stream
        entry, point = spec["entry"], spec["point"]
        for r in range(n_rep):
            stream_text = f"[{entry}, {point}, {r}]".encode()  # str([entry, point, r])
            for j, (m, params) in enumerate(pairs):
                task = {"study": study, "kind": kind, "dataset": spec, "repetition": r, "stream": [entry, point, r],
                        "seed": seed, "method": m, "params": params, "timing": timing}
                if keyed:
                    prefix = prefixes[j]
                    if prefix is None:
                        prefix = prefixes[j] = hashlib.sha256(f"{_ident(task)}|".encode())
                    h = prefix.copy()
                    h.update(stream_text)
                    task["index"] = index
                    task["key"] = h.hexdigest()[:24]
                    index += 1
                yield task


def grid_tasks(cfg: dict, where: str) -> list[dict]:
    """The generic expansion: data sets x repetitions x methods (x method grid)."""
    return list(iter_grid_tasks(cfg, where))


def result_columns() -> tuple[str, ...]:
    """The columns a generic row may have besides those of base_row: the engine's own and every column a result class
    declares (``methods.result_base.row_columns``), a plugin's loaded by now included."""
    return ("status", "message", "converged", "iterations", "nfev", *methods.result_base.row_columns(), "task_index")


def prepare(tasks: list[dict]) -> list[dict]:
    for i, t in enumerate(tasks):
        t["index"] = i
        t["key"] = task_key(t)
    return tasks


def iter_prepared(tasks):
    """Index and key the tasks of an iterable, lazily."""
    for i, t in enumerate(tasks):
        t["index"] = i
        t["key"] = task_key(t)
        yield t


def _blocks(iterable, size: int):
    it = iter(iterable)
    while True:
        block = list(itertools.islice(it, size))
        if not block:
            return
        yield block


class _Interner:
    """Equal strings of decoded rows share one object (the study, method, status, params of 10^5 rows)."""

    def __init__(self, limit: int = 200_000):
        self.table: dict = {}
        self.limit = limit

    def __call__(self, text: str) -> dict:
        row = row_from_json(text)
        table = self.table
        for k, v in row.items():
            if type(v) is str and len(v) < 256 and k != "data_stream":  # data_stream: one per row
                s = table.get(v)
                if s is None:
                    if len(table) < self.limit:
                        table[v] = v
                else:
                    row[k] = s
        return row


# ---------------------------------------------------------------- a study whose outputs are up to date

def outputs_code(cfg: dict) -> str:
    """Hash of what a study's outputs depend on besides its rows: its config, the code that analyses the rows and
    writes the outputs (``experiments.run`` with everything it imports, the study's module, ``fitbench.plots``, the
    installed plugins' modules with their distributions), the environment of the keys and the versions of the
    packages that compute, draw and format the outputs."""
    from importlib import metadata

    from experiments import codehash
    from experiments.provenance import PACKAGES
    versions = {}
    for pkg in PACKAGES:
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = None
    # plugins register plots (and columns) when they load: their code, with their whole distribution, is part of it;
    # one that failed to load registered nothing, and finding a module imports its package again (a sys.exit() there)
    methods.load_plugins()
    sources.load_plugins()
    plugins = sorted({ep.module for group in ("fitbench.methods", "fitbench.datasets")
                      for ep in metadata.entry_points(group=group) if not plugin_failed(group, ep)})
    ident = {"config": dict(cfg), "quick": bool(getattr(cfg, "quick", False)),  # a loaded config's [quick] flag
             "code": codehash.code_hash("experiments.run", "fitbench.plots", f"experiments.studies.{cfg['kind']}",
                                       outputs=True),
             "plugins": codehash.code_hash(*plugins) if plugins else None,
             "engine": ENGINE_VERSION, "env": environment(), "versions": versions}
    return hashlib.sha256(json.dumps(ident, sort_keys=True, default=str).encode()).hexdigest()


def fingerprint(outputs: str, keys) -> str:
    """A study's outputs (:func:`outputs_code`) and the cache keys of all its rows, in order: equal fingerprints mean
    the same rows (each key covers all code its row depends on) analysed by the same code."""
    h = hashlib.sha256(outputs.encode())
    for key in keys:
        h.update(key.encode())
        h.update(b"\n")
    return h.hexdigest()[:32]


#: the outputs of a study besides the files its report.json names
OUTPUT_FILES = ("results.csv", "summary.csv", "summary.md", "report.json", "meta.json")


def up_to_date(cfg: dict, tasks, target: Path) -> int | None:
    """The number of rows of a study whose outputs in ``target`` are those a run would write now, else None: its
    ``meta.json`` names the same :func:`fingerprint` (the same row keys, output code, environment and versions), no
    row is to be run again (:data:`RERUN_STATUSES`), ``results.csv`` is the file the run wrote (its SHA-256), every
    output and every table and figure of ``report.json`` is there, and the row store says it holds all the rows of
    that fingerprint (a change of the store since, by any program, clears that record). ``tasks``: a function
    returning a fresh iterable of the prepared tasks."""
    from experiments.verdict import results_sha256
    target = Path(target)
    try:
        meta = json_value((target / "meta.json").read_text(encoding="utf-8"))
        manifest = json_value((target / "report.json").read_text(encoding="utf-8"))
        named = [e["file"] for e in manifest.get("tables", []) + manifest.get("figures", [])]
    except (OSError, ValueError, TypeError, KeyError, AttributeError):
        return None
    old = meta.get("fingerprint") if isinstance(meta, dict) else None
    if not old or set(meta.get("status_counts") or {}) & set(RERUN_STATUSES) or not (target / "rows.sqlite").is_file():
        return None
    if not all((target / f).is_file() for f in (*OUTPUT_FILES, *named)):
        return None
    if fingerprint(outputs_code(cfg), (t["key"] for t in tasks())) != old:
        return None
    if results_sha256(target) != meta.get("results_sha256"):
        return None
    return RowStore.holds_complete(target / "rows.sqlite", old)


# ---------------------------------------------------------------- the run

class Landing:
    """Where the executors put each finished chunk: the row store (the cache, one transaction a chunk) and the run's
    frame (:class:`experiments.rowframe.RowFrame`), from the columns the worker made (or, for a chunk that came
    without them, its JSON rows)."""

    def __init__(self, store: RowStore, frame: RowFrame):
        self.store, self.frame = store, frame

    def put_batch(self, keys: list[str], batch: dict) -> None:
        self.store.put_batch(keys, batch)
        part = batch.get("part")
        if part is not None:
            self.frame.add(part)
        else:
            self.frame.add_rows([row_from_json(text) for text in batch["row"]])
        raise_if_signalled()  # an interrupt swallowed while the chunk landed (numpy's dtype comparison drops it)


#: the most tasks :func:`run` keeps from its first pass over them (to count and key them) for the passes that run them
#: and read the stored rows, instead of making them again (0.07 s for 40,000 tasks; 40,000 tasks hold about 35 MB)
KEEP_TASKS = 65_536


def run(tasks, store: RowStore, *, force: bool, jobs: int, executor: str, scheduler: str | None,
        desc: str, log=print, row_timeout: float | None = None, chunk_rows: int | None = None,
        outputs: str | None = None, while_rows_run=None):
    """Run what is not stored yet (and rows whose status is in :data:`RERUN_STATUSES`); return the rows
    as one DataFrame in task order, and the counts.

    ``tasks`` is a list of prepared tasks or a function returning a fresh iterable of them (it is called once to
    count, once to run and, when some rows were stored before, once to read those): the tasks of a large study
    are never all in memory (those of a study of at most :data:`KEEP_TASKS` are kept from the first pass). Rows go to the store as their chunk finishes; the frame is made from the columns the
    workers return, and from the store for the rows it already held. With ``outputs`` (:func:`outputs_code`) the
    counts hold the study's :func:`fingerprint`, and the store records that it holds every row of it when none is
    to be run again. ``while_rows_run`` is called (without arguments) just before rows are run, if any are."""
    make = tasks if callable(tasks) else (lambda: tasks)
    counts = {"tasks": 0, "stored": 0, "to_run": 0, "retried_errors": 0}
    used = set()
    keys = hashlib.sha256((outputs or "").encode())
    to_run = bytearray()  # one flag per task, in task order
    look_up = not force and not store.empty()
    kept: list | None = []  # the tasks of a small study, kept from this pass for the next (None: too many to keep)
    for block in _blocks(make(), 2000):
        if kept is not None:
            kept.extend(block)
            if len(kept) > KEEP_TASKS:
                kept = None
        block_keys = [t["key"] for t in block]
        status = store.done(block_keys) if look_up else {}
        counts["tasks"] += len(block)
        keys.update("".join(k + "\n" for k in block_keys).encode())
        seen = {}  # (method, data set spec) pairs of the block: their source is looked up once
        for t in block:
            seen[(t["method"], id(t["dataset"]))] = t
        used.update((t["method"], _source_name(t["dataset"])) for t in seen.values())
        if not status:  # nothing stored: every task runs
            to_run.extend(b"\x01" * len(block))
            counts["to_run"] += len(block)
            continue
        for k in block_keys:
            s = status.get(k)
            again = s is None or s in RERUN_STATUSES
            to_run.append(again)
            counts["to_run"] += again
            counts["retried_errors"] += again and s is not None
    counts["stored"] = counts["tasks"] - counts["to_run"]
    if kept is not None:
        make = lambda: kept  # noqa: E731 (the same tasks, not made again)
    isolate = runs_plugin_code(used)
    script = script_code(used) if counts["to_run"] else []
    if script and (jobs > 1 or executor == "dask" or row_timeout or isolate):
        why = (f"--jobs {jobs}" if jobs > 1 else "--executor dask" if executor == "dask" else
               "a row time limit" if row_timeout else "an installed plugin's method or data source in the study")
        raise InvalidInputError(f"{', '.join(script)} {'is' if len(script) == 1 else 'are'} registered by the program "
                                f"that runs (its __main__ module), which worker processes do not import, and {why} "
                                f"runs rows in worker processes: run with --jobs 1 and no row time limit (such rows "
                                f"then run in this process), or register it in a module or a plugin (docs/plugins.md)")
    log(f"   {counts['tasks']} rows: {counts['stored']} already stored, {counts['to_run']} to run"
        + (f" ({counts['retried_errors']} failed before, retried)"
           if counts["retried_errors"] else ""))
    frame = RowFrame(counts["tasks"])
    t0 = time.perf_counter()
    run_rows = execute
    if executor == "dask":  # the Dask executor sits above the local ones (it reuses their chunks and worker loop)
        from experiments.dask_executor import execute as run_rows
    todo = (t for n, t in enumerate(make()) if to_run[n])
    if while_rows_run is not None and counts["to_run"]:
        while_rows_run()
    run_rows(todo, Landing(store, frame), work=run_chunk, jobs=jobs, executor=executor, scheduler=scheduler,
             desc=desc, total=counts["to_run"], row_timeout=row_timeout, chunk_rows=chunk_rows, log=log,
             isolate=isolate)
    counts["wall_s"] = time.perf_counter() - t0
    if counts["stored"]:
        decode = _Interner()
        stored = (t for n, t in enumerate(make()) if not to_run[n])
        for block in _blocks(stored, 5000):
            found = store.get_by_key([t["key"] for t in block], decode=decode)
            if len(found) != len(block):
                raise MissingRows(len(block) - len(found))
            rows = [found[t["key"]] for t in block]
            for r, t in zip(rows, block):  # a stored row's place is its task's place in this run
                r["task_index"] = t["index"]
            frame.add_rows(rows)
            del rows, found
    df = frame.frame()
    counts["used"] = used
    if outputs is not None:
        counts["fingerprint"] = keys.hexdigest()[:32]
        if len(df) and not df["status"].isin(RERUN_STATUSES).any():
            store.mark_complete(counts["fingerprint"], len(df))
    return df, counts
