"""The guards a ``fitbench`` subcommand runs under (:func:`fitbench.cli.commands.main` sets them up; the subcommand
modules call :func:`run_method`): one BLAS/OpenMP thread, what is printed to stdout sent to stderr (a method's
prints, a ``--json`` command's stray output), a method's own exception turned into one line (:class:`MethodFailed`),
the output files checked before anything is computed (:func:`check_outputs`: none may be an input or another
output) and written together when the command has ended (:func:`staged_outputs`; SIGTERM and SIGHUP stop it as
Ctrl-C does: :func:`fitbench.stopping.stopping_signals`), and results turned into JSON-ready values
(:func:`jsonable`)."""
from __future__ import annotations

import contextlib
import os
from pathlib import Path

from fitbench.stopping import STOPPING_SIGNALS, Terminated, _signals_held, _stop, stopping_signals  # noqa: F401
from fitbench.streams import stdout_to_stderr
from fitbench.threads import one_thread_environment
from methods import InvalidInputError, exception_call, exception_text
from methods.files import StagedFiles, atomic_path, writable_target


class MethodFailed(Exception):
    """A method raised an exception other than :class:`~methods.InvalidInputError` (its own bug, e.g. a
    plugin writing into its read-only input): printed as one line, exit status
    :data:`fitbench.cli.commands.EXIT_METHOD_FAILED`."""


#: the variables BLAS and OpenMP libraries read their thread count from when they load (as the engine's workers)
@contextlib.contextmanager
def one_blas_thread():
    """One BLAS/OpenMP thread while a subcommand computes, unless the user chose a count
    (:func:`fitbench.threads.one_thread_environment`): libraries loaded already are limited through threadpoolctl;
    those loaded during the command (SciPy's OpenBLAS) read the variables, set to 1 in the block (docs/cli.md: the
    figures)."""
    with one_thread_environment() as chosen:
        if chosen:
            yield
        else:
            from threadpoolctl import threadpool_limits
            with threadpool_limits(limits=1):
                yield




def run_method(spec, data, **params):
    """``spec.checked(data, **params)`` (the result gate for every method, a built-in's too) with the method's prints
    sent to stderr (stdout carries the command's output alone: ``--json`` stays one JSON object) and its own exceptions
    turned into one line naming it (:class:`MethodFailed`); bad input (:class:`~methods.InvalidInputError`, the
    result gate's refusal) passes."""
    try:
        with stdout_to_stderr():
            return spec.checked(data, **params)
    except InvalidInputError as exc:   # bad input, said by the method: its message is the line (if it can be printed)
        try:
            str(exc)
        except KeyboardInterrupt:
            raise
        except BaseException:
            raise MethodFailed(f"{spec.id} failed: {' '.join(exception_text(exc).split())[:300]} (an error inside the "
                               f"method (module {spec.module}): report it to its author)") from None
        raise
    except KeyboardInterrupt:   # Ctrl-C: the command's own line and status
        raise
    except BaseException as exc:   # a method's sys.exit() is no success (nor a silent end); a plugin's own
        # BaseException subclass and an exception whose str() raises are the method's failure too, named by their type
        hint = ("a bug in fitbench: please report it" if spec.builtin else
                f"an error inside the method (module {spec.module}), not in the data: report it to its author")
        if isinstance(exc, Exception):
            what = " ".join(exception_text(exc).split())
            if isinstance(exc, ValueError) and "read-only" in what:
                hint += "; a method gets read-only points and must copy them (points.copy()) before writing"
            what = what[:300]
        else:
            what = f"it raised {' '.join(exception_call(exc).split())[:300]}"
        raise MethodFailed(f"{spec.id} failed: {what} ({hint})") from None


# ------------------------------------------------------------------------------------------ output files
class Outputs:
    """The files the running command writes: each declared by :func:`check_outputs` (option, path, what it is)
    and written to a temporary (:class:`methods.files.StagedFiles`) that :func:`staged_outputs` moves into place
    when the command has ended without error."""

    def __init__(self):
        self.files = StagedFiles()
        self.declared: list[tuple[str, str, str]] = []
        self.said: list[tuple[str, str]] = []   # (path, its "... written to PATH" line): :func:`say_written`


#: the running command's :class:`Outputs` (:func:`staged_outputs` sets it, None outside a command: written at once)
OUTPUTS: Outputs | None = None


def _same_file(a, b) -> bool:
    """``a`` and ``b`` name one file: :func:`os.path.samefile` when both exist (a symlink, a hard link, ``./x``
    and ``x``), else their resolved paths are equal (an output not written yet)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def check_outputs(inputs, outputs) -> None:
    """Refuse, before anything is computed or written, an output that is one of the command's ``inputs`` (the
    files it reads; None skipped) or that another output names too (a symlink, a hard link or another spelling
    included), a special file (:func:`methods.files.writable_target`) or a file in a missing folder.
    ``outputs``: (option as typed, path or None, what the file is) of each output file; the written ones are
    listed by :func:`written_files`."""
    inputs = [i for i in inputs if i is not None]
    seen = []
    for option, path, what in outputs:
        if path is None:
            continue
        for i in inputs:
            if _same_file(path, i):
                via = "" if str(path) == str(i) else f" ({i}, the same file by another name)"
                raise InvalidInputError(f"{option} {path}: this is the command's input file{via}; writing the {what} "
                                        "there would destroy the data read: give the output another file name")
        for other_option, other in seen:
            if _same_file(path, other):
                via = "" if str(path) == str(other) else " (by two names)"
                raise InvalidInputError(f"{other_option} {other} and {option} {path} name the same file{via}: the "
                                        "second would overwrite the first; give each output its own file name")
        target = writable_target(path)   # a FIFO, a device, a folder: refused now
        parent = target.parent if str(target.parent) else Path(".")
        if not parent.is_dir():
            raise InvalidInputError(f"{option} {path}: the folder {parent} does not exist; create it first")
        seen.append((option, path))
        if OUTPUTS is not None:
            OUTPUTS.declared.append((option, str(path), what))


@contextlib.contextmanager
def output_path(path):
    """``with output_path(p) as tmp:`` write output ``p`` to ``tmp``: staged until the running command ends
    (:func:`staged_outputs`), else :func:`methods.files.atomic_path`."""
    if OUTPUTS is None:
        with atomic_path(path) as tmp:
            yield tmp
    else:
        with contextlib.ExitStack() as stack:
            with _signals_held():   # the temporary is made and known to OUTPUTS before a signal can stop the command
                tmp = stack.enter_context(OUTPUTS.files.path(path))
            yield tmp


def written_files() -> list[dict]:
    """The running command's output files written so far (``path``, ``option``, ``what``), for its JSON: they
    are on disk once it has printed it (:func:`commit_outputs`)."""
    if OUTPUTS is None:
        return []
    staged = [os.path.realpath(p) for p in OUTPUTS.files.pending() + OUTPUTS.files.written]
    return [{"path": path, "option": option, "what": what} for option, path, what in OUTPUTS.declared
            if os.path.realpath(path) in staged]


def say_written(path, line: str) -> None:
    """Print ``line`` (``... written to PATH``) once ``path`` is on disk: at once outside a command, else when the
    command's outputs have moved into place (:func:`staged_outputs`), and only if ``path`` has: stdout never says
    a file was written that a failure then left as it was."""
    if OUTPUTS is None:
        print(line)
    else:
        OUTPUTS.said.append((str(path), line))


def commit_outputs() -> None:
    """Move the running command's outputs into place (all written); a failure is one line saying which were
    written and which not."""
    if OUTPUTS is None:
        return
    files = OUTPUTS.files
    try:
        with _signals_held():   # all moved into place or none, whenever a signal comes
            files.commit()
    except OSError as exc:
        left = files.pending()
        files.discard()
        raise InvalidInputError(f"cannot write {exc.filename}: {exc.strerror or exc}; "
                                + (f"written: {', '.join(files.written)}; " if files.written else "")
                                + f"not written: {', '.join(left)}") from None


@contextlib.contextmanager
def staged_outputs():
    """Run a command with its output files staged (:data:`OUTPUTS`): they replace their targets only when it ends
    without an error, all together (:func:`commit_outputs`); an error leaves every target as it was and says
    which files were not written."""
    global OUTPUTS
    saved, OUTPUTS = OUTPUTS, Outputs()
    outputs = OUTPUTS
    try:
        yield outputs
        commit_outputs()
    except InvalidInputError as exc:
        left = outputs.files.pending()
        if not left:
            raise
        raise InvalidInputError(f"{exc}; not written: {', '.join(left)}") from None
    finally:
        try:
            done = {os.path.realpath(p) for p in outputs.files.written}
            for path, line in outputs.said:
                if os.path.realpath(path) in done:
                    print(line)
            with _signals_held():
                outputs.files.discard()
        finally:
            OUTPUTS = saved


def jsonable(v):
    from methods.result_base import jsonable as j
    return j(v)
