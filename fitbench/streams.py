"""Standard streams, below every layer (the standard library only, as :mod:`fitbench.threads`): what a method prints
to stdout sent to stderr, for the command line (a ``--json`` command's output stays one JSON object) and for the
engine's rows (the run's stdout carries its own lines alone); and a command's standard streams kept writable once their
reader has gone (``fitbench positioning ... | head -1``), so the command still ends and writes its files."""
from __future__ import annotations

import contextlib
import io
import os
import sys


def _flush_c_stdio() -> None:
    """Flush the C library's stdio buffers (what compiled code printed with printf is still in them)."""
    try:
        import ctypes
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):
        pass   # no C library to reach (Windows): Python's prints are redirected all the same


@contextlib.contextmanager
def stdout_to_stderr():
    """Send what is printed to stdout to stderr inside the block: Python's prints (``sys.stdout``) and, when
    stdout is a real file descriptor, what compiled code writes to descriptor 1 (a Fortran or C solver's
    iteration log), whose C buffers are flushed before descriptor 1 is restored."""
    with contextlib.redirect_stdout(sys.stderr):
        try:
            out_fd, err_fd = sys.__stdout__.fileno(), sys.__stderr__.fileno()
        except (AttributeError, OSError, ValueError):
            out_fd = None
        if out_fd is None or out_fd == err_fd:
            yield
            return
        sys.__stdout__.flush()
        _flush_c_stdio()
        saved = os.dup(out_fd)
        try:
            os.dup2(err_fd, out_fd)
            yield
        finally:
            _flush_c_stdio()
            os.dup2(saved, out_fd)
            os.close(saved)


class _ReaderMayGo(io.TextIOWrapper):
    """A text stream on descriptor ``fd`` written to until its reader has gone (EPIPE: ``| head -1`` read what it
    wanted), then :data:`os.devnull` in its place (``os.dup2``: what is still buffered, compiled code's writes to the
    descriptor and the interpreter's flush at exit go nowhere), so a write never raises :class:`BrokenPipeError`.
    The layers below are the interpreter's own (compiled: a Ctrl-C arriving as a write returns cannot leave bytes
    already written in the buffer, to be written a second time; a raw layer in Python could)."""

    def __init__(self, fd: int, like):
        super().__init__(io.BufferedWriter(io.FileIO(fd, "w", closefd=False)), encoding=like.encoding,
                         errors=like.errors, line_buffering=like.line_buffering, write_through=like.write_through)
        self._fd = fd
        self.gone = False

    def _reader_gone(self) -> None:
        if not self.gone:
            self.gone = True
            _sink(self._fd)

    def write(self, s) -> int:
        try:
            return super().write(s)
        except BrokenPipeError:   # what is still buffered goes to the sink at the next flush
            self._reader_gone()
            return len(s)
        except OSError as exc:
            raise self._cannot_write(exc) from None

    def flush(self) -> None:
        try:
            super().flush()
        except BrokenPipeError:
            self._reader_gone()
            super().flush()
        except OSError as exc:
            raise self._cannot_write(exc) from None

    def _cannot_write(self, exc: OSError) -> "OutputError":
        """The descriptor refuses what is written (a full disk, ``> /dev/full``, an I/O error): not a reader that went.
        What is buffered goes to the sink (it cannot be written; the interpreter's flush at exit would fail again)
        and the caller is told (:class:`OutputError`)."""
        if not self.gone:
            self.gone = True
            _sink(self._fd)
            with contextlib.suppress(OSError):
                super().flush()
        return OutputError(exc.errno, exc.strerror or str(exc), f"standard {'output' if self._fd == 1 else 'error'}")


class OutputError(OSError):
    """Standard output or error could not be written (a full disk, ``> /dev/full``, an I/O error), unlike a reader
    that went (:func:`readers_may_go`): the command ends with one line and a non-zero status (``filename``: which
    stream)."""


def _sink(fd: int) -> None:
    """:data:`os.devnull` in place of descriptor ``fd``."""
    sink = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(sink, fd)
    finally:
        os.close(sink)


@contextlib.contextmanager
def readers_may_go():
    """Inside the block, ``sys.stdout`` and ``sys.stderr`` (when they are the process's own, on a descriptor) write
    through :class:`_ReaderMayGo`: a reader closing the pipe early (``| head -1``, ``2>&1 | head``) ends what the
    command prints, not the command (its computation and output files go on; Python would raise
    :class:`BrokenPipeError` at whichever print flushed next). The old streams are back when it ends. A stream that
    cannot be written for another reason (``> /dev/full``) raises :class:`OutputError` where it is written, or when
    the block ends."""
    swapped = []
    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if stream is None or stream is not getattr(sys, f"__{name}__"):
            continue   # already replaced (a test capturing it, a caller's redirection): left as it is
        try:
            fd = stream.fileno()
        except (AttributeError, OSError, ValueError):
            continue
        try:
            stream.flush()
        except BrokenPipeError:   # printed before and its reader gone already: that goes to the sink
            _sink(fd)
            stream.flush()
        guarded = _ReaderMayGo(fd, stream)
        setattr(sys, name, guarded)
        swapped.append((name, stream, guarded))
    failed = None
    try:
        yield
    finally:
        for name, stream, guarded in reversed(swapped):
            try:
                guarded.flush()
            except OutputError as exc:   # raised when the block ends (an exception of the block's own goes first)
                failed = failed or exc
            finally:
                setattr(sys, name, stream)
    if failed is not None:
        raise failed
