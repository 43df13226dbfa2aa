"""Executors: run tasks on this process, local worker processes or Dask, storing each row as it finishes."""
from __future__ import annotations

import contextlib
import os
import sys

from experiments.store import RowStore


def _run_task(task):
    from experiments.engine import run_task
    return run_task(task)


def _progress(total: int, desc: str):
    from tqdm import tqdm
    return tqdm(total=total, desc=desc, unit="row", disable=not sys.stderr.isatty(), leave=False, dynamic_ncols=True)


def execute(tasks: list[dict], store: RowStore, *, jobs: int, executor: str, scheduler: str | None, desc: str):
    """Run tasks and store each row as it finishes. KeyboardInterrupt cancels what is pending; what
    finished stays stored."""
    if not tasks:
        return
    bar = _progress(len(tasks), desc)
    try:
        if executor == "dask":
            _run_dask(tasks, store, jobs, scheduler, bar)
        elif jobs <= 1:
            for t in tasks:
                store.put(t["key"], _run_task(t))
                bar.update()
        else:
            _run_processes(tasks, store, jobs, bar)
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


def _run_processes(tasks, store, jobs, bar):
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed
    with _one_blas_thread_per_worker():
        pool = ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("spawn"))
        try:
            futures = {pool.submit(_run_task, t): t for t in tasks}
            for fut in as_completed(futures):
                store.put(futures[fut]["key"], fut.result())
                bar.update()
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown()


def _run_dask(tasks, store, jobs, scheduler, bar):
    from distributed import Client, LocalCluster, as_completed
    cluster = None
    if scheduler:
        client = Client(scheduler)
    else:
        with _one_blas_thread_per_worker():
            cluster = LocalCluster(n_workers=max(jobs, 1), threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=40)
        client = Client(cluster)
    try:
        futures = client.map(_run_task, tasks, pure=False)
        index = {f.key: t for f, t in zip(futures, tasks)}
        for fut in as_completed(futures):
            store.put(index[fut.key]["key"], fut.result())
            bar.update()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
