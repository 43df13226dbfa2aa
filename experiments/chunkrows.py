"""The rows of a chunk of tasks, as a worker of the engine makes them (:func:`run_chunk`: the executors' entry point),
and the isolation of a plugin's code: in a worker (:func:`mark_row_worker`), the rows of a plugin's method or data
source are fitted in a child process forked for them (one per method and data source in a chunk) and gated and
measured by the worker's own code (:func:`_plugin_rows`), so that what a plugin does to its process (patching the
gate, another method, NumPy) dies with the child (docs/plugins.md).

The row itself (its data, fit, gate, metrics, time limit and statuses) is :mod:`experiments.rows`; this module's code
is part of every row's cache key too (``experiments.codekeys.task_code``).
"""
from __future__ import annotations

import contextlib
import os
import signal
import threading
import time

import numpy as np

import methods
from datasets import sources
from experiments.rows import (_NO_LIMIT, DataSourceError, RowTimeout, _failure, _finished, _fitted, _generic_rows,
                              _measured_row, _other_family, _own_copy, _time_limit, _unforked, base_row, encode_rows,
                              failed_row, points_problem, run_task, source_of, task_data)
from experiments.studies import study_of
from experiments.timing import time_call
from methods import check_result, exception_text, result_base


def _loaded_before_rows() -> None:
    """Import what the rows import on first use (the built-in methods, the installed plugins' methods and data
    sources; each loader runs once a process), so that a row's time limit measures the row, not the imports of a
    worker that has just started: under load they took more than a 1 s limit and a row that crashed was labelled
    'timeout'. The run itself imported them all before its first row (a plugin that hangs on import stops it there)."""
    methods.list_methods()   # loads the built-in methods, then the installed plugins' (once a process)
    sources.load_plugins()


def _plugin_tasks(tasks: list[dict]) -> list[bool] | None:
    """Which tasks run a plugin's code (a method or a data source not fitbench's own), or None when none does."""
    seen, flags, any_plugin = {}, [], False
    for task in tasks:
        memo = (task.get("method"), id(task.get("dataset")))
        flag = seen.get(memo)
        if flag is None:
            try:
                flag = not (methods.get(task["method"]).builtin and _builtin_source(task["dataset"]))
            except Exception:  # no registered method or source (a study's own task): its own code runs it, as before
                flag = False
            seen[memo] = flag
        flags.append(flag)
        any_plugin = any_plugin or flag
    return flags if any_plugin else None


def _plugin_part(task: dict) -> tuple:
    """The rows that share a child process (:func:`_plugin_rows`) in a chunk: those of one method on one data source.
    A plugin's method that patches another plugin's method, or a data source, patches them in its own child only."""
    return task.get("method"), source_of(task["dataset"]) if isinstance(task.get("dataset"), dict) else None


def _builtin_source(spec: dict) -> bool:
    return sources.get_source(source_of(spec)).builtin


#: set in a process that runs the engine's worker loop (``experiments.localworkers._worker_main``: a local worker,
#: or a row process of a Dask worker), by :func:`mark_row_worker`
_ROW_WORKER = [False]


def mark_row_worker() -> None:
    """Say that this process is a worker of the engine: the rows of a plugin's code it is given run in a child
    process of their own (:func:`_forks_plugin_rows`)."""
    _ROW_WORKER[0] = True


def _forks_plugin_rows() -> bool:
    """Whether this process runs the rows of a plugin's code in a child process of their own: a worker of the
    engine (:func:`mark_row_worker`), in its main thread, where ``os.fork`` exists."""
    return _ROW_WORKER[0] and hasattr(os, "fork") and threading.current_thread() is threading.main_thread()


class _Positions:
    """The progress array of a chunk seen by a part of it: a row's position in the part is written as its position
    in the chunk (the parent blames a crash or a time-out on the row at that position)."""

    def __init__(self, progress, where: list[int]):
        self.progress, self.where = progress, where

    def __setitem__(self, i, value):
        if i == 1 and 0 <= int(value) < len(self.where):
            value = self.where[int(value)]
        self.progress[i] = value

    def __getitem__(self, i):
        return self.progress[i]


def run_chunk(tasks: list[dict], row_timeout: float | None = None, progress=None) -> dict:
    """Run a chunk of tasks in a worker; the rows come back encoded for the store and as the columns of the run's frame
    (:func:`encode_rows`). ``progress``
    (a shared array of two doubles) receives the start time and position of the running row, so that
    the parent can end a row stuck in compiled code. Without a time limit the generic fit rows run in batches
    (:func:`_generic_rows`)."""
    if row_timeout:
        _loaded_before_rows()
    t0 = time.perf_counter()
    plugin = _plugin_tasks(tasks) if _forks_plugin_rows() else None
    if plugin is None:
        rows = _chunk_rows(tasks, row_timeout, progress)
    else:  # the rows of a plugin's code run in child processes: what they do to their process dies with it
        rows = [None] * len(tasks)
        parts: dict = {}  # None: fitbench's own rows, here; (method, data source): the rows of one plugin's code
        for i, (task, flag) in enumerate(zip(tasks, plugin)):
            parts.setdefault(_plugin_part(task) if flag else None, []).append(i)
        for part, where in sorted(parts.items(), key=lambda kv: kv[0] is not None):
            some = [tasks[i] for i in where]
            at = progress if progress is None else _Positions(progress, where)
            got = _chunk_rows(some, row_timeout, at) if part is None else _plugin_rows(some, row_timeout, at)
            for i, row in zip(where, got):
                rows[i] = row
    return {"columns": encode_rows(rows), "seconds": time.perf_counter() - t0}


def _chunk_rows(tasks: list[dict], row_timeout: float | None, progress) -> list[dict]:
    """The rows of a chunk's tasks, in this process."""
    rows = []
    start = 0
    while start < len(tasks):
        kind = tasks[start]["kind"]
        end = start + 1
        while end < len(tasks) and tasks[end]["kind"] == kind:
            end += 1
        if not row_timeout and study_of(kind).generic_rows:
            rows.extend(_generic_rows(tasks[start:end], start, progress))
        else:
            for pos in range(start, end):
                if progress is not None:
                    progress[0], progress[1] = time.monotonic(), pos
                rows.append(run_task(tasks[pos], row_timeout))
        start = end
    return rows


# ------------------------------------------------- rows of a plugin's code: in a child process, gated in this one


def _plugin_rows(tasks: list[dict], row_timeout: float | None, progress) -> list[dict]:
    """The rows of tasks running a plugin's code (its method, or its data source; one method on one data source,
    :func:`_plugin_part`), fitted in a child process forked for them: a plugin that patches the gate, the metrics,
    another method or NumPy does it in that child, which ends with these rows; the worker (this process, which ran no plugin code since it started, save the imports of
    the installed plugins) gates the results and computes their metrics with its own code. The child sends back, for
    a plugin's method, the result as fitbench's own class in plain types (:func:`methods.result_base.family_copy`),
    the columns its class adds and its timing (and the data when the source is a plugin's too), read with
    :class:`_ResultUnpickler`, which makes fitbench's result classes and NumPy arrays and nothing else; for a built-in
    method on a plugin's data source (the data are the plugin's) and a study kind's own rows, the row. The child
    sends each row's item as soon as it is made; a child that ends before it sent them all ends this worker likewise
    (exit status or signal) with the first row it did not send at the chunk's progress position: the run labels that
    row 'crashed' and runs the others again, as for a worker that ended."""
    import pickle
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns
        status = 70
        try:
            os.close(read)
            _child_setup(write)
            for i, task in enumerate(tasks):
                try:
                    item = _child_item(task, row_timeout, progress, i)
                except BaseException as exc:  # not an Exception (run_task raises it again): the row's error
                    item = ("row", failed_row(task, "error", exception_text(exc)))
                try:
                    data = pickle.dumps(item, protocol=pickle.HIGHEST_PROTOCOL)
                except Exception as exc:
                    data = pickle.dumps(("row", failed_row(task, "error", f"its result cannot be sent to the "
                                                           f"engine ({type(exc).__name__}: {exc})")))
                _send_item(write, data)  # as soon as it is made: a row that breaks the child is the first not sent
            status = 0
        finally:
            os._exit(status)
    os.close(write)
    items = []
    with os.fdopen(read, "rb") as pipe:
        while len(items) < len(tasks):
            item = _read_item(pipe)
            if item is None:
                break
            items.append(item)
    _, wait_status = os.waitpid(pid, 0)
    if len(items) < len(tasks):  # it crashed, was ended or ended itself (a method's os._exit(0)) before it sent them:
        # this worker ends as it did, at the first row the child did not send (the run labels that row 'crashed')
        if progress is not None:
            progress[0], progress[1] = time.monotonic(), len(items)
        if os.WIFSIGNALED(wait_status):
            _end_by_signal(os.WTERMSIG(wait_status))
        os._exit((os.WEXITSTATUS(wait_status) if os.WIFEXITED(wait_status) else 0) or 1)
    rows = []
    for i, (task, item) in enumerate(zip(tasks, items)):
        if progress is not None:
            progress[0], progress[1] = time.monotonic(), i
        try:
            try:
                item = _ResultUnpickler(item).load()
            except Exception as exc:  # what this process does not read is not made into a row
                item = ("row", failed_row(task, "error", f"the process of the plugin's row sent what the engine does "
                                                         f"not read ({type(exc).__name__}: {str(exc)[:200]})"))
            row = _gated_plugin_row(task, item)
        except BaseException as exc:
            row = _failure(task, exc)
        rows.append(_finished(row, task))
    return rows


#: the most bytes of one row's item from a child (:func:`_read_item`): more is not a row but a broken child
MAX_ITEM_BYTES = 1 << 31


def _send_item(fd: int, data: bytes) -> None:
    """In the child: one row's item to the worker, its length (8 bytes, little-endian) first."""
    view = memoryview(len(data).to_bytes(8, "little") + data)
    while view:
        view = view[os.write(fd, view):]


def _read_item(pipe) -> bytes | None:
    """In the worker: the next item a child sent (:func:`_send_item`), or None at the end of what it sent (it ended,
    or sent a length no row has)."""
    head = pipe.read(8)
    if len(head) < 8:
        return None
    size = int.from_bytes(head, "little")
    if size > MAX_ITEM_BYTES:
        return None
    data = pipe.read(size)
    return data if len(data) == size else None


def _end_by_signal(signum: int) -> None:
    """End this process by the signal that ended its child (a segmentation fault is told as one, not as a kill), by
    SIGKILL if that signal does not end it."""
    with contextlib.suppress(Exception):
        signal.signal(signum, signal.SIG_DFL)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, [signum])
        os.kill(os.getpid(), signum)
        time.sleep(0.5)
    os.kill(os.getpid(), signal.SIGKILL)


def _child_setup(write: int) -> None:
    """In the child: it dies with the worker (a row past its time limit gets the worker killed), and keeps no file
    of the worker's but the standard streams and its pipe (the worker's connection to the run is not its to use)."""
    if hasattr(os, "closerange"):
        os.closerange(3, write)
        os.closerange(write + 1, 1 << 16)
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)  # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def _child_item(task: dict, row_timeout, progress, pos: int):
    """In the child: what the worker needs to make the row of a task running a plugin's code (see
    :func:`_plugin_rows`)."""
    if progress is not None:
        progress[0], progress[1] = time.monotonic(), pos
    spec = methods.get(task["method"])
    if spec.builtin or not study_of(task["kind"]).generic_rows:  # the data are the plugin's, or the study's own rows
        return "row", run_task(task, row_timeout)
    try:
        with (_time_limit(row_timeout) if row_timeout else _NO_LIMIT):
            points, truth = task_data(task)
            res, failed = _fitted(task, points)
            if res is None:
                return "row", failed
            problem = check_result(res, points)  # the plugin's class: its types, shapes and geometry
            if problem:
                return "row", {**base_row(task), "status": "invalid", "message": f"invalid result: {problem}"}
            checked = result_base.family_copy(res)
            if checked is res:  # a family a plugin declares: its class is its contract, its row is its own
                return "row", _measured_row(task, res, points, truth)
            own = result_base.own_columns(res, checked, None if _other_family(truth, task["method"]) else truth)
            timing = None
            if task.get("timing"):
                t, given = task["timing"], _own_copy(points) if type(points) is np.ndarray else points
                timing = time_call(lambda: _unforked(spec.unchecked, given, task["params"]),
                                   min_time_s=t.get("min_time_s", 0.02), rounds=t.get("rounds", 5))
            data = None if _builtin_source(task["dataset"]) else (points, result_base._plain_value(truth))
    except RowTimeout:
        return "row", failed_row(task, "timeout", f"the row ran longer than its limit of {row_timeout:g} s")
    except BaseException as exc:
        return "row", _failure(task, exc)
    return "fit", checked, own, timing, data


def _gated_plugin_row(task: dict, item) -> dict:
    """In the worker: the row of a task from what its child sent (:func:`_child_item`): a row as it is; a result
    gated against the data (this process's own, unless the data source is the plugin's) and measured by this
    process's code, with the columns the plugin's class adds and the timing of its fit."""
    if type(item) is tuple and len(item) == 2 and item[0] == "row" and type(item[1]) is dict:
        row = {**item[1], **base_row(task)}  # its identity is the task's
        if row.get("status") in _RESULT_STATUSES and _gated_here(task):
            return failed_row(task, "error", "the process of the plugin's row sent a row where the engine gates the "
                                             "result itself")
        return row
    if not (type(item) is tuple and len(item) == 5 and item[0] == "fit"):
        return failed_row(task, "error", "the process of the plugin's row sent no row for it")
    _, checked, own, timing, data = item
    if not result_base.builtin_class(type(checked)):
        return failed_row(task, "error", "the process of the plugin's row sent no result of fitbench's classes")
    checked.method, checked.params = task["method"], task["params"]  # gated as the task's method: its family's class
    if _builtin_source(task["dataset"]):  # the data are made here, whatever the child sent
        points, truth = task_data(task)
    elif type(data) is tuple and len(data) == 2:  # a plugin's data source: its child made them; checked as here
        points, truth = data
        problem = points_problem(points)
        if problem:
            raise DataSourceError(f"data set {task['dataset'].get('label')!r} (source {source_of(task['dataset'])!r}) "
                                  f"{problem}; the data source is at fault, not the methods")
    else:
        return failed_row(task, "error", "the process of the plugin's row sent no data for its data source")
    row = _measured_row({**task, "timing": None}, checked, points, truth,
                        own if type(own) is dict else None)
    if timing and type(timing) is dict and row.get("status") in ("ok", "not converged"):
        row.update({k: v for k, v in timing.items() if type(k) is str and k.startswith("time_")
                    and type(v) in (float, int)})
    return row


#: the statuses of a row made from a method's result (which the worker gates for a plugin's method)
_RESULT_STATUSES = ("ok", "not converged")


def _gated_here(task: dict) -> bool:
    """Whether the worker gates the result of this task's method itself (a plugin's method in a generic study, of a
    family whose contract is fitbench's class), so that its child may send no 'ok' row of its own."""
    spec = methods.get(task["method"])
    if spec.builtin or not study_of(task["kind"]).generic_rows:
        return False
    cls = result_base.contract(spec.family)
    return cls is not None and result_base.builtin_class(cls)


class _ResultUnpickler:
    """Reads what a plugin's child process sent: Python's plain values, NumPy arrays and scalars, instances of
    fitbench's own result classes and of the data classes of its loaded modules; any other class or function the data
    name is refused (unpickling calls what the data name: a child running a plugin's code could otherwise make this
    process run anything)."""

    NUMPY = {("numpy.core.multiarray", "_reconstruct"), ("numpy.core.multiarray", "scalar"),
             ("numpy._core.multiarray", "_reconstruct"), ("numpy._core.multiarray", "scalar"), ("numpy", "ndarray"),
             ("numpy", "dtype"), ("numpy.core.numeric", "_frombuffer"), ("numpy._core.numeric", "_frombuffer")}

    def __init__(self, data: bytes):
        import io
        import pickle
        outer = self

        class Unpickler(pickle.Unpickler):
            def find_class(self, module, name):
                return outer.find_class(module, name)
        self.unpickler = Unpickler(io.BytesIO(data))

    def load(self):
        return self.unpickler.load()

    def find_class(self, module: str, name: str):
        import dataclasses
        import importlib
        import pickle
        import sys
        if (module, name) in self.NUMPY or (module == "numpy" and (name.startswith(("float", "int", "uint"))
                                                                   or name == "bool_")):
            return getattr(importlib.import_module(module), name)
        if module == result_base.__name__ or module in result_base.family_modules():
            cls = getattr(importlib.import_module(module), name, None)
            if isinstance(cls, type) and result_base.builtin_class(cls):
                return cls
        if module.partition(".")[0] in ("methods", "datasets") and module in sys.modules:
            # a data class of fitbench's own (the data a source of a plugin gives to a method that takes no points)
            cls = getattr(sys.modules[module], name, None)
            if isinstance(cls, type) and cls.__module__ == module and dataclasses.is_dataclass(cls):
                return cls
        raise pickle.UnpicklingError(f"{module}.{name} is not a value fitbench reads from a plugin's process")
