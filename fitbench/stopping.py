"""Signals that stop a command (the standard library only, below every layer as :mod:`fitbench.streams`): SIGTERM (a
job scheduler's kill) and SIGHUP (a closed terminal) raised as an exception where the command is, as Ctrl-C raises
KeyboardInterrupt (:func:`stopping_signals`), so that its temporaries are removed on the way out and it ends with one
line and the shell's status for the signal; and a block that no stopping signal interrupts (:func:`_signals_held`
under :func:`stopping_signals`, :func:`signals_deferred` whatever the handlers), for moving outputs into place.
The ``fitbench`` subcommands (:mod:`fitbench.cli.guards`) and ``experiments.report`` / ``experiments.verify`` use
them."""
from __future__ import annotations

import contextlib
import os


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP (a job scheduler's kill, a closed terminal) while a command runs, taken as Ctrl-C is
    (:func:`stopping_signals`): ``signum``, the signal's number."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


#: the signals that stop a command as Ctrl-C does (its staged outputs removed on the way out)
STOPPING_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")
#: while outputs are moved into place or removed (:func:`_signals_held`): the stopping signals that arrived, else None
_HELD: list | None = None
#: the stopping signal that was raised as an exception in the running command (:func:`stopping_signals`), else None
_STOPPED_BY: int | None = None


def _interruption(signum: int) -> KeyboardInterrupt:
    import signal
    return KeyboardInterrupt() if signum == signal.SIGINT else Terminated(signum)


def _stop(signum, frame):
    global _STOPPED_BY
    if _HELD is not None:   # the outputs are being moved or removed: that ends first, then the command stops
        _HELD.append(signum)
        return
    _STOPPED_BY = signum
    raise _interruption(signum)


@contextlib.contextmanager
def stopping_signals():
    """Inside the block, SIGTERM and SIGHUP raise :class:`Terminated` where the command is, as SIGINT raises
    KeyboardInterrupt, so that the command removes its temporaries on the way out (the default action of both
    ends the process at once and left them in the user's folder); a signal arriving while the outputs are moved
    into place or removed (:func:`_signals_held`) waits until that is done. A signal the process ignores (``nohup``'s
    SIGHUP) or has its own handler for stays as it is; outside the main thread nothing changes (only it may set
    handlers)."""
    global _STOPPED_BY
    import signal
    import threading
    saved = {}
    if threading.current_thread() is threading.main_thread():
        for name in STOPPING_SIGNALS:
            num = getattr(signal, name, None)
            if num is not None and signal.getsignal(num) in (signal.SIG_DFL, signal.default_int_handler):
                saved[num] = signal.signal(num, _stop)
    stopped, _STOPPED_BY = _STOPPED_BY, None
    try:
        yield
    except Exception as exc:
        if _STOPPED_BY is None:
            raise
        # compiled code the signal's exception was raised in turned it into its own (matplotlib's renderer: a
        # ValueError 'Invalid bounding box'): the command was stopped all the same
        raise _interruption(_STOPPED_BY) from exc
    finally:
        _STOPPED_BY = stopped
        for num, old in saved.items():
            signal.signal(num, old)


@contextlib.contextmanager
def _signals_held():
    """Inside the block a stopping signal (:func:`stopping_signals`) is held; at its end it stops the command
    (unless the block failed: that failure is what the command reports)."""
    global _HELD
    saved, _HELD = _HELD, []
    try:
        yield
    finally:
        held, _HELD = _HELD, saved
    if held and saved is not None:
        saved.extend(held)
    elif held:
        _stop(held[0], None)


@contextlib.contextmanager
def signals_deferred():
    """Inside the block the stopping signals are blocked (``pthread_sigmask``, main thread, where the platform has it)
    and delivered at its end to whatever handler they have then (this module's, ``experiments.run``'s, the default):
    several files moved into place are all moved, whoever handles the signal."""
    import signal
    import threading
    nums = {getattr(signal, n) for n in STOPPING_SIGNALS if hasattr(signal, n)}
    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, nums)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def stopped_status(exc: KeyboardInterrupt) -> tuple[str, int]:
    """(what stopped the command, in words: ``interrupted`` or ``terminated (SIGTERM)``, and its exit status: 128 +
    the signal, as a shell reports a process the signal ended) of the KeyboardInterrupt that ended it: Ctrl-C, or one
    naming its signal in ``signum`` (:class:`Terminated`, ``experiments.rows.Terminated`` of a run's rows)."""
    import signal
    signum = getattr(exc, "signum", None)
    if not isinstance(signum, int) or signum == signal.SIGINT:
        return "interrupted", 128 + signal.SIGINT
    return f"terminated ({signal.Signals(signum).name})", 128 + signum


def quiet_while_starting(prog: str) -> None:
    """For ``python -m MODULE``, before the module imports what it needs: a stopping signal in that time ends the
    process with one line (``PROG: interrupted while starting; nothing was written``) and the shell's status, not a
    traceback from inside an import. :func:`started` gives the signals back to the command's own handling."""
    import signal

    def stopped(signum, frame):
        what = "interrupted" if signum == signal.SIGINT else f"terminated ({signal.Signals(signum).name})"
        os.write(2, f"\n{prog}: {what} while starting; nothing was written\n".encode())
        os._exit(128 + signum)
    for name in STOPPING_SIGNALS:
        num = getattr(signal, name, None)
        if num is not None and signal.getsignal(num) in (signal.SIG_DFL, signal.default_int_handler):
            signal.signal(num, stopped)


def started() -> None:
    """Undo :func:`quiet_while_starting`: Ctrl-C raises KeyboardInterrupt again, SIGTERM and SIGHUP have their default
    action (which :func:`stopping_signals` takes over); a signal the process ignored stays ignored."""
    import signal
    for name in STOPPING_SIGNALS:
        num = getattr(signal, name, None)
        if num is not None and getattr(signal.getsignal(num), "__qualname__", "").startswith("quiet_while_starting"):
            signal.signal(num, signal.default_int_handler if num == signal.SIGINT else signal.SIG_DFL)

