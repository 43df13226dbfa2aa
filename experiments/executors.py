"""Executors: run tasks on this process, local worker processes or Dask, storing each row as it finishes."""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time

from experiments.store import RowStore




def _progress(total: int, desc: str):
    from tqdm import tqdm
    return tqdm(total=total, desc=desc, unit="row", disable=not sys.stderr.isatty(), leave=False, dynamic_ncols=True)


def execute(tasks: list[dict], store: RowStore, *, work, jobs: int, executor: str, scheduler: str | None, desc: str):
    """Run tasks and store each row as it finishes. KeyboardInterrupt cancels what is pending; what
    finished stays stored."""
    if not tasks:
        return
    bar = _progress(len(tasks), desc)
    try:
        if executor == "dask":
            _run_dask(work, tasks, store, jobs, scheduler, bar)
        elif jobs <= 1:
            for t in tasks:
                store.put(t["key"], work(t))
                bar.update()
        else:
            _run_processes(work, tasks, store, jobs, bar)
    finally:
        bar.close()


BLAS_THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


@contextlib.contextmanager
def _one_blas_thread_per_worker():
    """Workers inherit the environment when they start (lazily, at the first submit): one BLAS thread each,
    unless the user chose otherwise. With several workers, multi-threaded BLAS on small matrices
    oversubscribes the cores (the multilateration study ran 3x slower with 2 workers x 2 OpenBLAS threads
    on 2 cores)."""
    saved = {v: os.environ.get(v) for v in BLAS_THREAD_VARS}
    for var in BLAS_THREAD_VARS:
        os.environ.setdefault(var, "1")
    try:
        yield
    finally:
        for v, val in saved.items():
            if val is None:
                os.environ.pop(v, None)
            else:
                os.environ[v] = val


def _die_with_parent(parent_pid: int) -> None:
    """Worker initializer: the worker ends when the run that started it ends, however it ends.

    On Linux the kernel sends SIGKILL to the worker when its parent dies (``prctl(PR_SET_PDEATHSIG)``
    through ctypes); elsewhere a daemon thread polls ``os.getppid()`` every 0.5 s. A worker ignores
    Ctrl-C (SIGINT reaches the whole process group): the parent stops the pool and prints one line.
    When the workers are gone, the multiprocessing resource tracker sees its pipe close and exits too."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    armed = False
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            libc = ctypes.CDLL(None, use_errno=True)
            armed = libc.prctl(1, signal.SIGKILL, 0, 0, 0) == 0  # 1 = PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            armed = False
    if os.getppid() != parent_pid:  # the parent died before the guard was armed
        os._exit(1)
    if not armed:
        def watch():
            while os.getppid() == parent_pid:
                time.sleep(0.5)
            os._exit(1)
        threading.Thread(target=watch, daemon=True, name="fitbench-parent-watchdog").start()


@contextlib.contextmanager
def _workers_ignore_ctrl_c():
    """Start workers with SIGINT ignored (an ignored signal stays ignored across exec, and Python then
    installs no KeyboardInterrupt handler): Ctrl-C reaches the whole process group, and a worker still
    importing must not print a traceback. The parent's own handler is restored at once."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _stop_pool(pool) -> None:
    """Stop a ProcessPoolExecutor now: cancel what is pending and end the running workers."""
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        with contextlib.suppress(Exception):
            proc.terminate()
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        with contextlib.suppress(Exception):
            proc.join(timeout=5)


def _run_processes(work, tasks, store, jobs, bar):
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed
    with _one_blas_thread_per_worker():
        pool = ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("spawn"),
                                   initializer=_die_with_parent, initargs=(os.getpid(),))
        try:
            with _workers_ignore_ctrl_c():
                futures = {pool.submit(work, t): t for t in tasks}  # the workers start here
            for fut in as_completed(futures):
                store.put(futures[fut]["key"], fut.result())
                bar.update()
        except BaseException:
            _stop_pool(pool)
            raise
        pool.shutdown()


#: how long a connection to a Dask scheduler may take before the run gives up (seconds)
DASK_CONNECT_TIMEOUT_S = 5


def connect_dask(scheduler: str):
    """A Client of the scheduler at ``scheduler`` (``tcp://host:port``...), or InvalidInputError in one line
    within :data:`DASK_CONNECT_TIMEOUT_S` seconds."""
    from distributed import Client
    from distributed.comm import parse_address
    from methods import InvalidInputError
    address = scheduler.strip()
    try:
        scheme, loc = parse_address(address, strict=True)
        host, _, port = loc.rpartition(":")
        if scheme in ("tcp", "tls") and (not host or not port.isdigit()):
            raise ValueError("needs host:port")
    except (ValueError, TypeError) as exc:
        raise InvalidInputError(f"--scheduler {scheduler!r} is not a scheduler address such as tcp://host:8786 ({exc})") from None
    import logging
    quiet = [logging.getLogger(n) for n in ("distributed", "distributed.client", "distributed.core", "distributed.comm")]
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


def _run_dask(work, tasks, store, jobs, scheduler, bar):
    from distributed import Client, LocalCluster, as_completed
    cluster = None
    if scheduler is not None:
        client = connect_dask(scheduler)
    else:
        with _one_blas_thread_per_worker():
            cluster = LocalCluster(n_workers=max(jobs, 1), threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=40)
        client = Client(cluster)
    try:
        futures = client.map(work, tasks, pure=False)
        index = {f.key: t for f, t in zip(futures, tasks)}
        for fut in as_completed(futures):
            store.put(index[fut.key]["key"], fut.result())  # rows are written by the client, not the workers
            bar.update()
    except BaseException:
        with contextlib.suppress(Exception):
            client.cancel(futures)
        raise
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
