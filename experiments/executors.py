"""Executors: run tasks on this process, local worker processes or Dask, storing each row as it finishes."""
from __future__ import annotations

import contextlib
import itertools
import signal
import sys
import threading
import time

from experiments.rows import encode_rows, failed_row, note_signal, raise_if_signalled
from experiments.store import RowStore
from experiments.localworkers import (_CALL, BLAS_THREAD_VARS, _main_module_not_imported_by_workers,  # noqa: F401
                                      _one_blas_thread_per_worker, _Worker, _worker_main, _workers_ignore_ctrl_c,
                                      take_early)




class Progress:
    """Rows done, rows/s and the ETA: a bar on a terminal, else a line every :attr:`every_s` seconds once a
    study has run that long (a log file of a long study says how far it is)."""

    every_s = 10.0

    def __init__(self, total: int, desc: str, log=print):
        from tqdm import tqdm
        self.total, self.desc, self.log, self.done = total, desc, log, 0
        self.t0 = self.last = time.monotonic()
        self.bar = tqdm(total=total, desc=desc, unit="row", disable=not sys.stderr.isatty(), leave=False,
                        dynamic_ncols=True)

    def line(self) -> str:
        elapsed = max(time.monotonic() - self.t0, 1e-9)
        rate = self.done / elapsed
        eta = (self.total - self.done) / rate if rate > 0 else float("inf")
        return (f"   {self.desc}: {self.done:,}/{self.total:,} rows ({self.done / max(self.total, 1):.0%}), "
                f"{_rate(rate)}, ETA {_duration(eta)}")

    def update(self, n: int = 1) -> None:
        self.done += n
        self.bar.update(n)
        now = time.monotonic()
        if self.bar.disable and now - self.last >= self.every_s and self.done < self.total:
            self.last = now
            self.log(self.line())

    def notice(self, text: str) -> None:
        """A line of its own, above the bar on a terminal."""
        if self.bar.disable:
            self.log(text)
        else:
            self.bar.write(text)

    def close(self) -> None:
        self.bar.close()


def _rate(rows_per_s: float) -> str:
    """A rate a person reads: ``250 rows/s``, ``4.2 rows/s``, or for rows slower than one a second ``3.7 s/row``."""
    if rows_per_s <= 0:
        return "no row done yet"
    if rows_per_s >= 9.95:
        return f"{rows_per_s:,.0f} rows/s"
    if rows_per_s >= 1:
        return f"{rows_per_s:.1f} rows/s"
    per_row = 1 / rows_per_s
    return f"{per_row:.1f} s/row" if per_row < 9.95 else f"{per_row:,.0f} s/row"


def _duration(seconds: float) -> str:
    if seconds == float("inf"):
        return "unknown"
    seconds = int(round(seconds))
    h, rest = divmod(seconds, 3600)
    m, s = divmod(rest, 60)
    return f"{h} h {m:02d} min" if h else (f"{m} min {s:02d} s" if m else f"{s} s")


class Chunks:
    """Tasks cut into chunks whose size follows the measured cost of a row: a chunk takes about
    :attr:`target_s` seconds of a worker (one transaction of the store, one message each way) (between 1 and :attr:`max_rows` rows), so that microsecond
    fits travel in thousands and slow rows one by one; ``declared`` fixes the size. With several workers and a known
    ``total``, a chunk is at most half of what is left per worker, so the run's last chunks are short. Rows of a
    chunk that failed as a whole (a worker died) come back one at a time first."""

    target_s = 0.5
    max_rows = 10000

    def __init__(self, tasks, declared: int | None = None, workers: int = 1, total: int | None = None):
        self.it = iter(tasks)
        self.declared = declared
        self.size = declared or 4
        self.workers = workers
        self.left = total  # rows not handed out yet (None: unknown)
        self.retry: list[list] = []
        self.cost = None  # seconds per row, smoothed

    def measured(self, rows: int, seconds: float) -> None:
        if self.declared or rows == 0:
            return
        per_row = seconds / rows
        self.cost = per_row if self.cost is None else 0.5 * self.cost + 0.5 * per_row
        self.size = int(min(self.max_rows, max(1, self.target_s / max(self.cost, 1e-7))))

    def next(self) -> list | None:
        if self.retry:
            return self.retry.pop(0)
        size = self.size
        if not self.declared and self.left is not None and self.workers > 1:
            # the last chunks shrink (at most a share of what is left per worker): no worker runs a long last chunk
            # while the others wait
            size = max(1, min(size, -(-self.left // (2 * self.workers))))
        chunk = list(itertools.islice(self.it, size))
        if self.left is not None:
            self.left -= len(chunk)
        if not self.declared and self.cost is None:
            self.size = min(self.size * 2, 64)  # until a cost is measured: small chunks, growing
        return chunk or None

    def again(self, tasks: list) -> None:
        """Tasks to run again, one per chunk, before any new chunk."""
        self.retry[:0] = [[t] for t in tasks]


def execute(tasks, store: RowStore, *, work, jobs: int, executor: str, scheduler: str | None, desc: str,
            total: int | None = None, row_timeout: float | None = None, chunk_rows: int | None = None, log=print,
            isolate: bool = False):
    """Run tasks (an iterable) in chunks and store each chunk's rows as it finishes. With one job, no time limit
    and rows of fitbench's own code (not ``isolate``: no plugin's method or data source) the rows run in this
    process; otherwise in worker processes that a crash, an exit or a stuck row cannot take down with the run. KeyboardInterrupt cancels what is pending; what
    finished stays stored."""
    if total == 0:
        return
    bar = Progress(total if total is not None else 0, desc, log)
    chunks = Chunks(tasks, chunk_rows, jobs, total)
    try:
        if executor != "local":
            raise ValueError(f"executor {executor!r}: this module runs rows locally (Dask: experiments.dask_executor)")
        if jobs <= 1 and not row_timeout and not isolate:
            _run_here(work, chunks, store, bar)
        else:
            _run_processes(work, chunks, store, max(jobs, 1), bar, row_timeout)
    finally:
        bar.close()


def _store(store: RowStore, batch: dict, tasks: list, bar) -> None:
    """A finished chunk (:func:`experiments.rows.encode_rows`) to the store: the row store, or the run's landing
    (``experiments.engine.Landing``: the row store and the run's frame)."""
    store.put_batch([t["key"] for t in tasks], batch)
    bar.update(len(tasks))


def _run_here(work, chunks: Chunks, store: RowStore, bar) -> None:
    previous = None
    if threading.current_thread() is threading.main_thread():
        handler = signal.getsignal(signal.SIGINT)

        def on_sigint(signum, frame):  # the run's own Ctrl-C: not a method's KeyboardInterrupt
            note_signal()
            if callable(handler):
                handler(signum, frame)
            raise KeyboardInterrupt
        previous = signal.signal(signal.SIGINT, on_sigint)
    from fitbench.streams import stdout_to_stderr   # a method's prints go to stderr, as in a worker (80 us a chunk)
    try:
        while (chunk := chunks.next()) is not None:
            raise_if_signalled()
            with stdout_to_stderr():
                out = work(chunk)
            chunks.measured(len(chunk), out["seconds"])
            _store(store, out["columns"], chunk, bar)
    finally:
        if previous is not None:
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


#: extra seconds a row may run past its limit before its worker is killed (a row stuck in compiled code
#: does not see the SIGALRM that ends a row running Python)
KILL_GRACE_S = 2.0


def map_in_idle_workers(func, arguments):
    """``func(*args)`` for each ``args`` of ``arguments``, in the run's idle local workers (:func:`kept_workers`),
    yielded in order (an iterator); what no worker makes (there is none, or one ended) is made in this process. The
    first calls are sent now, one per worker, so that the workers make them while this process does something else
    before it reads the results; each worker has one call at a time (a worker never waits to send a result while this
    process waits to send it the next). Closed before its end (``close()``: an error, Ctrl-C), it ends the workers that
    still have a call, so that no result is left for the next use of the workers."""
    return _IdleWorkerMap(func, arguments)


class _IdleWorkerMap:
    """The iterator of :func:`map_in_idle_workers`."""

    def __init__(self, func, arguments):
        import collections
        self.func = func
        self.free = [w for w in (_KEPT or []) if not w.stopping and w.chunk is None and not w.ended()]
        self.todo = iter(arguments)
        self.pending: collections.deque = collections.deque()  # (worker or None, args), in order
        try:
            while self.free and self._send_next():  # the first calls start at once
                pass
        except BaseException:
            self.close()
            raise

    def _send_next(self) -> bool:
        args = next(self.todo, None)
        if args is None:
            return False
        worker = self.free.pop(0) if self.free else None
        if worker is not None:
            try:
                worker.conn.send((_CALL, self.func, args))
            except OSError:  # the worker has ended: this process makes it
                worker = None
        self.pending.append((worker, args))
        return True

    def __iter__(self):
        return self

    def __next__(self):
        if not self.pending and not self._send_next():
            raise StopIteration
        try:
            worker, args = self.pending.popleft()
            done = False
            if worker is not None:
                try:
                    done, value = worker.conn.recv()
                except (EOFError, OSError):  # the worker ended: not one of the free workers any more
                    worker = None
                else:
                    self.free.append(worker)
            if not done:  # no worker, or it failed: made here (a failure of func raises here, as it would)
                value = self.func(*args)
            while self.free and self._send_next():
                pass
        except BaseException:
            self.close()
            raise
        return value

    def close(self) -> None:
        """End the workers that still have a call (their result must not reach the next user of the workers)."""
        pending, self.pending = self.pending, type(self.pending)()
        self.todo = iter(())
        for worker, _ in pending:
            if worker is not None:
                worker.stop(now=True)
                with contextlib.suppress(ValueError):
                    _KEPT.remove(worker)


#: seconds after which a row running without a time limit is named in the run's output (once)
STUCK_NOTICE_S = 60.0


def _notice_stuck_row(w: _Worker, seconds: float, bar) -> None:
    """Say once which row a worker has been running for :data:`STUCK_NOTICE_S` seconds without a time limit (a method
    that hangs would otherwise freeze the progress line with no word)."""
    pos = int(w.progress[1])
    if w.noticed == (w.chunk_id, pos) or not 0 <= pos < len(w.chunk or ()):
        return
    w.noticed = (w.chunk_id, pos)
    bar.notice(stuck_row_text(w.chunk[pos], seconds))


def stuck_row_text(task: dict, seconds: float) -> str:
    """The line that names a row running for ``seconds`` without a time limit (:data:`STUCK_NOTICE_S`), on every
    executor."""
    spec = task.get("dataset")
    where = f" on {spec.get('label')}" if isinstance(spec, dict) and spec.get("label") else ""
    rep = f", repetition {task['repetition']}" if "repetition" in task else ""
    return (f"   a row has been running for {seconds:.0f} s: {task.get('method', 'a row')}{where}{rep}; without a "
            f"time limit nothing ends it (--row-timeout SECONDS, or row_timeout in the study's TOML, ends such rows "
            f"as 'timeout')")


def _lost_chunk(chunks: Chunks, store: RowStore, bar, chunk: list, pos: int, status: str, message: str) -> None:
    """A worker died (or was killed) at row ``pos`` of ``chunk``: that row gets ``status``; the rows before
    it (their results died with the worker) and after it run again, one per chunk."""
    pos = min(max(int(pos), 0), len(chunk) - 1)
    bad = chunk[pos]
    _store(store, encode_rows([failed_row(bad, status, message)]), [bad], bar)
    chunks.again(chunk[:pos] + chunk[pos + 1:])


def _run_processes(work, chunks: Chunks, store: RowStore, jobs: int, bar, row_timeout) -> None:
    """Chunks on ``jobs`` worker processes (the run's early ones, else spawned; one BLAS thread each). A worker that dies labels the
    row it was running ``crashed``; a row past its limit by :data:`KILL_GRACE_S` gets its worker killed
    and is labelled ``timeout``; a new worker takes over and the study goes on."""
    import multiprocessing as mp
    from multiprocessing.connection import wait
    ctx = mp.get_context("spawn")
    workers: list[_Worker] = []
    received: list = []  # chunks whose rows came back, stored once their workers have their next chunk
    next_id = startup_failures = 0
    with _one_blas_thread_per_worker():
        try:
            kept = _KEPT if _KEPT is not None else []
            workers = [kept.pop() for _ in range(min(jobs, len(kept)))]
            for w in [w for w in workers if w.stopping]:  # told to end (a study with a second round of rows)
                workers.remove(w)
                w.stop()
            with _workers_ignore_ctrl_c():
                workers += [_Worker(ctx) for _ in range(jobs - len(workers))]
            while True:
                for w in workers:
                    if w.chunk is None:
                        chunk = chunks.next()  # rows to run again (a worker died) come first
                        if chunk is None:
                            break
                        try:
                            w.send(next_id, chunk, row_timeout)
                        except OSError:  # the idle worker has ended (killed from outside, or it could not start)
                            w.ended(5.0)
                            w.stop(now=True)   # its process group first, then it is reaped
                            code = w.proc.exitcode
                            startup_failures += 1
                            if startup_failures >= 3:
                                from methods import InvalidInputError
                                raise InvalidInputError(
                                    f"worker processes end before running a row (exit code {code}, 3 times); "
                                    f"run with --jobs 1 to see why") from None
                            chunks.retry.insert(0, chunk)  # the chunk goes to the worker that replaces it
                            with _workers_ignore_ctrl_c():
                                workers[workers.index(w)] = _Worker(ctx)
                            continue
                        next_id += 1
                while received:  # the workers run their next chunks meanwhile
                    out, chunk = received.pop(0)
                    _store(store, out["columns"], chunk, bar)
                busy = [w for w in workers if w.chunk is not None]
                if not busy:
                    if chunks.retry:  # a chunk waits for the worker that replaced one that had ended
                        continue
                    break
                raise_if_signalled()
                ready = wait([w.conn for w in busy] + [w.proc.sentinel for w in busy], timeout=0.5)
                for w in busy:
                    died = w.proc.sentinel in ready and not w.conn.poll()
                    if w.conn in ready and not died:
                        try:
                            chunk_id, out = w.conn.recv()
                        except (EOFError, OSError):
                            died = True
                        else:
                            chunk = w.chunk
                            w.chunk = None
                            if "failed" in out:
                                if len(chunk) > 1:
                                    chunks.again(chunk)
                                else:
                                    _lost_chunk(chunks, store, bar, chunk, 0, "error", out["failed"])
                                continue
                            chunks.measured(len(chunk), out["seconds"])
                            received.append((out, chunk))
                            startup_failures = 0
                            continue
                    if died:
                        pos, started = w.progress[1], w.progress[0]
                        w.ended(5.0)
                        w.stop(now=True)   # its process group first, then it is reaped
                        code = w.proc.exitcode
                        if not started:  # it died before running a row: the worker, not a row
                            startup_failures += 1
                            if startup_failures >= 3:
                                from methods import InvalidInputError
                                raise InvalidInputError(
                                    f"worker processes end before running a row (exit code {code}, 3 times); "
                                    f"run with --jobs 1 to see why")
                            chunks.again(w.chunk)
                        else:
                            startup_failures = 0
                            _lost_chunk(chunks, store, bar, w.chunk, pos, "crashed",
                                        f"the process running this row ended (exit code {code})")
                        with _workers_ignore_ctrl_c():
                            workers[workers.index(w)] = _Worker(ctx)
                        continue
                    started = w.progress[0]
                    if not row_timeout and started and time.monotonic() - started > STUCK_NOTICE_S:
                        _notice_stuck_row(w, time.monotonic() - started, bar)
                    if row_timeout and started and time.monotonic() - started > row_timeout + KILL_GRACE_S:
                        pos = w.progress[1]
                        w.stop(now=True)
                        _lost_chunk(chunks, store, bar, w.chunk, pos, "timeout",
                                    f"the row ran longer than its limit of {row_timeout:g} s (the process running it was ended)")
                        with _workers_ignore_ctrl_c():
                            workers[workers.index(w)] = _Worker(ctx)
        except BaseException as exc:
            for w in workers:
                w.stop(now=True)
            if isinstance(exc, KeyboardInterrupt):  # what finished stays stored
                for out, chunk in received:
                    _store(store, out["columns"], chunk, bar)
            raise
        for w in workers:
            if _KEPT is not None and not w.ended():
                _KEPT.append(w)  # for the next study of the run (kept_workers), and the writing of its outputs
            else:
                w.stop()


#: idle worker processes kept between the studies of one run (:func:`kept_workers`), else None
_KEPT: list | None = None
_KEPT_JOBS = 0
_KEPT_LAST = False  # the study running is the run's last one (:func:`last_study`)


@contextlib.contextmanager
def kept_workers(jobs: int):
    """Keep local worker processes between the studies run inside the block (they start once per run, not once per
    study: 0.4 s of imports a worker here); :func:`start_kept_workers` starts them early. They are stopped when the
    block ends, however it ends."""
    global _KEPT, _KEPT_JOBS, _KEPT_LAST
    _KEPT, _KEPT_JOBS, _KEPT_LAST = take_early(jobs), jobs, False
    try:
        yield
    finally:
        kept, _KEPT, _KEPT_JOBS, _KEPT_LAST = _KEPT, None, 0, False
        for w in kept:  # all told first, then waited for: they end side by side
            w.ask_to_stop()
        for w in kept:
            w.stop()


def last_study() -> None:
    """Inside :func:`kept_workers`: the study about to run is the run's last (:func:`workers_done`)."""
    global _KEPT_LAST
    if _KEPT is not None:
        _KEPT_LAST = True


def workers_done() -> None:
    """A study has no more work for the workers: after the run's last study they are told to end now, and end while
    the run writes the rest of its outputs (not after it)."""
    if _KEPT is not None and _KEPT_LAST:
        for w in _KEPT:
            w.ask_to_stop()


def start_kept_workers() -> None:
    """Inside :func:`kept_workers`: start the workers not started yet now, so that they import while the run prepares
    a study's rows (a study whose outputs are up to date needs none: call this once rows may run)."""
    if _KEPT is None or len(_KEPT) >= _KEPT_JOBS:
        return
    import multiprocessing as mp
    ctx = mp.get_context("spawn")
    with _one_blas_thread_per_worker(), _workers_ignore_ctrl_c():
        _KEPT.extend(_Worker(ctx) for _ in range(_KEPT_JOBS - len(_KEPT)))

