"""The guards a ``fitbench`` subcommand runs under (:func:`fitbench.cli.commands.main` sets them up; the subcommand
modules call :func:`run_method`): one BLAS/OpenMP thread, what is printed to stdout sent to stderr (a method's
prints, a ``--json`` command's stray output), a method's own exception turned into one line (:class:`MethodFailed`),
and results turned into JSON-ready values (:func:`jsonable`)."""
from __future__ import annotations

import contextlib

from fitbench.streams import stdout_to_stderr
from fitbench.threads import one_thread_environment
from methods import InvalidInputError, exception_call, exception_text


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


def jsonable(v):
    from methods.result_base import jsonable as j
    return j(v)
