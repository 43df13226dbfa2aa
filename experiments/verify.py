"""``python -m experiments.verify [STUDY ...] [--results DIR] [--against DIR] [--quick] [--jobs N] [--write-verdict]``

Reproducibility verdict: runs the studies (into a temporary folder) or reads a finished run (``--against``)
and compares every non-timing column of each ``results.csv`` with the committed one (``--results``; default
``results/``, or ``results/quick`` with ``--quick``), with the tolerances declared with the metrics
(``experiments.metrics.TOLERANCES``: exact for ids, statuses and counts; relative + absolute per metric).
A study that is not one of the project's (a user's TOML) runs from the TOML file its ``meta.json`` records
(``config_file``), or from the TOML given as STUDY.
Rows are matched by their identity (study, data set, data stream, repetition, seed, method, parameters).
A row with the same status other than "ok" in both runs (an iteration that did not converge) is compared by
its status and counts only: its values are where the iteration stopped, not a result. When the two runs used
other kernel backends (``meta.json``: compiled, or ``FITBENCH_KERNELS=numpy``), an iterative method's statuses and
counts, and the values of a row whose status differs, are listed apart as what the backend explains.

Prints one line per study and a table of the columns outside tolerance with their worst rows. A check modifies
neither folder: only with ``--write-verdict`` is the verdict recorded (atomically) in ``RESULTS/verify.json``,
the file the report of RESULTS shows (:func:`last_verdict` reads it; ``python -m experiments.run`` records
its own verdict in ``OUT/verify.json``).
The comparison itself is :mod:`experiments.compare` (the end of ``python -m experiments.run`` uses it too).
Exit status: 0 all agree, 1 some values differ, 2 bad input (missing folder or study, unreadable table), 130 / 143 /
129 stopped by Ctrl-C / SIGTERM / SIGHUP (one line, no verdict written).
"""
from __future__ import annotations

if __name__ == "__main__":   # Ctrl-C, SIGTERM, SIGHUP while the command imports its modules: one line, no traceback
    from fitbench.stopping import quiet_while_starting
    quiet_while_starting("experiments.verify")

import argparse
import sys
import tempfile
from pathlib import Path

from experiments import config as configs
from experiments import run as runner
from experiments.jsontext import json_value
from experiments.compare import (IDENTITY, WORST_ROWS, compare_study, identity_columns,  # noqa: F401  (the library's names)
                                 reference_snapshot, verdict_after_run, verify)
from experiments.verdict import VERDICT_FILE, last_verdict, results_sha256, verdict_markdown  # noqa: F401  (the report's reading side)
from experiments.verdict import is_project_study, recorded_config
from experiments.rows import clear_signal
from fitbench import __version__
from fitbench.stopping import stopped_status
from methods import InvalidInputError


def config_of(study: str, results: Path, known: dict) -> str:
    """What to run to check ``study`` of ``results``: a project study by its name; any other (also one named like a
    project study: :func:`experiments.verdict.is_project_study` decides by the TOML its ``meta.json`` records) by
    that TOML file (``config_file``), refused in one line when that file is not there."""
    if is_project_study(results / study, known):
        return study
    recorded = recorded_config(results / study)
    if recorded is None or not recorded.is_file():
        who = (f"{study} in {results} ran from another TOML than the project's study of that name" if study in known
               else f"{study} is not one of the project's studies")
        where = (f"its meta.json records {recorded}, which is not there" if recorded is not None else
                 "its meta.json records no TOML file (written by an older fitbench)")
        raise InvalidInputError(f"{who} and {where}; give its TOML file: "
                                f"python -m experiments.verify PATH/{study}.toml --results {results}")
    return str(recorded)


def main(argv=None, prog: str = "python -m experiments.verify") -> int:
    """The command; a plugin that fails to load is reported in one line, once, as by ``experiments.run``. A reader
    of its output that goes (``| head -1``) ends what it prints, not the check (:func:`fitbench.streams.readers_may_go`:
    the verdict is still written with ``--write-verdict``, exit status as the verdict); Ctrl-C, SIGTERM and SIGHUP
    stop it as they stop a run (``experiments.run``'s handlers: the studies it runs stop between rows) with one line
    and 128 + the signal, the temporary run removed."""
    from fitbench.streams import OutputError, readers_may_go
    try:
        with readers_may_go(), runner.plugin_warnings_once():
            clear_signal()   # a new check in this process: no interrupt received yet
            with runner._interrupts_are_the_run_s():
                return _main(argv, prog)
    except OutputError as exc:   # `> /dev/full`: the verdict is not told, so the check does not pass
        print(f"experiments.verify: error: cannot write {exc.filename}: {exc.strerror}", file=sys.stderr)
        return 2


def _main(argv, prog: str) -> int:
    parser = argparse.ArgumentParser(prog=prog,
                                     description="Check that a run reproduces the committed results within declared tolerances.")
    parser.add_argument("--version", action="version", version=f"%(prog)s (fitbench {__version__})")
    parser.add_argument("studies", nargs="*", metavar="STUDY",
                        help="studies to check, by name or TOML file (default: every study in --results; a study that "
                             "is not one of the project's runs from the TOML its meta.json records)")
    parser.add_argument("--results", type=Path, help="committed results (default: results/, or results/quick with --quick)")
    parser.add_argument("--against", type=Path, help="a finished run to check (default: run the studies now, in a temporary folder)")
    parser.add_argument("--quick", action="store_true", help="the quick grids (compared with results/quick)")
    parser.add_argument("--jobs", type=int, default=2, help="workers when the studies are run (default: 2)")
    parser.add_argument("--write-verdict", action="store_true",
                        help="record the verdict in RESULTS/verify.json, which the report of RESULTS shows "
                             "(default: print it, write nothing)")
    args = parser.parse_args(argv)
    results = args.results or (Path("results/quick") if args.quick else Path("results"))
    verdict_before = _stat(results / VERDICT_FILE)
    try:
        if not results.is_dir():
            raise InvalidInputError(f"--results {results} is not a folder of committed results"
                                    + (" (the quick results are generated with python -m experiments.run --quick "
                                       "--out results/quick and committed)" if args.quick else ""))
        if args.against is not None and not args.against.is_dir():
            raise InvalidInputError(f"--against {args.against} is not a folder of results")
        present = sorted(p.parent.name for p in results.glob("*/results.csv"))
        known = configs.available()
        named = {}   # a study given as its TOML file (a user's study): its name -> that file
        for s in args.studies:
            if s.endswith(".toml"):
                named[configs.load(s)["name"]] = s
        for s in args.studies:   # a name that is neither a study here nor a known one: never "run it first"
            if not s.endswith(".toml") and s not in present and s not in known:
                raise InvalidInputError(f"unknown study {s!r}: --results {results} holds "
                                        f"{', '.join(present) or 'no study'}; the known studies are {', '.join(known)}")
        studies = [configs.load(s)["name"] if s.endswith(".toml") else s for s in args.studies] or present
        if not studies:
            raise InvalidInputError(f"--results {results} holds no study (no */results.csv)")
        for s in studies:
            meta_path = results / s / "meta.json"
            if meta_path.is_file():
                try:
                    committed_quick = bool(json_value(meta_path.read_text(encoding="utf-8")).get("quick"))
                except (ValueError, AttributeError):
                    raise InvalidInputError(f"{meta_path} is not readable JSON") from None
                if committed_quick != args.quick:
                    raise InvalidInputError(f"{results}/{s} holds a {'quick' if committed_quick else 'full'} run; "
                                            f"{'add' if committed_quick else 'drop'} --quick or choose another --results")
        if args.against is not None:
            verdict = verify(studies, results, args.against, write=args.write_verdict)
        else:
            ready = {}
            for s in studies:  # a study whose data are not available here: named -> an error, implied -> a note
                try:
                    spec = named.get(s) or config_of(s, results, known)
                    runner.check_ready(configs.load(spec, quick=args.quick), configs.MAX_ROWS)
                    ready[s] = spec
                except InvalidInputError as exc:
                    if args.studies:
                        raise
                    print(f"{s}: not checked here: {exc}")
            if not ready:
                raise InvalidInputError("no study of --results can run here (see above)")
            studies = list(ready)
            with tempfile.TemporaryDirectory(prefix="fitbench-verify-") as tmp:
                for s in studies:
                    runner.run_study(ready[s], Path(tmp), quick=args.quick, jobs=runner.usable_jobs(args.jobs))
                verdict = verify(studies, results, Path(tmp), write=args.write_verdict,
                                 against_name=f"a fresh run of python -m experiments.verify (fitbench {__version__})")
    except InvalidInputError as exc:
        print(f"experiments.verify: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:   # Ctrl-C, SIGTERM, SIGHUP
        what, status = stopped_status(exc)
        written = args.write_verdict and _stat(results / VERDICT_FILE) != verdict_before
        print(f"{chr(10) if status == 130 else ''}experiments.verify: {what}"
              + (f" after the verdict was written to {results / VERDICT_FILE}" if written else "; no verdict written"),
              file=sys.stderr)
        return status
    return 0 if verdict["agree"] else 1


def _stat(path: Path) -> tuple | None:
    """(inode, modification time, size) of ``path``, None when it is not there: a verdict written since differs."""
    try:
        st = path.stat()
    except OSError:
        return None
    return st.st_ino, st.st_mtime_ns, st.st_size


if __name__ == "__main__":
    from fitbench.stopping import started
    started()
    sys.exit(main())
