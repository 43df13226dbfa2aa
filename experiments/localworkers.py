"""Local worker processes (one BLAS thread each, SIGINT ignored): started, told to stop, ended.

Light to import (the standard library and fitbench.threads): ``python -m experiments.run`` starts its workers with
:func:`start_early` before it imports its own modules (pandas, the report's code): on Linux as copies of the run made
once it has imported the rows' code (:mod:`experiments.chunkrows`), elsewhere spawned, importing it while the run
imports its own. Workers started later are spawned. :mod:`experiments.executors` runs chunks on them.
"""
from __future__ import annotations

import atexit
import contextlib
import errno
import functools
import os
import signal
import sys
import threading
import time
import weakref

from fitbench.threads import BLAS_THREAD_VARS, one_thread_environment  # noqa: F401 (BLAS_THREAD_VARS: re-exported)


@contextlib.contextmanager
def _one_blas_thread_per_worker():
    """Workers inherit the environment when they start (lazily, at the first submit): one BLAS thread each,
    unless the user chose otherwise (:func:`fitbench.threads.one_thread_environment`). With several workers,
    multi-threaded BLAS on small matrices oversubscribes the cores (the multilateration study ran 3x slower with
    2 workers x 2 OpenBLAS threads on 2 cores)."""
    with one_thread_environment():
        yield


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


@contextlib.contextmanager
def _main_module_not_imported_by_workers():
    """While a worker process is started: a spawned process imports the parent's ``__main__`` module first (under
    ``python -m experiments.run``, experiments.run with pandas, pydantic and the report's code: 0.6 s of CPU a
    worker here), which a worker never uses (it runs :func:`_worker_main`). An empty stand-in
    ``__main__`` (no name, no file) makes the start-up import nothing of it."""
    import types
    real = sys.modules.get("__main__")
    sys.modules["__main__"] = types.ModuleType("__main__")
    try:
        yield
    finally:
        if real is not None:
            sys.modules["__main__"] = real


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


def _lead_own_group() -> None:
    """Worker start: the worker leads a process group of its own (POSIX ``setpgid``), which the processes a method
    starts join (``subprocess.Popen``, ``multiprocessing``, ``os.fork``: a child is in its parent's group unless it
    leaves it), so that the run ends them with the worker (:func:`end_process_group`). Not through
    ``PR_SET_PDEATHSIG``: the kernel clears it in a forked child, and a method's child could not be asked to set it.
    A process that starts a session of its own (``start_new_session=True``, a daemon) leaves the group on purpose
    and is not ended. The worker is then outside the terminal's foreground group: Ctrl-C reaches the run alone
    (workers ignore it anyway: the run stops them), and the run's own end ends them (:func:`_die_with_parent`). A
    process of a background group that writes to the terminal under ``stty tostop`` (a method's or NumPy's warning) or
    reads from it is stopped by SIGTTOU/SIGTTIN, and its chunk would never return: the worker ignores both (a write
    then goes through, a read fails)."""
    if hasattr(os, "setpgid"):
        with contextlib.suppress(OSError):
            os.setpgid(0, 0)
        for name in ("SIGTTOU", "SIGTTIN"):
            if hasattr(signal, name):
                signal.signal(getattr(signal, name), signal.SIG_IGN)


#: pidfd_send_signal(2)'s flag that signals the process group of the pidfd's process (<linux/pidfd.h>, Linux 6.9)
_PIDFD_SIGNAL_PROCESS_GROUP = 1 << 2


class ProcessGroup:
    """The process group a child of this process leads (:func:`_lead_own_group`), ended by :meth:`end`. Made at once
    after the child's start, before this process can reap it. On Linux it holds a pidfd of the child (pidfd_open(2)),
    through which the group is signalled as an object (pidfd_send_signal(2), PIDFD_SIGNAL_PROCESS_GROUP, Linux 6.9):
    its members are ended even after the child was reaped, and never a group that was given the same id after the
    child was reaped and its members had ended. Where that is not available (an older kernel, another POSIX system)
    the group is signalled by its id (killpg(2)) only while the child is known unreaped (waitid(2) with ``WNOWAIT``:
    until it is reaped the id is the child's; where waitid is missing, ``reaped()``, the record of the object that
    reaps the child in this process, multiprocessing's or subprocess's); after that, what is left of its group is not
    ended. Residual there: a thread of this process reaping the child between that check and the signal (the run
    does not: a worker is stopped and reaped by the thread that owns it), and, without a pidfd, a new child of this
    process given the reaped child's id meanwhile."""

    def __init__(self, pid: int | None, reaped=None):
        self.pid = pid
        self._fd = None
        self._reaped = reaped
        if pid is not None and hasattr(os, "pidfd_open"):
            with contextlib.suppress(OSError):
                self._fd = os.pidfd_open(pid)

    def _leader_unreaped(self) -> bool:
        if not _has_waitid():   # only what reaps it here knows (macOS before Python 3.13 has no waitid)
            return self._reaped is not None and not self._reaped()
        if self._fd is not None and hasattr(os, "P_PIDFD"):
            idtype, ident = os.P_PIDFD, self._fd
        else:
            idtype, ident = os.P_PID, self.pid
        try:
            os.waitid(idtype, ident, os.WEXITED | os.WNOHANG | os.WNOWAIT)
        except OSError:   # ECHILD: reaped (or never a child of this process)
            return False
        return True

    def end(self) -> None:
        """SIGKILL to the group (the child and what its methods started that is still in it); nothing if the group
        cannot be told from a group that reused its id (see the class)."""
        if self.pid is None:
            return
        if self._fd is not None and hasattr(signal, "pidfd_send_signal"):
            try:
                signal.pidfd_send_signal(self._fd, signal.SIGKILL, None, _PIDFD_SIGNAL_PROCESS_GROUP)
                return
            except OSError as exc:
                if exc.errno != errno.EINVAL:   # ESRCH: no member left (or the group was never made)
                    return
        if hasattr(os, "killpg") and self._leader_unreaped():
            with contextlib.suppress(OSError):   # ESRCH: no such group (the child never made it)
                os.killpg(self.pid, signal.SIGKILL)

    def close(self) -> None:
        """Release the pidfd (the group can no longer be ended through this object)."""
        fd, self._fd = self._fd, None
        if fd is not None:
            with contextlib.suppress(OSError):
                os.close(fd)

    def __del__(self):
        self.close()


def end_process_group(group: ProcessGroup | None) -> None:
    """SIGKILL to the process group a child leads (:class:`ProcessGroup`; None: nothing)."""
    if group is not None:
        group.end()


def _has_waitid() -> bool:
    """This system tells a child that has ended without reaping it (waitid(2) with ``WNOWAIT``)."""
    return hasattr(os, "waitid") and hasattr(os, "WNOWAIT")


def _exit_state(pid: int, timeout: float) -> bool | None:
    """Wait up to ``timeout`` seconds for child ``pid`` to end without reaping it (``waitid`` with ``WNOWAIT``): True
    if it has ended (its id stays its own until it is reaped), False if it still runs, None if it was reaped already
    or this cannot be known here (no ``waitid``)."""
    if not _has_waitid():
        return None
    deadline = time.monotonic() + timeout
    while True:
        try:
            if os.waitid(os.P_PID, pid, os.WEXITED | os.WNOHANG | os.WNOWAIT) is not None:
                return True
        except ChildProcessError:   # reaped already (by multiprocessing's join or is_alive)
            return None
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.002)


_CALL = "call"  # the first item of a message that asks a worker for func(*args), not for rows


def _worker_main(conn, parent_pid: int, progress) -> None:
    """A local worker: receive chunks, send back their rows as columns, until told to stop."""
    _die_with_parent(parent_pid)  # first: a run killed while this worker imports takes it along
    for name in ("SIGTERM", "SIGHUP"):   # a copy of a starting run has its handlers: a worker's are the defaults
        sig = getattr(signal, name, None)
        if sig is not None and callable(signal.getsignal(sig)):
            signal.signal(sig, signal.SIG_DFL)
    _lead_own_group()  # what a method starts is in the worker's group, ended with it (_Worker.stop)
    with contextlib.suppress(OSError, ValueError):  # a method's prints (print, os.write(1, ...), a solver's printf, a
        os.dup2(2, 1)   # process it starts) go to the run's stderr: its stdout carries the run's own lines alone
    # the pipe to the run is this process's alone: a process a method starts (os.system's shell) inherited it (it came
    # through fd passing, inheritable) and kept it open after the worker died, so the run did not see the death
    with contextlib.suppress(OSError, AttributeError):
        os.set_inheritable(conn.fileno(), False)
    import warnings

    from methods.plugins import PluginLoadWarning
    # a plugin that fails to load is reported once, by the run (which loads the plugins before any row): a worker,
    # started perhaps before the run found it, loads the same plugins again and says nothing of it
    warnings.simplefilter("ignore", PluginLoadWarning)
    import gc

    from experiments.chunkrows import mark_row_worker, run_chunk  # the rows' code: imported here, in the worker
    from experiments.rows import ROW_GC_THRESHOLD
    mark_row_worker()
    from methods import exception_text
    gc.set_threshold(ROW_GC_THRESHOLD, *gc.get_threshold()[1:])  # a worker only makes rows (experiments.rows)
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):
            return
        if msg is None:  # the run needs no more rows: end at once (the interpreter's own finalisation of NumPy,
            exit_now(0)   # SciPy and the methods took 0.25 s a worker, in the run's last moments)
        if msg[0] == _CALL:  # a piece of the run's own work (map_in_idle_workers)
            _, func, args = msg
            try:
                conn.send((True, func(*args)))
            except Exception as exc:
                conn.send((False, exception_text(exc)))
            continue
        chunk_id, tasks, row_timeout = msg
        try:
            out = run_chunk(tasks, row_timeout, progress)
        except BaseException as exc:  # a failure of the engine itself: reported, the chunk is retried alone
            out = {"failed": exception_text(exc)}
        progress[0] = 0.0
        conn.send((chunk_id, out))


def exit_now(status: int = 0, *, as_python_does: bool = False):
    """End this process now with ``status``: what it printed is flushed; ``as_python_does``: first, as the interpreter
    does at exit, its other (non-daemon) threads are waited for and the functions registered with :mod:`atexit` run
    (logging's, multiprocessing's, a plugin's). What is skipped is the interpreter's teardown of every module and
    object: 0.25-0.3 s in a process that loaded NumPy, SciPy and the methods, more with pandas and matplotlib, paid
    after the command's work is done (its files are written and closed by then)."""
    if as_python_does:
        for thread in threading.enumerate():
            if thread is not threading.current_thread() and not thread.daemon:
                thread.join()
        atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(status)


def _mp_reaped(proc) -> bool:
    """Whether multiprocessing has reaped ``proc`` (a started Process), asked without reaping it: its Popen records the
    exit status in ``returncode`` when it reaps the child (CPython's multiprocessing/popen_fork.py; ``exitcode`` and
    ``is_alive`` reap it first). Used only where waitid(2) is missing; an object without that record counts as reaped
    (its group is then not signalled by its id)."""
    popen = getattr(proc, "_popen", None)
    return popen is None or getattr(popen, "returncode", 0) is not None


#: the workers this process started and has not stopped (:func:`_end_groups_of_ended_workers`)
_STARTED: weakref.WeakSet = weakref.WeakSet()


def _end_groups_of_ended_workers() -> None:
    """End the process group of every worker of this process that has ended and is not reaped yet. Called before a
    process is started: ``multiprocessing.Process.start`` reaps every child of this process that has ended
    (``multiprocessing.process._cleanup``), and a worker reaped that way could have its group signalled only through a
    pidfd (Linux 6.9); on an older kernel what its methods started would outlive it (:class:`ProcessGroup`). Residual:
    a worker ending between this look and the start."""
    for worker in list(_STARTED):
        if worker._exit_state(0) is True:
            worker.group.end()


class _Worker:
    def __init__(self, ctx):
        self.conn, child = ctx.Pipe()
        self.progress = ctx.RawArray("d", 2)
        self.proc = ctx.Process(target=_worker_main, args=(child, os.getpid(), self.progress), daemon=True,
                                name="fitbench-worker")
        _end_groups_of_ended_workers()   # the start below reaps the workers that have ended
        with _main_module_not_imported_by_workers():
            self.proc.start()
        self.group = ProcessGroup(self.proc.pid, reaped=functools.partial(_mp_reaped, self.proc))   # at once
        _STARTED.add(self)
        child.close()
        self.chunk = None
        self.chunk_id = None
        self.stopping = False
        self.noticed = None  # (chunk id, position) of the row last named as running long

    def send(self, chunk_id: int, chunk: list, row_timeout) -> None:
        self.chunk, self.chunk_id = chunk, chunk_id
        self.progress[0] = 0.0
        self.conn.send((chunk_id, chunk, row_timeout))

    def _exit_state(self, timeout: float) -> bool | None:
        """:func:`_exit_state` of the worker; without waitid its pipe sentinel tells (it is ready once the worker has
        ended; waiting on it reaps nothing) while multiprocessing has not reaped it."""
        if _has_waitid():
            return _exit_state(self.proc.pid, timeout)
        if _mp_reaped(self.proc):
            return None
        from multiprocessing.connection import wait
        return bool(wait([self.proc.sentinel], timeout))

    def ended(self, timeout: float = 0) -> bool:
        """The worker's process has ended (waited for up to ``timeout`` s), told without reaping it where the system
        can (``is_alive`` and ``join`` reap it): its process group is then still ended safely by :meth:`stop`."""
        state = self._exit_state(timeout)
        if state is None:   # reaped already: multiprocessing knows
            self.proc.join(timeout)
            return not self.proc.is_alive()
        return state

    def ask_to_stop(self) -> None:
        """Tell the worker to end once it is idle, without waiting for it (:meth:`stop` then waits)."""
        if not self.stopping:
            self.stopping = True
            with contextlib.suppress(Exception):
                self.conn.send(None)

    def stop(self, now: bool = False) -> None:
        """End the worker (``now``: killed, else told to end and waited for up to 5 s, then killed) and its process
        group with it: what a method started in the worker does not outlive it (:func:`_lead_own_group`)."""
        if now:
            self.group.end()   # the worker leads it: one signal ends the worker and its children
            with contextlib.suppress(Exception):
                self.proc.kill()
        else:
            self.ask_to_stop()
            if self._exit_state(5.0) is not True:
                with contextlib.suppress(Exception):
                    self.proc.kill()
                self._exit_state(5.0)
            self.group.end()
        self.proc.join(timeout=5)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join(timeout=5)
        self.group.close()
        _STARTED.discard(self)
        with contextlib.suppress(Exception):
            self.conn.close()


#: workers started by :func:`start_early`, until the run takes them (:func:`take_early`)
_EARLY: list = []


def start_early(argv: list[str]) -> None:
    """Start the local workers of ``python -m experiments.run ARGV`` now, before the run imports its own modules, when
    the arguments clearly ask for them: ``--jobs N`` above 1 (or its default on a machine of several cores) on the
    local executor, and rows that will run (``--force``, or an ``--out`` folder that does not exist yet: a run into a
    folder with results first finds out which of its studies are up to date, and starts workers only then). Anything
    else (an option this cannot read, ``--help``) starts nothing: the run decides as it always does."""
    try:
        import argparse
        parser = argparse.ArgumentParser(add_help=False)
        parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1))
        parser.add_argument("--executor", default="local")
        parser.add_argument("--scheduler")
        parser.add_argument("--out")
        parser.add_argument("--force", action="store_true")
        parser.add_argument("--list", action="store_true")
        parser.add_argument("-h", "--help", "--version", dest="other", action="store_true")
        args, _ = parser.parse_known_args(argv)
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        jobs = min(args.jobs, cores)
        if (jobs < 2 or args.executor != "local" or args.scheduler or args.list or args.other or
                not (args.force or (args.out and not os.path.exists(args.out)))):
            return
    except (SystemExit, Exception):  # an argument this cannot read: the run's own parser says what is wrong
        return
    with _one_blas_thread_per_worker():
        ctx = _forking_context()
        with _workers_ignore_ctrl_c():
            _EARLY.extend(_Worker(ctx) for _ in range(jobs))


def _forking_context():
    """The start method of the workers :func:`start_early` starts. On Linux: ``fork``, after this process imported the
    rows' code (which it needs too): the workers are copies of it, ready at once, instead of each importing NumPy, the
    methods, the data sources and pandas again (0.6 s of CPU a worker, while this process imports its own modules on
    the same cores). This process has no other thread yet (the command calls this first), so the copies hold no lock another
    thread took; the BLAS libraries load here with one thread (:func:`_one_blas_thread_per_worker`, around the call),
    as a spawned worker's would. Elsewhere (macOS: fork is unsafe with its system libraries), and for workers started
    later (the run has threads then), ``spawn``."""
    import multiprocessing as mp
    if not sys.platform.startswith("linux") or threading.active_count() > 1 or "fork" not in mp.get_all_start_methods():
        return mp.get_context("spawn")
    import experiments.chunkrows  # noqa: F401 (the rows' code, imported once here for every worker)
    import experiments.rows  # noqa: F401
    import methods.plugins  # noqa: F401
    import pandas  # noqa: F401 (a chunk's columns, experiments.rowframe.part_of: the run imports it anyway; each
    # worker imported it again on its first chunk, 0.27 s of CPU a worker while the run imports its own modules)
    for stream in (sys.stdout, sys.stderr):  # nothing buffered here is written again by a copy
        with contextlib.suppress(Exception):
            stream.flush()
    return mp.get_context("fork")


def take_early(jobs: int) -> list:
    """The workers :func:`start_early` started (at most ``jobs``; any beyond are ended), now the caller's."""
    taken, extra = _EARLY[:jobs], _EARLY[jobs:]
    _EARLY.clear()
    for w in extra:
        w.stop(now=True)
    return taken
