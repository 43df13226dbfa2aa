"""``python -m methods``: the ``fitbench`` command line (:mod:`fitbench.cli`), kept as an alias. A program,
not a module anything imports: the methods package itself imports no command-line code."""
import sys

from fitbench.cli.commands import main

sys.exit(main(prog="python -m methods"))
