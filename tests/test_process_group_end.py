"""The run ends the process group a worker leads (what its methods started) without ever signalling a group by a
number that may have been given to another process: once the worker is reaped its id is free, and a SIGKILL to
``-pid`` would reach whatever group took that number (another run's worker leads one). The group is signalled through
a pidfd of the worker (Linux 6.9), or by its id only while the worker is not reaped."""
import contextlib
import errno
import os
import signal
import time

import pytest

from experiments import localworkers

pytestmark = pytest.mark.skipif(not hasattr(os, "killpg") or not hasattr(os, "waitid")
                                or not os.path.isdir("/proc"), reason="POSIX process groups, waitid, /proc")


def _group_pidfd() -> bool:
    """This kernel signals a process group through a pidfd (PIDFD_SIGNAL_PROCESS_GROUP, Linux 6.9)."""
    try:
        fd = os.pidfd_open(os.getpid())
    except (AttributeError, OSError):
        return False
    try:
        signal.pidfd_send_signal(fd, 0, None, 1 << 2)   # PIDFD_SIGNAL_PROCESS_GROUP, <linux/pidfd.h>
        return True
    except OSError as exc:   # ESRCH: this process leads no group (the flag is known); EINVAL: an unknown flag
        return exc.errno != errno.EINVAL
    finally:
        os.close(fd)


#: os.waitid as this system has it (a test takes it away from the run's code)
_WAITID = getattr(os, "waitid", None)


def _reaped(pid: int) -> bool:
    try:
        _WAITID(os.P_PID, pid, os.WEXITED | os.WNOHANG | os.WNOWAIT)
    except ChildProcessError:
        return True
    return False


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _ended(member: int) -> bool:
    """``member`` ends within 5 s."""
    deadline = time.monotonic() + 5
    while _alive(member) and time.monotonic() < deadline:
        time.sleep(0.01)
    return not _alive(member)


@pytest.fixture
def killpg_calls(monkeypatch):
    """os.killpg recorded with whether the group's leader (a child of this process) was reaped at the call; a call
    for a reaped leader is not made (its number may be another's)."""
    calls = []
    real = os.killpg

    def killpg(pgid, sig):
        reaped = _reaped(pgid)
        calls.append((pgid, reaped))
        if not reaped:
            real(pgid, sig)
    monkeypatch.setattr(os, "killpg", killpg)
    return calls


@pytest.fixture(params=["pidfd", "id"])
def how(request, monkeypatch):
    """The two ways a group is signalled: through the pidfd (where the kernel can), or by its id (an older kernel:
    pidfd_send_signal refuses the process-group flag with EINVAL)."""
    if request.param == "pidfd" and not _group_pidfd():
        pytest.skip("this kernel signals no process group through a pidfd (Linux < 6.9)")
    if request.param == "id":
        def refuse(*args):
            raise OSError(errno.EINVAL, "Invalid argument")
        monkeypatch.setattr(signal, "pidfd_send_signal", refuse, raising=False)
    return request.param


def _start_member(send, recv, tmp_path) -> int:
    """Ask a worker (its loop's call message) to leave a `sleep 60` in its process group; its id."""
    out = tmp_path / "member"
    send((localworkers._CALL, os.system, (f"sleep 60 </dev/null >/dev/null 2>&1 & echo $! > {out}",)))
    assert recv() == (True, 0)
    deadline = time.monotonic() + 5
    while not (out.exists() and out.read_text().strip()) and time.monotonic() < deadline:
        time.sleep(0.01)
    return int(out.read_text())


def _end_member(pid: int) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, signal.SIGKILL)


@contextlib.contextmanager
def _killed_leaving_a_member(process, tmp_path):
    """``process`` (a local worker or a Dask row process) made to leave a member in its group (:func:`_start_member`),
    then killed (SIGKILL); the member's id while in the block, the member killed after it."""
    member = _start_member(process.conn.send, process.conn.recv, tmp_path)
    try:
        os.kill(process.proc.pid, signal.SIGKILL)
        yield member
    finally:
        _end_member(member)


def test_a_local_worker_reaped_before_it_is_stopped(tmp_path, killpg_calls, how):
    """A worker that died is reaped (multiprocessing's join or is_alive) before the run stops it: its group is never
    signalled by its number then, and (pidfd) what its method left in it is still ended."""
    import multiprocessing as mp
    w = localworkers._Worker(mp.get_context("spawn"))
    with _killed_leaving_a_member(w, tmp_path) as member:
        deadline = time.monotonic() + 10
        while w.proc.is_alive() and time.monotonic() < deadline:   # reaps it: the worker's id is free from here
            time.sleep(0.01)
        assert _reaped(w.proc.pid)
        w.stop(now=True)
        assert not [c for c in killpg_calls if c[1]], f"a group signalled by the id of a reaped worker: {killpg_calls}"
        if how == "pidfd":
            assert _ended(member), "what the worker's method started outlived it"


def test_a_local_worker_that_died_ends_its_group_before_it_is_reaped(tmp_path, killpg_calls, how):
    """The run's path for a worker that died (ended, then stopped, then reaped): its group is ended either way, by
    its id only while the worker is not reaped."""
    import multiprocessing as mp
    w = localworkers._Worker(mp.get_context("spawn"))
    with _killed_leaving_a_member(w, tmp_path) as member:
        assert w.ended(10.0) and not _reaped(w.proc.pid)   # told without reaping it
        w.stop(now=True)
        assert _reaped(w.proc.pid)
        assert not [c for c in killpg_calls if c[1]], killpg_calls
        assert _ended(member), "what the worker's method started outlived it"


def test_a_dask_row_process_that_died_ends_its_group_before_it_is_reaped(tmp_path, killpg_calls, how):
    """A Dask worker's row process that died: its group is ended (by its id only while it is not reaped)."""
    from experiments.dask_executor import _RowProcess
    rp = _RowProcess()
    with _killed_leaving_a_member(rp, tmp_path) as member:
        assert rp._died()[0] == "died"
        assert rp.proc.returncode == -signal.SIGKILL
        assert not [c for c in killpg_calls if c[1]], killpg_calls
        assert _ended(member), "what the row process's method started outlived it"


def test_a_dead_worker_reaped_by_the_start_of_another_has_its_group_ended(tmp_path, killpg_calls, how):
    """multiprocessing's Process.start reaps every child that has ended: a worker that died while the run started
    another (the replacement of a worker that died in the same wait) was reaped before the run ended its group, and
    on a kernel without PIDFD_SIGNAL_PROCESS_GROUP what its method started lived on. A worker's start first ends the
    groups of the workers that have ended."""
    import multiprocessing as mp
    ctx = mp.get_context("spawn")
    w = localworkers._Worker(ctx)
    other = None
    with _killed_leaving_a_member(w, tmp_path) as member:
        try:
            assert w.ended(10.0) and not _reaped(w.proc.pid)
            other = localworkers._Worker(ctx)   # the replacement of another worker
            w.stop(now=True)
            assert not [c for c in killpg_calls if c[1]], killpg_calls
            assert _ended(member), "what the dead worker's method started outlived it"
            assert w.proc.exitcode == -signal.SIGKILL
        finally:
            if other is not None:
                other.stop(now=True)


@pytest.fixture
def no_waitid(monkeypatch):
    """A system without waitid (macOS before Python 3.13) and without a process group's pidfd."""
    def refuse(*args):
        raise OSError(errno.EINVAL, "Invalid argument")
    monkeypatch.setattr(signal, "pidfd_send_signal", refuse, raising=False)
    monkeypatch.delattr(os, "waitid")


def test_without_waitid_a_dead_workers_group_is_ended_before_it_is_reaped(tmp_path, killpg_calls, no_waitid):
    """Without waitid no worker's group was ever ended: the run now signals it while the worker's process object has
    not reaped it (the run finds a dead worker by its pipe, which reaps nothing)."""
    import multiprocessing as mp
    w = localworkers._Worker(mp.get_context("spawn"))
    with _killed_leaving_a_member(w, tmp_path) as member:
        assert w.conn.poll(10)
        with pytest.raises(EOFError):
            w.conn.recv()
        w.stop(now=True)
        assert _reaped(w.proc.pid) and w.proc.exitcode == -signal.SIGKILL
        assert killpg_calls and not [c for c in killpg_calls if c[1]], killpg_calls
        assert _ended(member), "what the dead worker's method started outlived it"


def test_without_waitid_a_dask_row_process_that_died_ends_its_group(tmp_path, killpg_calls, no_waitid):
    from experiments.dask_executor import _RowProcess
    rp = _RowProcess()
    with _killed_leaving_a_member(rp, tmp_path) as member:
        deadline = time.monotonic() + 10
        while not rp.conn.poll(0.05) and time.monotonic() < deadline:   # its socket closes: found without reaping
            pass
        assert rp._died()[0] == "died"
        assert rp.proc.returncode == -signal.SIGKILL
        assert killpg_calls and not [c for c in killpg_calls if c[1]], killpg_calls
        assert _ended(member), "what the row process's method started outlived it"
