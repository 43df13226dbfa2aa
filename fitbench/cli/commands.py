"""The subcommands of ``fitbench`` (also ``python -m fitbench`` and ``python -m methods``): ``list``,
``fit METHOD_ID FILE`` and the machine-test subcommands (circular-test, positioning, magnify,
multilaterate, roundness), one argparse tree built by :func:`build_parser`.

Bad input ends with one line on stderr and exit status 2, never a traceback; warnings (a likely unit mix-up, a
swapped pair of runs, a nominal centre far from the data) are lines ``fitbench: warning: ...`` on stderr, printed
before the command's figures and written into its report and JSON (``warnings``). Units: every reader takes
``--unit`` (its file's length unit, default mm); options on the command line are in mm (lengths), mm/min (feed) and
degrees (angles); printed output is in µm, µrad and °; JSON in mm and rad with a ``units`` field. Subcommands are
one table (``SUBCOMMANDS``): adding one is a function ``add_NAME(sub)`` that builds its parser and sets ``func``.
Each subcommand lives in its own module, ``fitbench/cli/NAME.py`` with ``add_parser(sub)`` and ``run(args)``
(listing, fit, circular_test, positioning, magnify, multilaterate, roundness, history), which ``add_NAME`` imports
when the parser is built; this module holds the program around them (the parser, :func:`build_parser`,
:func:`main`, exit statuses, ``--json`` output, Ctrl-C), and :mod:`fitbench.cli.guards` what both use (one BLAS
thread, stdout to stderr, :func:`~fitbench.cli.guards.run_method`), below the subcommands so that the imports run
one way.
"""
from __future__ import annotations

import argparse
import sys
import warnings

import fitbench.cli.options as cli_options
from fitbench.streams import OutputError, readers_may_go
from methods import InvalidInputError
from fitbench.cli.options import version, warn
# the guards, and the names other modules and tests import from here
from fitbench.cli.guards import (MethodFailed, Terminated, commit_outputs, jsonable as _jsonable,  # noqa: F401
                                 one_blas_thread, run_method, staged_outputs, stdout_to_stderr, stopping_signals)

EXIT_BAD_INPUT = 2
#: the subcommands of ``fitbench`` that run the experiment modules (fitbench.cli.DELEGATED), absent from
#: ``python -m methods``
EXPERIMENT_SUBCOMMANDS = ("run", "report", "verify")
#: a method raised an exception of its own (a bug in the method, not bad input): one line, this status
EXIT_METHOD_FAILED = 3
#: Ctrl-C (SIGINT): 128 + 2, what a shell reports for a process SIGINT ended
EXIT_INTERRUPTED = 130


PROG = "python -m methods"


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2 (argparse prints usage over several lines)
        # the help of the (sub)command that refused: 'fitbench positioning --help' lists positioning's options
        raise InvalidInputError(f"{message} (see '{self.prog} --help')")

    def parse_args(self, args=None, namespace=None):
        """argparse's, with an option the subcommand does not know (``fitbench positioning x.csv --bogus``, which
        argparse reports from the top-level parser) pointing at that subcommand's help."""
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            chosen = self.subcommands.get(getattr(parsed, "command", None), self)
            chosen.error(f"unrecognized arguments: {' '.join(extras)}")
        return parsed

    #: the subcommands' parsers by name (:func:`build_parser` sets them)
    subcommands: dict = {}


# ----------------------------------------------------------------------------------------- the table
def add_list(sub):
    """The methods: fitbench/cli/listing.py."""
    from fitbench.cli import listing
    listing.add_parser(sub)


def add_fit(sub):
    """One method on a file: fitbench/cli/fit.py."""
    from fitbench.cli import fit
    fit.add_parser(sub)


def add_circular_test(sub):
    """ISO 230-4 circular test: fitbench/cli/circular_test.py."""
    from fitbench.cli import circular_test
    circular_test.add_parser(sub)


def add_positioning(sub):
    """ISO 230-2 positioning and compensation tables: fitbench/cli/positioning.py."""
    from fitbench.cli import positioning
    positioning.add_parser(sub)


def add_magnify(sub):
    """Magnified contouring errors: fitbench/cli/magnify.py."""
    from fitbench.cli import magnify
    magnify.add_parser(sub)


def add_multilaterate(sub):
    """Multilateration: fitbench/cli/multilaterate.py."""
    from fitbench.cli import multilaterate
    multilaterate.add_parser(sub)


def add_roundness(sub):
    """ISO 12181 roundness: the parser and command live in fitbench/cli/roundness.py."""
    from fitbench.cli import roundness
    roundness.add_parser(sub)


def add_history(sub):
    """The trend of a machine's tests: fitbench/cli/history.py."""
    from fitbench.cli import history
    history.add_parser(sub)


#: the subcommands: name -> function adding its parser (another module may add an entry)
SUBCOMMANDS = {"list": add_list, "fit": add_fit, "circular-test": add_circular_test, "positioning": add_positioning,
               "magnify": add_magnify, "multilaterate": add_multilaterate, "roundness": add_roundness,
               "history": add_history}


def build_parser(prog: str = PROG, extra_commands: dict | None = None) -> argparse.ArgumentParser:
    p = _Parser(prog=prog, description="fitbench: fitting methods of machine-tool metrology")
    p.add_argument("--version", action="version", version=f"fitbench {version()}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in SUBCOMMANDS.values():
        add(sub)
    for name, help_text in (extra_commands or {}).items():
        sub.add_parser(name, help=help_text, add_help=False)
    p.subcommands = dict(sub.choices)
    for action in sub.choices.values():
        action.add_argument("--version", action="version", version=f"fitbench {version()}",
                            help="print the version and exit") if "--version" not in action._option_string_actions else None
    return p


def _json_only(args) -> int:
    """Run a ``--json`` command with everything printed to stdout sent to stderr (:func:`stdout_to_stderr`: a
    plugin printing when it is imported, compiled code writing to descriptor 1) and print the command's JSON
    (:func:`fitbench.cli.options.print_json`) once stdout is restored: stdout carries the JSON object alone."""
    saved, cli_options.JSON_PENDING = cli_options.JSON_PENDING, []
    pending = cli_options.JSON_PENDING
    try:
        with stdout_to_stderr():
            code = args.func(args)
    finally:
        cli_options.JSON_PENDING = saved
    commit_outputs()   # the files the JSON lists are written before it is printed
    for text in pending:
        print(text)
    return code


def main(argv=None, prog: str = "fitbench", extra_commands: dict | None = None) -> int:
    """The command ``prog`` (``fitbench``, or ``python -m methods`` without the experiment subcommands): error
    and warning lines start with ``prog`` (:data:`fitbench.cli.options.PROGRAM`)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        with readers_may_go():   # `fitbench ... | head -1`: the command still ends, its files written, exit 0
            return _main(argv, prog, extra_commands)
    except OutputError as exc:   # `> /dev/full`: its staged output files are not written
        print(f"{prog}: error: cannot write {exc.filename}: {exc.strerror}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _main(argv, prog, extra_commands) -> int:
    saved = cli_options.PROGRAM, cli_options.CAUGHT, cli_options.SAID
    cli_options.PROGRAM = prog
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", category=UserWarning)
            # the warnings are printed as the command gives them and before its figures (the subcommand asks
            # cli_options.said_warnings() before it prints, writes its report or its JSON, which carry them);
            # what is left is printed when it ends
            cli_options.CAUGHT, cli_options.SAID = caught, []
            failed = None
            try:
                if argv and argv[0] in EXPERIMENT_SUBCOMMANDS and argv[0] not in (extra_commands or {}):
                    raise InvalidInputError(f"'{argv[0]}' is a subcommand of fitbench, not of {prog}: use "
                                            f"'fitbench {argv[0]} ...' or 'python -m experiments.{argv[0]} ...'")
                args = build_parser(prog, extra_commands).parse_args(argv)
                # the output files: written together at the end; SIGTERM and SIGHUP stop it as Ctrl-C does
                with one_blas_thread(), stopping_signals(), staged_outputs():
                    if not getattr(args, "json", False):
                        return args.func(args)
                    return _json_only(args)
            except InvalidInputError as exc:
                failed = str(exc)
                raise
            finally:
                from methods.units import UnitWarning
                for w in list(caught):
                    # an error naming the unit to give (--unit ...) says what a unit warning before it said
                    if issubclass(w.category, UserWarning) and not (
                            failed and issubclass(w.category, UnitWarning) and "--unit" in failed):
                        warn(str(w.message))
    except InvalidInputError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except MethodFailed as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return EXIT_METHOD_FAILED
    except BrokenPipeError as exc:   # not stdout's or stderr's reader (readers_may_go): a pipe the command wrote to
        print(f"{prog}: error: {exc.strerror or exc}; no output file was written", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Terminated as exc:   # SIGTERM, SIGHUP: as Ctrl-C, one line and the shell's status for the signal
        import signal
        print(f"{prog}: terminated ({signal.Signals(exc.signum).name})", file=sys.stderr)
        return 128 + exc.signum
    except KeyboardInterrupt:   # Ctrl-C: one line and the shell's status for SIGINT, as experiments.run ends
        print(f"\n{prog}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        cli_options.PROGRAM, cli_options.CAUGHT, cli_options.SAID = saved
