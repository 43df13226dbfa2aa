"""The Dask executor: chunks of rows as Dask tasks, on a LocalCluster or the cluster at ``--scheduler``.

The client submits chunks (at most two per worker thread in flight) and stores the rows they return; it
never waits without looking: every second it checks that the cluster still has workers, and a cluster
with none for :func:`no_worker_limit_s` seconds stops the run with one line (the finished rows are kept).

Isolation, as the local executor gives it (``experiments.executors``):

* With a time limit (``--row-timeout``) a Dask task does not run its rows in the worker's thread, where
  an exception raised asynchronously cannot end a row blocked in compiled code: it hands them to a *row
  process*, a child of the worker (kept for the next chunk), and watches it. A row past its limit ends
  by the child's own alarm (SIGALRM), or, if that cannot reach it, by the parent killing the child
  :data:`experiments.executors.KILL_GRACE_S` later; a child that dies labels its row ``crashed``; either
  way the other rows of the chunk run again in a new child and the task returns every row. The Dask
  worker itself never dies of a row.
* Without a time limit the rows run in the worker's thread, and a row that ends its process
  (``os._exit``, a segfault) kills the worker; its nanny starts a new one. The chunk comes back as
  ``KilledWorker`` (``allowed-failures`` is 0: no blind retries) and is bisected: its halves run again
  *alone* (nothing else in flight, so a death is theirs), down to single rows; a row whose worker died
  :data:`DASK_ROW_ATTEMPTS` times, the last time alone, is ``crashed``. The innocent rows of the chunk are
  computed as usual.
* A study running a plugin's code (its method or data source) runs its rows in row processes, with or without
  a time limit: there, as in a local worker, the rows of the plugin's code are fitted in a child forked for the
  chunk and gated and measured by the row process's own code (``experiments.chunkrows``), so what the plugin does to
  its process (patching the gate, a built-in method, NumPy) reaches neither the Dask worker nor another row.
* Without a time limit, a row that has been running for ``experiments.executors.STUCK_NOTICE_S`` seconds is named
  once in the run's output, as the local executor names it: the worker watches its running row (:class:`_LongRows`)
  and sends the line as a Dask event (``Worker.log_event``), which the client prints (``Client.subscribe_topic``).

References: Dask distributed's ``KilledWorker`` and ``distributed.scheduler.allowed-failures``
(https://distributed.dask.org/en/stable/killed.html); the Linux parent-death signal, prctl(2)
``PR_SET_PDEATHSIG``.
"""
from __future__ import annotations

import collections
import contextlib
import json
import mmap
import os
import queue
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import CancelledError

from experiments import executors
from experiments.executors import (KILL_GRACE_S, Chunks, Progress, _main_module_not_imported_by_workers,
                                  _one_blas_thread_per_worker, _store, stuck_row_text)
from experiments.localworkers import ProcessGroup, _exit_state
from methods import InvalidInputError

#: how long a connection to a Dask scheduler may take before the run gives up (seconds)
DASK_CONNECT_TIMEOUT_S = 5
#: deaths of its worker after which a row is ``crashed`` (the last one with the row running alone)
DASK_ROW_ATTEMPTS = 2
#: seconds a cluster may have no worker before the run stops (``FITBENCH_DASK_NO_WORKER_S`` overrides)
NO_WORKER_S = 120.0
#: seconds between two looks at the cluster's workers while no chunk finishes
CHECK_EVERY_S = 1.0
#: chunks cancelled by the scheduler in a row (no chunk finishing between) before the run stops
MAX_CANCELLED = 20
#: times in a row a row process may die before running a row before the task gives up
CHILD_START_ATTEMPTS = 3
#: the Dask event topic on which a worker names a row running long without a time limit (:class:`_LongRows`)
LONG_ROW_TOPIC = "fitbench-row-running-long"


class RowProcessError(RuntimeError):
    """A Dask worker cannot start a row process (it dies before running a row): the run stops."""


class WorkerCodeError(RuntimeError):
    """A Dask worker would compute rows with other code or another environment than the run that keys them: the run
    stops before any of its rows is stored."""


def no_worker_limit_s() -> float:
    """:data:`NO_WORKER_S`, or the seconds in ``FITBENCH_DASK_NO_WORKER_S`` (a cluster whose workers queue
    for a batch system may need longer)."""
    value = os.environ.get("FITBENCH_DASK_NO_WORKER_S")
    if value is None:
        return NO_WORKER_S
    try:
        seconds = float(value)
    except ValueError:
        seconds = float("nan")
    if not seconds > 0:
        raise InvalidInputError(f"FITBENCH_DASK_NO_WORKER_S must be a positive number of seconds, got {value!r}")
    return seconds


def connect_dask(scheduler: str):
    """A Client of the scheduler at ``scheduler`` (``tcp://host:port``...), or InvalidInputError in one line
    within :data:`DASK_CONNECT_TIMEOUT_S` seconds."""
    from distributed import Client
    from distributed.comm import parse_address
    address = scheduler.strip()
    try:
        scheme, loc = parse_address(address, strict=True)
        host, _, port = loc.rpartition(":")
        if scheme in ("tcp", "tls") and (not host or not port.isdigit()):
            raise ValueError("needs host:port")
    except (ValueError, TypeError) as exc:
        raise InvalidInputError(f"--scheduler {scheduler!r} is not a scheduler address such as tcp://host:8786 "
                                f"({exc})") from None
    import logging
    quiet = [logging.getLogger(n)
             for n in ("distributed", "distributed.client", "distributed.core", "distributed.comm")]
    levels = [lg.level for lg in quiet]
    for lg in quiet:
        lg.setLevel(logging.CRITICAL)
    try:
        return Client(address, timeout=DASK_CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError, ValueError) as exc:
        raise InvalidInputError(f"no Dask scheduler answered at {address} within {DASK_CONNECT_TIMEOUT_S} s "
                                f"({type(exc).__name__}); start one (dask scheduler) or check the address") from None
    finally:
        for lg, level in zip(quiet, levels):
            lg.setLevel(level)


# ---------------------------------------------------------------- in a Dask worker: rows in a row process

_IDLE: list = []  # row processes of this worker waiting for a chunk
_IDLE_LOCK = threading.Lock()
_SPAWNER = None  # one long-lived thread starts every row process (the parent-death signal follows that thread)


def _spawn(args, fds):
    global _SPAWNER
    with _IDLE_LOCK:
        if _SPAWNER is None:
            from concurrent.futures import ThreadPoolExecutor
            _SPAWNER = ThreadPoolExecutor(1, thread_name_prefix="fitbench-row-process-spawner")
    return _SPAWNER.submit(subprocess.Popen, args, pass_fds=fds, stdin=subprocess.DEVNULL).result()


def _child_main(conn_fd: int, progress_fd: int, parent_pid: int) -> None:
    """A row process: the local executor's worker loop (``experiments.executors``), talking to its Dask
    worker over an inherited socket and publishing the running row in an inherited shared page."""
    from multiprocessing.connection import Connection
    from experiments.executors import _worker_main
    progress = memoryview(mmap.mmap(progress_fd, 16)).cast("d")
    _worker_main(Connection(conn_fd), parent_pid, progress)


class _RowProcess:
    """A child of this Dask worker that runs chunks; ``progress`` = (start time of the running row, or 0;
    its position in the chunk), shared memory both processes see."""

    def __init__(self):
        from multiprocessing.connection import Connection
        mine, theirs = socket.socketpair()
        self.conn = Connection(mine.detach())
        self.page = self._map = self.progress = None
        try:
            self.page = tempfile.TemporaryFile()
            self.page.truncate(16)
            self._map = mmap.mmap(self.page.fileno(), 16)   # (it holds a descriptor of its own)
            self.progress = memoryview(self._map).cast("d")
            code = ("import sys, json; sys.path[:0] = json.loads(sys.argv[1]); "
                    "from experiments.dask_executor import _child_main; _child_main(*map(int, sys.argv[2:]))")
            self.proc = _spawn([sys.executable, "-c", code, json.dumps(sys.path), str(theirs.fileno()),
                                str(self.page.fileno()), str(os.getpid())], [theirs.fileno(), self.page.fileno()])
            # at once, before it can be reaped; where waitid is missing, Popen's returncode says whether it was
            self.group = ProcessGroup(self.proc.pid, reaped=lambda proc=self.proc: proc.returncode is not None)
        except BaseException:   # no row process (too many processes or open files): nothing of it is left open
            self.conn.close()
            self._close_page()
            raise
        finally:
            theirs.close()

    def send(self, tasks: list, row_timeout) -> None:
        self.progress[0] = self.progress[1] = 0.0
        self.conn.send((0, tasks, row_timeout))

    def wait(self, row_timeout, look=None):
        """``("done", out)``, ``("died", pos, started, exit code)`` or ``("timeout", pos)``; ``look(started, pos)``
        is called every 0.2 s with the running row (:class:`_LongRows`)."""
        while True:
            if self.conn.poll(0.2):
                try:
                    _, out = self.conn.recv()
                    return ("done", out)
                except (EOFError, OSError):
                    pass
                return self._died()
            if self._ended(0) and not self.conn.poll(0):
                return self._died()
            started = self.progress[0]
            if started and row_timeout and time.monotonic() - started > row_timeout + KILL_GRACE_S:
                pos = int(self.progress[1])
                self.stop(now=True)
                return ("timeout", pos)
            if started and look is not None:
                look(started, int(self.progress[1]))

    def _died(self):
        pos, started = int(self.progress[1]), self.progress[0]
        self.group.end()   # it has closed its end of the socket, or ended: its group now, before anything reaps it
        self._ended(5.0)
        self.stop(now=True)
        return ("died", pos, started, self.proc.returncode)

    def _ended(self, timeout: float) -> bool:
        """The row process has ended (waited for up to ``timeout`` s), told without reaping it where the system can."""
        state = _exit_state(self.proc.pid, timeout)
        if state is None:   # reaped already, or no waitid
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.proc.wait(timeout=timeout)
            return self.proc.returncode is not None
        return state

    def stop(self, now: bool = False) -> None:
        with contextlib.suppress(Exception):
            if now:
                self.group.end()   # the row process leads a group: with the processes it started
                self.proc.kill()
            else:
                self.conn.send(None)
        if not self._ended(5.0):
            self.proc.kill()
            self._ended(5.0)
        self.group.end()   # what its methods started and left in its group: before it is reaped (ProcessGroup)
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(timeout=5)
        self.group.close()
        with contextlib.suppress(Exception):
            self.conn.close()
        self._close_page()

    def _close_page(self) -> None:
        """Release the progress page: the view, the mapping (and its descriptor) and the file."""
        for release in (getattr(self.progress, "release", None), getattr(self._map, "close", None),
                        getattr(self.page, "close", None)):
            if release is not None:
                with contextlib.suppress(Exception):
                    release()


def dask_setup(worker) -> None:
    """Preload of the local cluster's worker processes (each start and restart): they ignore SIGINT, which a
    terminal's Ctrl-C sends to the whole process group; the run stops them itself and prints one line (else each
    worker printed its KeyboardInterrupt traceback)."""
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread of the worker process: nothing to do there
        pass


# ---------------------------------------------------------------- in a Dask worker: the code it runs is the run's

_STAMPS: dict = {}  # file -> (mtime_ns, size) when this worker first looked at it: its code as loaded


def _stat(path: str):
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_mtime_ns, st.st_size


def run_checked(fn, tasks: list, row_timeout, expected, notice_s: float | None = None) -> dict:
    """A Dask task: ``fn(tasks, row_timeout)`` once this worker's code and environment are shown to be the run's
    (:func:`check_code`), since the run stores the rows under keys of its own code. A worker started before a method
    was edited (or a ``git pull``) runs the code it loaded then: its rows were stored under the new code's keys.
    ``notice_s``: a row running that long without a time limit is named to the run (:class:`_LongRows`)."""
    check_code(tasks, expected)
    if fn is run_isolated:
        return run_isolated(tasks, row_timeout, notice_s)
    if row_timeout or not notice_s:
        return fn(tasks, row_timeout)
    return _watched(fn, tasks, _LongRows(tasks, notice_s, _to_the_run()))


class _LongRows:
    """In a Dask worker: name each row of ``tasks`` that has been running for ``notice_s`` seconds without a time
    limit, once, to the run (``say``), in the words of the local executor (``executors.STUCK_NOTICE_S``): a method
    that hangs would otherwise leave the run's progress line frozen with no word."""

    def __init__(self, tasks: list, notice_s: float | None, say):
        self.tasks, self.notice_s, self.say, self.named = tasks, notice_s, say, set()

    def look(self, started: float, i) -> None:
        """The row at index ``i`` of the tasks started at ``started`` (``time.monotonic``, the machine's clock)."""
        if not self.notice_s or not started or i is None or not 0 <= i < len(self.tasks) or i in self.named:
            return
        seconds = time.monotonic() - started
        if seconds >= self.notice_s:
            self.named.add(i)
            with contextlib.suppress(Exception):   # the run goes on without the notice
                self.say(stuck_row_text(self.tasks[i], seconds))


def _to_the_run():
    """A function that sends a text to the run's client as a Dask event on :data:`LONG_ROW_TOPIC` (thread-safe;
    outside a Dask worker it drops it)."""
    try:
        from distributed import get_worker
        worker = get_worker()
    except Exception:   # not in a Dask worker's task
        return lambda text: None
    return lambda text: worker.log_event(LONG_ROW_TOPIC, text)


def _watched(fn, tasks: list, long_rows: _LongRows) -> dict:
    """``fn(tasks, None, progress)`` in this thread (rows in the Dask worker's thread, no time limit) while another
    thread looks at the running row once a second (:class:`_LongRows`; a row holding the interpreter's lock in
    compiled code keeps it from looking)."""
    progress = [0.0, 0.0]
    done = threading.Event()

    def watch():
        while not done.wait(min(1.0, long_rows.notice_s / 2)):
            long_rows.look(progress[0], int(progress[1]))
    watcher = threading.Thread(target=watch, daemon=True, name="fitbench-long-rows")
    watcher.start()
    try:
        return fn(tasks, None, progress)
    finally:
        done.set()


def check_code(tasks: list, expected) -> None:
    """Raise :class:`WorkerCodeError` unless this process computes as the run does: the same environment
    (``codekeys.environment``: kernels, Python and numerical packages' versions), the same code hashes for one task of
    each (method, study kind, data set) of the chunk (``codekeys.task_code``, as the run computed them), and none of
    those files changed since this worker loaded its modules (their size and time stamp when it first looked)."""
    from experiments import codehash, codekeys
    reps, environment = expected
    host = socket.gethostname()
    restart = ("restart the workers (they load fitbench and the plugins when they start) and run the same command "
               "again; the finished rows are kept")
    mine = codekeys.environment()
    if mine != environment:
        differ = sorted(k for k in set(mine) | set(environment) if mine.get(k) != environment.get(k))
        raise WorkerCodeError(f"the Dask worker on {host} computes with another environment than this run "
                              f"({', '.join(differ)}: {[mine.get(k) for k in differ]} there, "
                              f"{[environment.get(k) for k in differ]} here); install the same versions there, then "
                              f"{restart}")
    if not _STAMPS:
        for module in list(sys.modules.values()):
            path = getattr(module, "__file__", None)
            if path:
                _STAMPS.setdefault(os.path.realpath(path), _stat(path))
    for pos, code in reps:
        task = tasks[pos]
        theirs = codekeys.task_code(task)
        if theirs != code:
            differ = [k for k in code if theirs.get(k) != code[k]]
            raise WorkerCodeError(f"the Dask worker on {host} has other code than this run for {task['method']} "
                                  f"({', '.join(differ)}); give the workers this run's code (the same commit and "
                                  f"plugins), then {restart}")
        modules = [m for m in (methods_module(task["method"]), source_module(task)) if m]
        modules += ["experiments.metrics", "experiments.timing", "experiments.rows", f"experiments.studies.{task['kind']}"]
        for module in modules:
            for path in map(os.path.realpath, map(str, codehash.files_of(module))):
                now = _stat(path)
                if _STAMPS.setdefault(path, now) != now:
                    raise WorkerCodeError(f"the Dask worker on {host} loaded {path} before it was changed: its "
                                          f"{task['method']} rows would not be this code's; {restart}")


def methods_module(method: str) -> str | None:
    import methods
    try:
        return methods.get(method).module
    except LookupError:  # unknown here: its code hash already differs from the run's
        return None


def source_module(task: dict) -> str | None:
    from datasets import sources
    from experiments.rows import source_of
    try:
        return sources.get_source(source_of(task["dataset"])).module
    except (LookupError, TypeError, ValueError):  # a study's own data (its code is the study's)
        return None


def expected_code(chunk: list) -> tuple:
    """What :func:`check_code` compares in the worker: the run's environment and code hashes of one task of each
    (method, study kind, data set) of ``chunk``."""
    from experiments import codekeys
    seen, reps = set(), []
    for pos, task in enumerate(chunk):
        k = (task["method"], task["kind"], id(task["dataset"]))
        if k not in seen:
            seen.add(k)
            reps.append((pos, codekeys.task_code(task)))
    return reps, codekeys.environment()


def run_isolated(tasks: list, row_timeout: float | None, notice_s: float | None = None, say=None) -> dict:
    """A Dask task: run a chunk in a row process of this worker (see the module's docstring) and return its
    rows in the store's columns, every row labelled, in the order of ``tasks`` (``row_timeout`` None: no limit; then
    a row running ``notice_s`` seconds is named to the run, by ``say``: :class:`_LongRows`)."""
    from experiments.rows import encode_rows, failed_row
    n = len(tasks)
    status: list = [None] * n
    rows: list = [None] * n
    seconds = 0.0
    todo = collections.deque([list(range(n))])
    with _IDLE_LOCK:
        child = _IDLE.pop() if _IDLE else None
    start_failures = 0
    long_rows = _LongRows(tasks, None if row_timeout else notice_s, say or _to_the_run())

    def label(i, what, message):
        enc = encode_rows([failed_row(tasks[i], what, message)])
        status[i], rows[i] = enc["status"][0], enc["row"][0]
    try:
        while todo:
            idx = todo.popleft()
            if child is None:
                child = _RowProcess()
            t0 = time.perf_counter()
            child.send([tasks[i] for i in idx], row_timeout)
            what, *info = child.wait(row_timeout, lambda started, pos, idx=idx:
                                     long_rows.look(started, idx[pos] if 0 <= pos < len(idx) else None))
            if what == "done":
                out = info[0]
                if "failed" in out:  # the engine itself failed: the rows alone, then an error row
                    if len(idx) > 1:
                        todo.extendleft([i] for i in reversed(idx))
                    else:
                        label(idx[0], "error", out["failed"])
                    continue
                seconds += out["seconds"]
                for i, s, r in zip(idx, out["columns"]["status"], out["columns"]["row"]):
                    status[i], rows[i] = s, r
                start_failures = 0
                continue
            child = None
            seconds += time.perf_counter() - t0
            if what == "timeout":
                pos = info[0]
                label(idx[pos], "timeout",
                      f"the row ran longer than its limit of {row_timeout:g} s (the process running it was ended)")
            else:
                pos, started, code = info
                if not started:  # it died before running a row: the process, not a row
                    start_failures += 1
                    if start_failures >= CHILD_START_ATTEMPTS:
                        raise RowProcessError(f"row processes of the Dask worker on {socket.gethostname()} end before "
                                              f"running a row (exit code {code}, {start_failures} times)")
                    todo.appendleft(idx)
                    continue
                label(idx[pos], "crashed", f"the process running this row ended (exit code {code})")
            rest = idx[:pos] + idx[pos + 1:]  # the rows before it died with the process: they run again
            if rest:
                todo.appendleft(rest)
    except BaseException:
        if child is not None:
            child.stop(now=True)
        raise
    if child is not None:
        with _IDLE_LOCK:
            _IDLE.append(child)
    return {"columns": {"status": status, "row": rows}, "seconds": seconds}


# ---------------------------------------------------------------- in the client

def execute(tasks, store, *, work, jobs: int, scheduler: str | None, desc: str, total: int | None = None,
            row_timeout: float | None = None, chunk_rows: int | None = None, log=print, executor: str = "dask",
            isolate: bool = False):
    """``experiments.executors.execute`` on Dask: the tasks in chunks (sized as there), each chunk's rows
    stored as it returns (:func:`run_dask`). Rows always run in Dask's worker processes; with ``isolate`` (a
    plugin's method or data source in the study) in their row processes (:func:`run_isolated`)."""
    if total == 0:
        return
    bar = Progress(total if total is not None else 0, desc, log)
    try:
        run_dask(work, Chunks(tasks, chunk_rows, jobs, total), store, jobs, scheduler, bar, row_timeout, isolate)
    finally:
        bar.close()


def run_dask(work, chunks, store, jobs: int, scheduler, bar, row_timeout, isolate: bool = False) -> None:
    """Run ``chunks`` (an ``experiments.executors.Chunks``) as Dask tasks of ``work`` (or
    :func:`run_isolated` with a time limit or, ``isolate``, rows of a plugin's code) on a LocalCluster of ``jobs`` single-threaded worker processes,
    or on the cluster at ``scheduler``; store each chunk's rows as it returns (see the module's docstring).

    Ctrl-C is the run's own from before the cluster starts (:func:`_ctrl_c_sets`): interrupted while a LocalCluster
    started, Python had raised KeyboardInterrupt inside its start, and distributed's exit hook then failed to close
    the half-started cluster with a long traceback; the workers start with SIGINT blocked (:func:`_ctrl_c_held`)
    until their preload ignores it."""
    import dask
    from distributed import Client, LocalCluster
    limit_s = no_worker_limit_s()
    settings = {"distributed.scheduler.allowed-failures": 0}
    if scheduler is None:
        # A LocalCluster closes a nanny whose worker has not registered again within this timeout after a
        # death; with workers dying one after another the timeout fell on a restart, every nanny was closed
        # and the run waited for ever. Our nannies restart their workers themselves.
        settings["distributed.deploy.lost-worker-timeout"] = "100000 s"
    cluster = client = None
    finished: queue.Queue = queue.Queue()
    interrupted = threading.Event()
    pending: dict = {}  # key -> (future, chunk, ran alone)
    previous = _ctrl_c_sets(interrupted, finished)
    try:
        with dask.config.set(settings):
            if scheduler is not None:
                client = connect_dask(scheduler)
                where = f"the Dask cluster at {scheduler.strip()}"
            else:
                try:
                    with _one_blas_thread_per_worker(), _ctrl_c_held(), _main_module_not_imported_by_workers():
                        cluster = LocalCluster(n_workers=max(jobs, 1), threads_per_worker=1, processes=True,
                                               dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": False},
                                               silence_logs=50,  # its HTTP server on a free local port, no dashboard
                                               preload=[__name__])  # dask_setup below: Ctrl-C is the run's alone
                    client = Client(cluster)
                except Exception as exc:  # distributed gives a thread 10 s to start its event loop (an assert)
                    if interrupted.is_set():  # the user's Ctrl-C, held while the cluster started, came first
                        raise KeyboardInterrupt from None
                    from methods import InvalidInputError
                    raise InvalidInputError(
                        f"the local Dask cluster did not start ({type(exc).__name__}: {str(exc) or 'no message'}; "
                        f"a machine too busy to start it in distributed's time limits?); run the same command again, "
                        f"or with --executor local") from None
                where = "the local Dask cluster"
            _drive(client, where, work, chunks, store, bar, row_timeout, limit_s, interrupted, finished, pending,
                   isolate)
    except BaseException:
        if client is not None:
            with contextlib.suppress(Exception):
                client.cancel([f for f, _, _ in pending.values()])
        raise
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
        if client is not None:
            with contextlib.suppress(Exception):
                client.close()
        if cluster is not None:
            with contextlib.suppress(Exception):
                cluster.close()


def _drive(client, where: str, work, chunks, store, bar, row_timeout, limit_s: float, interrupted: threading.Event,
           finished: queue.Queue, pending: dict, isolate: bool = False) -> None:
    """The run's loop over the chunks on ``client`` (see the module's docstring); ``pending`` holds the chunks in
    flight (the caller cancels them when the loop raises)."""
    from distributed import KilledWorker
    from experiments.rows import encode_rows, failed_row, raise_if_signalled
    if interrupted.is_set():
        raise KeyboardInterrupt
    fn = run_isolated if row_timeout or isolate else work
    retry: collections.deque = collections.deque()  # chunks whose worker died: each runs alone
    deaths: collections.Counter = collections.Counter()  # row key -> deaths of the worker running it
    threads = _threads(client)

    def submit(chunk, alone):
        fut = client.submit(run_checked, fn, chunk, row_timeout, expected_code(chunk),
                            None if row_timeout else executors.STUCK_NOTICE_S, pure=False)
        pending[fut.key] = (fut, chunk, alone)
        fut.add_done_callback(finished.put)

    def fill():
        while True:
            if retry:
                if not pending:
                    submit(retry.popleft(), True)
                return
            if len(pending) >= 2 * max(threads, 1):
                return
            chunk = chunks.next()
            if chunk is None:
                return
            submit(chunk, False)

    def died(chunk, alone, why):
        for t in chunk:
            deaths[t["key"]] += 1
        if len(chunk) > 1:
            half = len(chunk) // 2
            retry.extendleft([chunk[half:], chunk[:half]])
        elif alone and deaths[chunk[0]["key"]] >= DASK_ROW_ATTEMPTS:
            msg = (f"its Dask worker died each of the {deaths[chunk[0]['key']]} times it ran this row, the last "
                   f"time with nothing else running ({why})")
            _store(store, encode_rows([failed_row(chunk[0], "crashed", msg)]), chunk, bar)
        else:
            retry.appendleft(chunk)

    notices: queue.Queue = queue.Queue()  # rows running long, named by the workers (_LongRows)
    with contextlib.suppress(Exception):  # (the subscription ends with the client, closed after the run)
        client.subscribe_topic(LONG_ROW_TOPIC, lambda event: notices.put(event[1]))
    fill()
    cancelled = 0
    seen = checked = time.monotonic()
    while pending:
        try:
            fut = finished.get(timeout=CHECK_EVERY_S)
        except queue.Empty:
            fut = None
        while not notices.empty():
            bar.notice(str(notices.get_nowait()))
        if interrupted.is_set():
            raise KeyboardInterrupt
        raise_if_signalled()  # SIGTERM: the run's handler raised it, maybe where it was lost
        if fut is not None and fut.key in pending:
            _, chunk, alone = pending[fut.key]
            try:
                out = fut.result(timeout=10)
            except KilledWorker as exc:
                del pending[fut.key]
                died(chunk, alone, type(exc).__name__)
            except RowProcessError as exc:
                raise InvalidInputError(f"{exc}; run with --jobs 1 on that machine to see why") from None
            except WorkerCodeError as exc:
                raise InvalidInputError(str(exc)) from None
            except TimeoutError:  # its result was lost with a worker before it was fetched
                if not fut.done():
                    fut.add_done_callback(finished.put)  # computed again: wait for it
                else:
                    del pending[fut.key]
                    retry.appendleft(chunk)
            except CancelledError as exc:  # the scheduler lost it (restarted), or the connection is gone
                del pending[fut.key]
                cancelled += 1
                if client.status not in ("running", "connecting") or cancelled > MAX_CANCELLED:
                    raise InvalidInputError(f"the connection to {where} was lost ({type(exc).__name__}); "
                                            f"the finished rows are kept, run the same command again") from None
                retry.appendleft(chunk)
            except Exception as exc:  # the engine itself failed: the rows alone, then an error row
                del pending[fut.key]
                if len(chunk) > 1:
                    retry.extendleft([t] for t in reversed(chunk))
                else:
                    _store(store, encode_rows([failed_row(chunk[0], "error", f"{type(exc).__name__}: {exc}")]),
                           chunk, bar)
            else:
                del pending[fut.key]
                cancelled = 0
                chunks.measured(len(chunk), out["seconds"])
                _store(store, out["columns"], chunk, bar)
        now = time.monotonic()
        if now - checked >= CHECK_EVERY_S:
            checked = now
            threads = _threads(client)
            if threads:
                seen = now
            elif now - seen > limit_s:
                raise InvalidInputError(
                    f"{where} has had no worker for {limit_s:g} s ({len(pending)} chunks waiting); "
                    f"the finished rows are kept: start workers (dask worker ADDRESS) and run the same command "
                    f"again, or give workers longer to come with FITBENCH_DASK_NO_WORKER_S=SECONDS")
        fill()


def _ctrl_c_sets(interrupted: threading.Event, wake: queue.Queue):
    """In the main thread: SIGINT sets ``interrupted`` and wakes the run's loop (a None in ``wake``), which then
    raises KeyboardInterrupt itself; Python's own handler raised it wherever the main thread was, and distributed's
    callbacks in this process (its garbage-collection timer) swallowed it with a printed traceback. Returns the
    previous handler (None outside the main thread: nothing changed)."""
    if threading.current_thread() is not threading.main_thread():
        return None
    from experiments.rows import note_signal

    def on_sigint(signum, frame):
        note_signal()
        interrupted.set()
        wake.put(None)
    return signal.signal(signal.SIGINT, on_sigint)


@contextlib.contextmanager
def _ctrl_c_held():
    """SIGINT blocked in this thread while a LocalCluster starts: the threads it starts and the worker processes
    they spawn inherit the blocked signal (fork and exec keep the signal mask), so a Ctrl-C before a worker's
    preload (:func:`dask_setup`) ignores it cannot end that worker with a traceback; here it waits until the
    block ends and then reaches the run's own handler. multiprocessing's resource tracker starts first: starting, it
    blocks and then *unblocks* SIGINT in the thread that starts it (the same guard for its own process), which
    would undo this block in the thread that spawns the workers."""
    from multiprocessing import resource_tracker
    resource_tracker.ensure_running()
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def _threads(client) -> int:
    """Threads of the cluster's live workers (0 if the scheduler does not answer)."""
    try:
        return sum(client.nthreads().values())
    except Exception:
        return 0
