"""The ``fitbench`` command called in the test's process (its console script's entry point, ``fitbench.cli.main``;
another command's entry point by :func:`call`), and the check of a refusal: exit 2, one line on stderr, no traceback
(the project's rule for bad input)."""
from __future__ import annotations

import contextlib
import io
from typing import NamedTuple

from fitbench.cli import main


class Called(NamedTuple):
    """What a call of the command gave: its exit status and its two streams (unpacks as ``code, out, err``)."""

    returncode: int
    stdout: str
    stderr: str


def call(entry, *args) -> Called:
    """``entry([ARGS...])``, a command's entry point (each argument as ``str``), its stdout and stderr captured."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = entry([str(a) for a in args])
    return Called(code, out.getvalue(), err.getvalue())


def cli(*args) -> Called:
    """``fitbench ARGS...`` (each argument as ``str``), its stdout and stderr captured."""
    return call(main, *args)


def one_error_line(called: Called, *words, absent=()) -> None:
    """``called`` refused its input: exit 2, one line on stderr holding each of ``words`` and none of ``absent``,
    no traceback."""
    assert called.returncode == 2, (called.stdout, called.stderr)
    assert "Traceback" not in called.stderr and len(called.stderr.strip().splitlines()) == 1, called.stderr
    for w in words:
        assert w in called.stderr, called.stderr
    for w in absent:
        assert w not in called.stderr, called.stderr
