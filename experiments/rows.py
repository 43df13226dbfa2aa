"""A row (in a worker, or in the run's own process): a task's data from its seed stream, the generic fit row (the
fit, the result gate, the metrics, the timing), the generic rows of a batch, a row's time limit and the statuses of
rows that gave no result, and rows encoded as the row store's columns. A chunk of rows and the isolation of a plugin's
code: :mod:`experiments.chunkrows`.

This module sits below both the engine (``experiments.engine``: configs, tasks, keys, the run) and the executors
(``experiments.executors``: where chunks run). Its code is part of every row's cache key
(``experiments.codekeys.task_code``).
"""
from __future__ import annotations

import contextlib
import gc
import json
import math
import os
import signal
import threading
import time

import numpy as np
import orjson

import methods
from datasets import sources
from experiments.metrics import metrics
from experiments.rowframe import part_of
from experiments.seeding import generators
from experiments.studies import study_of
from experiments.timing import time_call
from methods import InvalidInputError, check_result, exception_call, exception_text, result_base


def source_of(spec: dict) -> str:
    """The registered data source of an expanded data set spec."""
    if "published" in spec:
        return "published"
    if "file" in spec:
        return "file"
    return spec.get("source") or spec["generator"]


class DataSourceError(Exception):
    """A data source gave data that break its contract (points that are not an (N, 2) array of finite real numbers):
    the source is at fault, not the methods, so its rows are 'error' naming the data set and the source (a method's
    'skipped' means the method refused good data)."""


def load_data(spec: dict, seed: int, stream: list[int], rng: np.random.Generator | None = None):
    """Data and truth of a data set spec, from its registered source (random sources draw from the
    spec's own seed stream: ``rng`` when the caller made its generator, :func:`experiments.seeding.generators`);
    points are checked once here (:func:`points_problem`), :class:`DataSourceError` if bad."""
    name = source_of(spec)
    source = sources.get_source(name)
    if "published" in spec:
        data, truth = source.load(None, name=spec["published"], variant=spec.get("variant"))
    elif "file" in spec:
        data, truth = source.load(None, path=spec["file"], truth=spec.get("truth"), **spec.get("read", {}))
    else:
        if rng is None:
            rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=tuple(stream)))
        data, truth = source.load(rng, **spec["params"])
    if source.gives is np.ndarray or (source.gives is None and isinstance(data, np.ndarray)):
        problem = points_problem(data)
        if problem:
            raise DataSourceError(f"data set {spec.get('label', name)!r} (source {name!r}) {problem}; the data "
                                  f"source is at fault, not the methods")
        if type(data) is not np.ndarray or (data.dtype is not _FLOAT64 and data.dtype != _FLOAT64):
            data = _float64_points(data)
    return data, truth


_FLOAT64 = np.dtype(np.float64)


def _float64_points(data: np.ndarray) -> np.ndarray:
    """Points of a data source as the read-only float64 (N, 2) array the methods and the gate both see (a float32,
    integer or ndarray-subclass array converted once here: a method fitting the float64 values and a gate checking
    them against the source's float32 ones would call an honest fit a lie). A masked array reaches here without a
    masked value (:func:`points_problem`)."""
    return methods.immutable(np.ascontiguousarray(np.ma.getdata(data), dtype=np.float64))


_isfinite = np.isfinite


def points_problem(data) -> str | None:
    """What is wrong with the points a data source gave (the contract of ``gives=numpy.ndarray``, and of an undeclared
    source giving an array: an (N, 2) array of finite real numbers, N >= 1, none of them masked; any real dtype, made
    float64 by :func:`load_data`), or None. One pass over the points."""
    if not isinstance(data, np.ndarray):
        return f"gave a {type(data).__name__}, not an (N, 2) numpy array of points"
    if data.dtype.kind not in "fiu":
        return f"gave points of dtype {data.dtype}, not real numbers"
    if data.ndim != 2 or data.shape[1] != 2:
        return f"gave points of shape {data.shape}, not an (N, 2) array of x, y"
    if not len(data):
        return "gave no points"
    if isinstance(data, np.ma.MaskedArray) and np.ma.getmaskarray(data).any():
        masked = int(np.ma.getmaskarray(data).any(axis=1).sum())
        return (f"gave a masked array with {masked} of {len(data)} points masked: give the measured points only, as "
                f"a plain array (numpy.ma.compress_rows(points)); a method would fit the values under the mask")
    if data.dtype.kind == "f":
        if not _isfinite(data).all():  # one sweep (no overflow to silence: half the cost of a sum under errstate)
            bad = np.flatnonzero(~np.isfinite(data).all(axis=1))
            if bad.size:
                return f"gave {bad.size} of {len(data)} points with NaN or inf (first at index {bad[0]})"
    return None


_COLUMNS_OF: dict = {}


def _columns_of(spec_params: dict, params: dict) -> dict:
    """The parameter columns of a (data set, method) pair. Tasks of one pair share these dicts (also after
    pickling to a worker), so the columns are built once per pair; the cache holds the dicts themselves,
    so an id is never reused while cached."""
    memo = (id(spec_params), id(params))
    hit = _COLUMNS_OF.get(memo)
    if hit is not None and hit[0] is spec_params and hit[1] is params:
        return hit[2]
    cols = {"params": json.dumps(params, sort_keys=True)}
    for k, v in spec_params.items():
        cols[f"data_{k}"] = v if np.isscalar(v) else json.dumps(v)
    for k, v in params.items():
        cols[f"param_{k}"] = v if np.isscalar(v) or v is None else json.dumps(v)
    if len(_COLUMNS_OF) > 4096:
        _COLUMNS_OF.clear()
    _COLUMNS_OF[memo] = (spec_params, params, cols)
    return cols


_NO_PARAMS: dict = {}


def base_row(task: dict) -> dict:
    spec = task["dataset"]
    cols = _columns_of(spec.get("params", _NO_PARAMS), task["params"])
    row = {"study": task["study"], "dataset": spec["label"], "repetition": task["repetition"], "seed": task["seed"],
           "data_stream": ".".join(map(str, task["stream"])), "method": task["method"], "params": cols["params"]}
    row.update(cols)  # "params" first, then the data_ and param_ columns, as they always came
    return row


#: columns a generic row may have besides those of base_row: the engine's own and every column a result class


def fit_row(task: dict, points, truth) -> dict:
    """Fit, measure, time: the generic row of a task (a method's exceptions become status 'error'; one of the gate,
    the metrics or the timing reaches the caller)."""
    res, failed = _fitted(task, points)
    return failed if res is None else _measured_row(task, res, points, truth)


def _fitted(task: dict, points, pid: int | None = None):
    """(the result of the task's method on ``points``, None), or (None, its row) when the method raised: 'skipped'
    for an input it refuses, 'error' for any other exception (a method's bug: recorded, retried on the next run).
    ``pid``: this process's id, when the caller knows it (a batch asks once: each ``os.getpid`` is a system call)."""
    if pid is None:
        pid = _getpid()
    spec = methods.get(task["method"])
    own = None if spec.builtin else _own_copy(points)
    try:
        res = spec.unchecked(points if own is None else own, **task["params"])  # gated by _measured_row
    except InvalidInputError as exc:
        try:
            res, failed = None, {**base_row(task), "status": "skipped", "message": str(exc)}
        except Exception:   # a refusal whose str() raises: the method's own bug, named by its type
            res, failed = None, {**base_row(task), "status": "error", "message": exception_text(exc)}
    except Exception as exc:
        res, failed = None, {**base_row(task), "status": "error", "message": exception_text(exc)}
    else:
        failed = None
    finally:
        end_if_forked(pid)
    if own is not None and not _unchanged(own, points):
        return None, {**base_row(task), "status": "invalid", "message": _WROTE_INTO_INPUT}
    return res, failed


_getpid = os.getpid


def _unforked(func, points, params: dict):
    """``func(points, **params)``, a child it forks and returns in ended where it returns (:func:`end_if_forked`)."""
    pid = _getpid()
    try:
        return func(points, **params)
    finally:
        end_if_forked(pid)


def end_if_forked(pid: int) -> None:
    """End this process at once if it is not process ``pid``: a method (or a study's code) that forked and returned
    in the child. Only the process a chunk was given to makes its rows; the child would run on as a second worker on
    its parent's pipe, and its rows would be stored in place of others (a duplicated row, a missing one)."""
    if _getpid() != pid:
        os._exit(0)


#: the message of the row of a method that changed the points it was given
_WROTE_INTO_INPUT = ("invalid result: the method wrote into the points it was given (read-only: changed through C or "
                     "ctypes, past NumPy's flags); the methods after it got the data unchanged")


def _unchanged(copy: np.ndarray, points: np.ndarray) -> bool:
    """Whether a method's copy of the points still equals them (NaN where NaN was: data a source gives otherwise than
    as checked points may hold it)."""
    try:
        return np.array_equal(copy, points, equal_nan=True)
    except TypeError:  # a dtype without NaN
        return np.array_equal(copy, points)


def _own_copy(points):
    """A private read-only copy of a point array for a plugin's method (None for other data): a method writing into
    its input through C cannot change the data of the methods after it, and the write is seen by comparing the copy
    with the data afterwards (the built-in methods are fitbench's, tested not to write)."""
    if type(points) is not np.ndarray:
        return None
    return methods.immutable(np.array(points))


def _measured_row(task: dict, res, points, truth, sent: dict | None = None) -> dict:
    """The row of a method's result: 'invalid' if it breaks its family's contract (the gate), else its status,
    metrics and (if the task asks) timing."""
    row = base_row(task)
    problem = check_result(res, points)  # the gate: a result that breaks its family's contract is no row
    given = res
    plugin = not result_base.trusted(res, task["method"])
    if not problem and plugin:
        # a plugin's method or class: the row is computed by fitbench's own class from a copy of the values in plain
        # types, which the gate checks again; the plugin's class adds its own columns only
        checked = result_base.family_copy(res)
        if checked is not res:
            problem = check_result(checked, points)
            res = checked
    if problem:
        return {**row, "status": "invalid", "message": f"invalid result: {problem}"}
    converged = res.converged
    row["status"] = "ok" if converged else "not converged"
    row["message"] = res.message
    row["converged"] = converged
    row["iterations"] = res.iterations
    row["nfev"] = res.nfev
    other = _other_family(truth, task["method"])
    if other:  # a circle's centre error against a square's centre means nothing: no truth errors, and the row says so
        row["message"] = f"{res.message}; no errors against the truth: the data are of family {other[0]!r}, " \
                         f"{task['method']} of {other[1]!r}"
        truth = None
    own = None
    if given is not res:  # the columns the plugin's class adds (one the engine writes is refused below)
        own = result_base.own_columns(given, res, truth)
    if sent:  # what a plugin's class adds, computed in its process (_plugin_rows): numbers only
        family = {c.name for c in type(res).COLUMNS}
        own = {**(own or {}), **{k: v for k, v in sent.items() if type(k) is str
                                 and k not in family and type(v) in (float, int)}}
    try:
        measured = metrics(res, truth, own)
    except Exception as exc:  # fitbench's class on checked values: the truth is what it cannot take (a wrong type, a
        # wrong shape: TypeError, ValueError, IndexError, KeyError)
        if not truth:
            raise
        metrics(res, None, own)  # without the truth it can: the data source is at fault
        raise DataSourceError(f"data set {_label(task)} gave a truth that cannot be compared with a fit "
                              f"({exception_text(exc)}); the data source is at fault, not the methods") from None
    if plugin and any(map(result_base.engine_column, measured)):  # the engine's columns are the engine's alone
        taken = [k for k in measured if result_base.engine_column(k)]
        return {**base_row(task), "status": "invalid", "message": f"invalid result: its class gives the column(s) "
                f"{', '.join(map(repr, taken))}, which the engine writes in the row; rename them"}
    row.update(measured)
    if task.get("timing"):
        t = task["timing"]
        spec = methods.get(task["method"])
        given = points if spec.builtin else (_own_copy(points) if type(points) is np.ndarray else points)
        row.update(time_call(lambda: spec.unchecked(given, **task["params"]),
                             min_time_s=t.get("min_time_s", 0.02), rounds=t.get("rounds", 5)))
    return row


def _label(task: dict) -> str:
    """The data set of a task as its errors name it: ``'label' (source 'name')``."""
    spec = task["dataset"]
    try:
        return f"{spec.get('label')!r} (source {source_of(spec)!r})"
    except (KeyError, TypeError, AttributeError):
        return repr(spec.get("label"))


def _other_family(truth, method: str) -> tuple[str, str] | None:
    """(the family the data's truth names, the method's) when they differ (``truth["family"]``: a data source's truth
    says what shape the data are), else None."""
    family = truth.get("family") if isinstance(truth, dict) else None
    if family is None:
        return None
    own = methods.get(method).family
    return None if family == own else (str(family), own)


#: statuses the environment causes (not the method): never served from the cache, recomputed on the next run
ENVIRONMENT_STATUSES = ("timeout", "crashed", "unavailable")
#: statuses recomputed on the next run (a method's error may be a bug fixed since)
RERUN_STATUSES = ("error",) + ENVIRONMENT_STATUSES
#: the prefix of the message of a compiled kernel that was not built (methods._compiled)
_NOT_BUILT = "fitbench's compiled kernel"


class RowTimeout(BaseException):
    """Raised inside a row that ran longer than its time limit (a BaseException: a method's ``except
    Exception`` does not swallow it)."""


#: set when the run itself received SIGINT/SIGTERM: a KeyboardInterrupt is then the user's, not a method's
_SIGNALLED = threading.Event()


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so that the run stops the way Ctrl-C stops it; ``signum``: the signal."""

    signum = signal.SIGTERM


class HungUp(Terminated):
    """SIGHUP (the terminal of the run closed, a session ended), taken as SIGTERM."""

    signum = getattr(signal, "SIGHUP", 1)


#: the signals that stop a run as Ctrl-C does, and the exception each raises in its main thread
STOPPING_SIGNALS = {signal.SIGINT: KeyboardInterrupt, signal.SIGTERM: Terminated,
                    **({signal.SIGHUP: HungUp} if hasattr(signal, "SIGHUP") else {})}


_RECEIVED: list = []  # the exception of the first interrupt the run received (KeyboardInterrupt or Terminated)


def note_signal(exc_type: type = KeyboardInterrupt) -> None:
    """Record that the run received an interrupt (a signal handler calls this before raising)."""
    _SIGNALLED.set()
    if not _RECEIVED:
        _RECEIVED.append(exc_type)


def raise_if_signalled() -> None:
    """Raise the run's own interrupt again at a safe point of the main thread. A signal handler raises it wherever the
    main thread is, and code there can swallow it: numpy's dtype comparison drops an exception raised while it
    converts the other operand, and an exception in a weakref callback is only printed (a Ctrl-C or SIGTERM was lost
    about once in 20 and the run ended with exit 0)."""
    if _RECEIVED and threading.current_thread() is threading.main_thread():
        raise _RECEIVED[0]()


def signalled() -> bool:
    """Whether the run received SIGINT or SIGTERM."""
    return _SIGNALLED.is_set()


def clear_signal() -> None:
    """A new run in this process (``experiments.run.main`` again): no interrupt received yet."""
    _SIGNALLED.clear()
    _RECEIVED.clear()


class _time_limit:
    """A row's time limit: SIGALRM in a process's main thread (it also interrupts a sleep), else a timer
    that raises :class:`RowTimeout` asynchronously in the row's thread (Dask workers run rows in threads)."""

    def __init__(self, seconds):
        self.seconds = seconds

    def __enter__(self):
        if not self.seconds:
            return self
        self.main = threading.current_thread() is threading.main_thread() and hasattr(signal, "setitimer")
        if self.main:
            def fire(signum, frame):
                raise RowTimeout()
            self.old = signal.signal(signal.SIGALRM, fire)
            signal.setitimer(signal.ITIMER_REAL, self.seconds)
        else:
            import ctypes
            tid, self.lock, self.active = threading.get_ident(), threading.Lock(), True

            def fire():
                with self.lock:
                    if self.active:
                        ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(tid), ctypes.py_object(RowTimeout))
            self.timer = threading.Timer(self.seconds, fire)
            self.timer.daemon = True
            self.timer.start()
        return self

    def __exit__(self, *exc):
        if not self.seconds:
            return False
        if self.main:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, self.old)
        else:
            with self.lock:
                self.active = False
            self.timer.cancel()
        return False


def failed_row(task: dict, status: str, message: str) -> dict:
    """The row of a task that produced no result (time-out, crash, ...), with its identity columns."""
    return {**base_row(task), "status": status, "message": bounded_message(message), "task_index": task.get("index")}


#: the data of the last generic row: (its data set spec, seed, stream, (points, truth))
_LAST_DATA: list = [None, None, None, None]


def task_data(task: dict, rng: np.random.Generator | None = None):
    """:func:`load_data` of a task for the generic fit, shared with the row before it when that row had the same data set,
    seed and stream (the methods of one repetition follow each other in a chunk: their data are made once). Methods
    see the points read-only (``methods.fit``) and the fit row only reads the truth, so a row cannot change the data
    of the next."""
    spec, seed, stream = task["dataset"], task["seed"], task["stream"]
    last = _LAST_DATA
    if last[0] is spec and last[1] == seed and last[2] == stream:
        return last[3]
    last[0] = None
    data = load_data(spec, seed, stream, rng)
    last[:] = [spec, seed, list(stream), data]
    return data


def run_task(task: dict, row_timeout: float | None = None) -> dict:
    """Worker entry point: the row of the task's study (``Study.execute``: the generic fit by default). A row that
    runs longer than ``row_timeout`` seconds is ``timeout``; one that raises SystemExit or
    KeyboardInterrupt (not the run's own interrupt) is ``crashed``; a kernel or module that cannot be
    loaded makes it ``unavailable``."""
    pid = _getpid()
    try:
        with (_time_limit(row_timeout) if row_timeout else _NO_LIMIT):
            try:
                row = study_of(task["kind"]).execute(task)  # the generic fit unless the study kind has its own rows
            finally:
                end_if_forked(pid)
    except RowTimeout:
        row = failed_row(task, "timeout", f"the row ran longer than its limit of {row_timeout:g} s")
    except BaseException as exc:
        row = _failure(task, exc)
    return _finished(row, task)


def _failure(task: dict, exc: BaseException) -> dict:
    """The row of a task whose study code raised ``exc``: 'crashed' for SystemExit or a KeyboardInterrupt that is
    not the run's own (which is raised again: the run stops), 'unavailable' for an ImportError (a kernel or module
    that cannot be loaded), 'error' for any other exception, GeneratorExit included (docs/results.md: a raised
    exception, not a process ended)."""
    if isinstance(exc, (KeyboardInterrupt, SystemExit)):
        if isinstance(exc, KeyboardInterrupt) and _SIGNALLED.is_set():
            raise exc  # the run was interrupted: stop
        return failed_row(task, "crashed", f"the row raised {exception_call(exc)}")
    if not isinstance(exc, (Exception, GeneratorExit)):
        raise exc
    status = "unavailable" if isinstance(exc, ImportError) else "error"
    return {**base_row(task), "status": status, "message": exception_text(exc)}


#: the most characters of a row's message that are kept (:func:`bounded_message`): a method's message of a solver's
#: whole log (10^5 lines) made results.csv unreadable by Python's csv module (fields above 131,072 characters)
MESSAGE_CHARS = 2000


def bounded_message(message):
    """``message`` made writable (:func:`writable_text`) and cut to its first :data:`MESSAGE_CHARS` characters with a
    marker saying how long it was."""
    if type(message) is str:
        if not message.isascii():
            message = writable_text(message)
        if len(message) > MESSAGE_CHARS:
            return f"{message[:MESSAGE_CHARS]} ... [message cut: {len(message):,} characters in all]"
    return message


def writable_text(text: str) -> str:
    """``text`` as UTF-8 can write it: what it cannot encode (a lone surrogate, from bytes decoded with
    ``errors="surrogateescape"`` or a C extension's message) as Python's backslash escape (``\\ud800``), the rest
    unchanged (every writer of a row, its CSV, JSON, report and row store, then takes it)."""
    try:
        text.encode("utf-8")
        return text
    except UnicodeEncodeError:
        return text.encode("utf-8", "backslashreplace").decode("utf-8")


def _finished(row: dict, task: dict) -> dict:
    """A task's row as it is stored: a compiled kernel that was not built is 'unavailable', the message bounded
    (:func:`bounded_message`), the task's index, JSON's values (:func:`_plain`)."""
    if row.get("status") == "skipped" and str(row.get("message", "")).startswith(_NOT_BUILT):
        row["status"] = "unavailable"
    message = row.get("message")
    if type(message) is str and len(message) > MESSAGE_CHARS:
        row["message"] = bounded_message(message)   # (a shorter one is made writable by _plain, as every text)
    row["task_index"] = task.get("index")
    return _plain(row)


_NO_LIMIT = contextlib.nullcontext()  # a row without a time limit

#: the cyclic garbage collector's first threshold (allocations between two collections of the youngest objects;
#: CPython's default is 700) while a run makes rows. A row allocates hundreds of dicts, lists and arrays and almost no
#: reference cycle: at 700 the collector ran 549 times in a 40,000-row study and took 0.28 s of its 5 s of CPU, at 20,000
#: 9 times and 0.063 s, at 100,000 twice and 0.036 s. A cycle still goes at the next collection, after at most this many
#: allocations (a few MB of garbage at most).
ROW_GC_THRESHOLD = 100_000


@contextlib.contextmanager
def fewer_collections():
    """The garbage collector's first threshold at :data:`ROW_GC_THRESHOLD` inside the block (the process's own
    thresholds again after it)."""
    old = gc.get_threshold()
    gc.set_threshold(max(old[0], ROW_GC_THRESHOLD), *old[1:])
    try:
        yield
    finally:
        gc.set_threshold(*old)


#: the most tasks, and the most bytes of their data, of one batch of :func:`_generic_rows`
BATCH_TASKS, BATCH_BYTES = 256, 16 << 20


def _generic_rows(tasks: list[dict], first: int, progress) -> list[dict]:
    """The generic fit rows of tasks of a study without its own ``execute``, in batches of at most
    :data:`BATCH_TASKS` tasks and :data:`BATCH_BYTES` of data: each batch's data, then its fits (a method's one after
    the other), then its gates, metrics and rows, each step one loop over the batch. The same rows as :func:`run_task`
    without a time limit task by task (a method is a function of its data and parameters): each step runs the same
    code; a loop of one code over many tasks keeps it in the processor's caches (interleaved, the fits of a
    40,000-row study and the rest of its rows cost 5-10 us a row more)."""
    rows, start = [], 0
    while start < len(tasks):
        batch, data, size, last = [], [], 0, None
        rngs = _generators(tasks[start:start + BATCH_TASKS])
        for task in tasks[start:start + BATCH_TASKS]:  # 1. the data (a repetition's data once for its methods)
            if progress is not None:
                progress[0], progress[1] = time.monotonic(), first + start + len(batch)
            try:
                got = task_data(task, rngs.get(id(task)))
            except BaseException as exc:
                got = _failure(task, exc)
            if got is not last and type(got) is tuple:
                size += getattr(got[0], "nbytes", 0)  # the points (the truth is a few numbers)
                last = got
            batch.append(task)
            data.append(got)
            if size >= BATCH_BYTES:
                break
        fits = [None] * len(batch)
        pid = _getpid()  # a method that forks and returns in the child: the child ends where it returns
        order = range(len(batch))
        if len({task["method"] for task in batch}) > 1:
            order = sorted(order, key=lambda i: batch[i]["method"])
        for i in order:  # 2. the fits, a method's together
            task, got = batch[i], data[i]
            if type(got) is not tuple:
                fits[i] = (None, got)
                continue
            if progress is not None:
                progress[0], progress[1] = time.monotonic(), first + start + i
            try:
                fits[i] = _fitted(task, got[0], pid)
            except BaseException as exc:
                fits[i] = (None, _failure(task, exc))
        for i, task in enumerate(batch):  # 3. the gate, the metrics, the row
            res, row = fits[i]
            if res is not None:
                if progress is not None:
                    progress[0], progress[1] = time.monotonic(), first + start + i
                points, truth = data[i]
                try:
                    row = _measured_row(task, res, points, truth)
                except BaseException as exc:
                    row = _failure(task, exc)
            rows.append(_finished(row, task))
        start += len(batch)
    return rows


def _generators(tasks: list[dict]) -> dict:
    """The random generators of the tasks of a batch that draw new data (a data set of a source, not a published or
    read one; not the same data set, seed and stream as the task before them), by ``id(task)``, made together
    (:func:`experiments.seeding.generators`); a task without one makes its own (:func:`load_data`)."""
    wanted: dict = {}
    previous = None
    for task in tasks:
        spec, seed, stream = task["dataset"], task["seed"], task["stream"]
        now = (spec, seed, stream)
        if previous is not None and previous[0] is spec and previous[1] == seed and previous[2] == stream:
            continue
        previous = now
        if "published" in spec or "file" in spec or type(seed) is not int:
            continue
        wanted.setdefault(seed, []).append(task)
    out = {}
    for seed, some in wanted.items():
        for task, rng in zip(some, generators(seed, [t["stream"] for t in some])):
            if rng is not None:
                out[id(task)] = rng
    return out


def encode_rows(rows: list[dict]) -> dict:
    """A chunk's rows in the columns of the row store (``status``, ``row`` as JSON text) and as a part of the run's
    frame (``part``: :func:`experiments.rowframe.part_of`), made by the worker: the process that stores them only
    inserts and keeps the columns (it serves every worker)."""
    return {"status": [r.get("status") for r in rows], "row": [row_json(r) for r in rows], "part": part_of(rows)}


def row_json(row: dict) -> str:
    """A row as JSON text (orjson; what orjson does not write, such as an integer beyond 64 bits or a key that is
    not a string, is written by :mod:`json`: the same JSON value)."""
    try:
        return orjson.dumps(row).decode()
    except orjson.JSONEncodeError:
        return json.dumps(row)


def row_from_json(text: str) -> dict:
    """A stored row (JSON text; a NaN literal an older run wrote is read by :mod:`json`)."""
    try:
        return orjson.loads(text)
    except orjson.JSONDecodeError:   # (orjson refuses a lone surrogate, which an older run may have stored: made writable)
        return {k: writable_text(v) if type(v) is str and not v.isascii() else v for k, v in json.loads(text).items()}


def _plain(row: dict) -> dict:
    """The row with JSON's values, converted in place (run_task's row is its own): NumPy scalars as Python ones,
    non-finite floats as None; the keys and their order stay."""
    isfinite = math.isfinite
    for k, v in row.items():
        t = type(v)
        if t is str:
            if not v.isascii():
                row[k] = writable_text(v)
            continue
        if t is int or t is bool or v is None:
            continue
        if t is float:
            if v - v != 0.0:  # inf - inf and NaN - NaN are NaN: not finite
                row[k] = None
            continue
        if isinstance(v, np.generic):
            v = v.item()
        if isinstance(v, float) and not isfinite(v):
            v = None
        row[k] = v
    return row
