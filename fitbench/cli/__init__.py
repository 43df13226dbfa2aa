"""The ``fitbench`` command: ``fitbench SUBCOMMAND ...`` (also ``python -m fitbench``; ``python -m methods``
is the same command without the experiment subcommands).

``run``, ``report`` and ``verify`` hand their arguments to ``experiments.run.main``,
``experiments.report.main`` and ``experiments.verify.main`` (imported only when used, by module name);
every other subcommand is in :mod:`fitbench.cli.commands` (one argparse tree, :func:`build_parser`; each
subcommand in its own module, ``fitbench/cli/NAME.py``).
``--version`` works everywhere.

Folders not given on the command line are relative to the current directory, never inside the installed package:
``run`` writes ``results/`` (``results/quick/``, ``results/user/``), ``report`` reads ``results/`` and writes where
``python -m experiments.report`` does (``experiments.report.default_out``: ``paper/`` for ``results/``, else
``RESULTS/paper``).
"""
from __future__ import annotations

import importlib
import sys

from fitbench import __version__

#: folders a delegated subcommand gets relative to the current directory unless given: name -> [(option, folder)]
#: (``run`` chooses its own: results/, results/quick/ with --quick, results/user/ for a study not the project's;
#: ``report`` its --out from its --results, ``experiments.report.default_out``; all relative to the current directory)
CWD_DEFAULTS = {"report": [("--results", "results")]}

#: subcommands delegated to the experiment modules: name -> (module, one-line help)
DELEGATED = {"run": ("experiments.run", "run studies (python -m experiments.run)"),
             "report": ("experiments.report", "build the comparison report (python -m experiments.report)"),
             "verify": ("experiments.verify", "check results against another machine's (python -m experiments.verify)")}


def main(argv=None) -> int:
    """The ``fitbench`` command (``argv``: its arguments); Ctrl-C ends any subcommand with one line and status 130."""
    try:
        return _main(argv)
    except KeyboardInterrupt:
        print("\nfitbench: interrupted", file=sys.stderr)
        return 130


def _main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] in DELEGATED:
        name, rest = argv[0], argv[1:]
        if "--version" in rest:
            print(f"fitbench {__version__}")
            return 0
        module_name = DELEGATED[name][0]
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name and module_name.startswith(exc.name):
                print(f"fitbench: error: '{name}' is not available in this installation ({module_name} is missing)",
                      file=sys.stderr)
                return 2
            raise
        if not any(a in ("-h", "--help") for a in rest):
            for option, folder in CWD_DEFAULTS.get(name, []):
                if not any(a == option or a.startswith(option + "=") for a in rest):
                    rest = [*rest, option, folder]
        try:
            return int(module.main(rest, prog=f"fitbench {name}") or 0)   # its usage names what the user typed
        except SystemExit as exc:  # argparse's --help / errors inside the delegated module
            return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    from fitbench.cli.commands import main as commands_main
    return commands_main(argv, prog="fitbench", extra_commands={k: v[1] for k, v in DELEGATED.items()})


def build_parser(prog: str = "fitbench"):
    """The whole argparse tree of the ``fitbench`` command (the delegated subcommands as names only)."""
    from fitbench.cli.commands import build_parser as build
    return build(prog, extra_commands={k: v[1] for k, v in DELEGATED.items()})
