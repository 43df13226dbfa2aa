"""Standard streams, below every layer (the standard library only, as :mod:`fitbench.threads`): what a method prints
to stdout sent to stderr, for the command line (a ``--json`` command's output stays one JSON object) and for the
engine's rows (the run's stdout carries its own lines alone)."""
from __future__ import annotations

import contextlib
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
