"""``python -m experiments.run [NAME ...] [--list] [--quick] [--jobs N] [--executor local|dask]
[--scheduler ADDRESS] [--out DIR] [--force] [--seed S] [--max-rows N] [--row-timeout SECONDS] [--no-report]``

Runs studies (no NAME: the default studies) and writes, per study, ``OUT/NAME/results.csv`` (long
format, one row per run; timing columns start with ``time_``), ``meta.json`` (provenance, counts,
findings), ``summary.csv``/``summary.md`` and the study's figures. Rows are stored as they finish
in ``OUT/NAME/rows.sqlite``: an interrupted run resumes; ``--force`` recomputes. One run at a time writes
into an ``--out`` folder (a lock; a second run says so in one line). At the end the report is rebuilt (``paper/`` for the default ``results/``, else ``OUT/paper``; ``python -m experiments.report``).
Without ``--out`` a study that is not one of the project's (its TOML outside ``experiments/configs/``) writes into
``results/user/`` (its report ``results/user/paper/``), never into the committed ``results/`` and ``paper/``.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import os
import signal
import sys
import tempfile
import threading
import time
from itertools import islice
from pathlib import Path

if __name__ == "__main__":  # the command: its local workers start now and import while this process imports its own
    def _stopped_while_starting(signum, frame):
        """Ctrl-C, SIGTERM or SIGHUP while the command imports its modules and starts its workers (before main's
        handlers): one line, no traceback (the workers end with it: they die with their parent)."""
        what = "interrupted" if signum == signal.SIGINT else f"terminated ({signal.Signals(signum).name})"
        os.write(2, f"\nexperiments.run: {what} while starting; no rows had run\n".encode())
        os._exit(128 + signum)
    for _sig in (signal.SIGINT, signal.SIGTERM, getattr(signal, "SIGHUP", None)):
        if _sig is not None and signal.getsignal(_sig) is not signal.SIG_IGN:   # nohup's SIGHUP stays ignored
            signal.signal(_sig, _stopped_while_starting)

    from experiments.localworkers import start_early
    start_early(sys.argv[1:])

from experiments import compare  # the verdict on every run: fresh results against the committed ones
from experiments import config as configs
from experiments import codekeys, engine
from experiments import analysis, figures, outputs
from experiments import study as contract
from experiments.csvtext import blocks, csv_text, write_results
from experiments.jsontext import json_text, json_value
from experiments.executors import kept_workers, last_study, map_in_idle_workers, start_kept_workers, workers_done
from experiments.provenance import collect, write_atomic
from experiments.rows import (ENVIRONMENT_STATUSES, STOPPING_SIGNALS, Terminated, base_row, clear_signal,
                              fewer_collections, note_signal, raise_if_signalled, signalled)
from experiments.summary import summarise, summary_units, to_markdown, with_units
from fitbench import __version__
import methods
from methods import InvalidInputError
from methods.files import NotRegularFileError, check_regular


def default_studies() -> list[str]:
    return [n for n in configs.available() if configs.load(n).get("default", False)]


#: what an interrupt message names: the row store of the study that was running
_CURRENT: dict = {}
#: one line per study of the run none of whose rows has a result (``study.failed_rows``): the run exits 1
_FAILED: list = []
DEFAULT_OUT = Path("results")  # relative to the working directory, never inside the installed package


def confined(out: Path, name: str) -> Path:
    """``out/name``, refused unless it lies inside ``out`` (a name is never a path)."""
    target = (out / name).resolve()
    if target.parent != out.resolve() or not name or name in (".", ".."):
        raise InvalidInputError(f"study name {name!r} would write outside --out {out}; a name is a plain word")
    return out / name


def check_summary_by(cfg: dict, study, tasks: list[dict]) -> None:
    """Refuse summary_by columns no row will have, before any row runs. The columns are known from the
    tasks (identity, data and parameter columns), the generic fit (status, metrics, timing) and, for a
    study with its own ``execute``, the ``ROW_COLUMNS`` it may declare."""
    by = cfg.get("summary_by")
    if not by:
        return
    own = study.row_columns(cfg)
    if own is None:
        return  # its columns are known only after it ran: checked then (finish)
    known = set(engine.result_columns()) | set(own)
    for t in tasks[:10000]:
        known |= set(base_row(t))
    unknown = [c for c in by if c not in known]
    if unknown:
        raise configs.ConfigError(f"{cfg.where}: summary_by: no row will have the column(s) {', '.join(unknown)}; "
                                  f"the rows have: {', '.join(sorted(known))}")


def summary_columns(cfg: dict, df) -> list[str]:
    """The summary's grouping: the study's ``summary_by``, else the data set, its parameters, the method
    and its parameters — never the per-repetition data stream (a summary averages over repetitions)."""
    default = ["dataset"] + [c for c in df.columns if c.startswith("data_") and c != "data_stream"] + ["method", "params"]
    return [c for c in cfg.get("summary_by", default) if c not in ("data_stream", "repetition")]


def plugin_distributions(used) -> dict[str, str]:
    """{distribution: version} of every plugin method or data source among ``used`` ((method id, source
    name) pairs of the study's tasks)."""
    from datasets import sources
    from methods.plugins import distributions_of
    mods = set()
    known = {s.id for s in methods.list_methods()}
    for method, source in used:
        if method in known:
            mods.add(methods.get(method).module)
        try:
            mods.add(sources.get_source(source).module)
        except KeyError:
            pass
    return distributions_of(sorted(mods))


class EnvironmentFailure(InvalidInputError):
    """Every row of a study failed for a reason of the environment (a kernel not built, a module that does
    not import, time-outs, crashes): nothing to analyse, and nothing of it was cached as a result."""


def _limited(tasks, cfg: dict, max_rows: int):
    """The tasks, refused with one line as soon as there are more than ``max_rows`` (a study's own task
    list is counted while it is expanded, never built whole first)."""
    for n, t in enumerate(tasks, 1):
        if n > max_rows:
            raise configs.ConfigError(f"{cfg.where}: the study has more than {max_rows:,} rows, more than the "
                                      f"limit; shrink the grid or pass a larger --max-rows")
        yield t


def check_size(cfg: dict, max_rows: int) -> None:
    """Refuse a study above ``max_rows`` from its grid sizes alone, before anything is expanded (a study
    that multiplies its rows says so in ``Study.count_rows``; its task list is also counted while it is made)."""
    study = contract.study_of(cfg["kind"])
    for bound in (configs.count_rows(cfg), study.count_rows(cfg)):
        if bound > max_rows and not study.own_tasks and bound // max(cfg.get("repetitions", 1), 1) <= GRID_COUNTED:
            bound = engine.grid_rows(cfg, cfg.where)  # the rows themselves: methods' on and max_n leave out some
        configs.check_rows(cfg, bound, max_rows)


#: the most (data set, method) pairs whose rows :func:`check_size` counts one by one (a larger grid is refused from its
#: size alone)
GRID_COUNTED = 1_000_000


def check_ready(cfg: dict, max_rows: int) -> None:
    """Everything a study needs before its first row, checked before any study of the run starts: its size
    (:func:`check_size`) and its first task (a study whose data are not available here, such as a reference
    folder named by an environment variable, says so now, not after the studies before it ran)."""
    check_size(cfg, max_rows)
    check_has_rows(cfg, task_source(cfg, contract.study_of(cfg["kind"]), max_rows))


def check_has_rows(cfg: dict, make) -> None:
    """A study whose tasks are none is refused before it runs (its analysis would have no rows)."""
    if next(iter(make()), None) is None:
        study = contract.study_of(cfg["kind"])
        raise configs.ConfigError(f"{cfg.where}: the grid has 0 rows: " + (
            f"the study kind {cfg['kind']!r} makes no task from it" if study.own_tasks else
            engine.why_no_rows(cfg, cfg.where)))


def task_source(cfg: dict, study, max_rows: int):
    """A function returning a fresh iterable of the study's prepared tasks (index and cache key), lazily."""
    return lambda: _limited(study.prepared_tasks(cfg), cfg, max_rows)


def environment_failure(cfg: dict, df) -> EnvironmentFailure | None:
    """The one-line error of a study whose rows all failed for reasons of the environment, else None."""
    if not len(df) or not df["status"].isin(ENVIRONMENT_STATUSES).all():
        return None
    reasons = df.groupby(["status", "message"], sort=False, dropna=False).size().sort_values(ascending=False)
    (status, message), n = reasons.index[0], int(reasons.iloc[0])
    more = f" ({len(reasons) - 1} other reasons for the other rows)" if len(reasons) > 1 else ""
    return EnvironmentFailure(f"{cfg.where}: all {len(df)} rows failed for a reason of the environment, not "
                              f"of the methods: {status}: {message} ({n} rows){more}; nothing of it is cached as a "
                              f"result: fix it and run the same command again")


def run_study(name: str, out: Path, *, quick=False, jobs=1, executor="local", scheduler=None, force=False,
              seed=None, log=print, max_rows=configs.MAX_ROWS, row_timeout=None) -> Path:
    codekeys.forget_data_hashes()
    cfg = configs.load(name, quick=quick, seed=seed)
    study = contract.study_of(cfg["kind"])
    target = confined(out, cfg["name"])
    log(f"== {cfg['name']}: {cfg['title']}" + (" [quick]" if quick else ""))
    check_size(cfg, max_rows)
    make = task_source(cfg, study, max_rows)
    check_has_rows(cfg, make)
    if cfg.get("summary_by"):
        check_summary_by(cfg, study, list(islice(make(), 10000)))
    jobs = min(jobs, cfg.get("max_jobs", jobs))
    row_timeout = row_timeout if row_timeout is not None else cfg.get("row_timeout")
    n_rows = None if force else engine.up_to_date(cfg, make, target)
    if n_rows is not None and not _records_config_file(cfg, out, target):
        n_rows = None  # the same study from a moved TOML: its rows are stored; its outputs name the TOML it ran from
    if n_rows is not None:  # the same rows analysed by the same code: the outputs there are this run's
        log(f"   {n_rows} rows: {n_rows} already stored, 0 to run; results.csv, tables and figures up to date")
        _FAILED.extend(filter(None, [analysis.failed_rows(cfg, target / "results.csv")]))
        return target
    start_kept_workers()  # rows may run: workers (of a run on several) import while this study prepares
    store = engine.RowStore(target / "rows.sqlite", log=log)
    _CURRENT["store"] = target / "rows.sqlite"
    try:
        df, counts = engine.run(make, store, force=force, jobs=jobs, executor=executor, scheduler=scheduler,
                                desc=cfg["name"], log=log, row_timeout=row_timeout, chunk_rows=cfg.get("chunk_rows"),
                                outputs=engine.outputs_code(cfg),
                                # this process waits for the workers: it loads what the figures need meanwhile
                                while_rows_run=figures.load_plotting_in_background if jobs > 1 or executor == "dask"
                                else None)
    finally:
        store.close()
    raise_if_signalled()
    failure = environment_failure(cfg, df)
    if failure is not None:
        raise failure
    _FAILED.extend(filter(None, [analysis.failed_rows(cfg, df)]))
    used = counts.pop("used")
    outputs.remove_leftover_tmp(target)
    # results.csv is made by the run's idle workers (if any) while this process analyses the rows
    texts = map_in_idle_workers(csv_text, blocks(df))
    try:
        t0 = time.perf_counter()
        log("   analysis, tables and figures ...")
        findings, analysed = analysis.analyse(study, df, cfg, target, log)
        log(f"   analysis done ({time.perf_counter() - t0:.1f} s)")
    finally:  # written also when the analysis fails: the rows are the run's result
        results_sha256 = write_results(df, target / "results.csv", texts)
        workers_done()
    raise_if_signalled()
    if cfg.get("summary_by") and set(cfg["summary_by"]) - set(df.columns):
        raise configs.ConfigError(f"{cfg.where}: summary_by: no row has the column(s) "
                                  f"{', '.join(sorted(set(cfg['summary_by']) - set(df.columns)))}; "
                                  f"the rows have: {', '.join(df.columns)}")
    summary = summarise(df, summary_columns(cfg, df))
    public_cfg = dict(cfg)
    meta = {**collect(public_cfg), "study": cfg["name"], "quick": quick, "executor": executor, "jobs": jobs,
            "row_timeout_s": row_timeout, "environment": codekeys.environment(),
            "counts": counts, "n_rows": len(df), "status_counts": df["status"].value_counts().to_dict(),
            "plugins": plugin_distributions(used), "results_sha256": results_sha256, "findings": findings,
            "fingerprint": counts.pop("fingerprint"), "inputs": compare.inputs(cfg), **config_file(cfg, out)}
    units = summary_units(summary, cfg)
    outputs.write_manifest(target, cfg, analysed, with_units(summary, units))   # its fallback table: units as summary.md
    template = (cfg.get("report") or {}).get("findings")
    if template and analysed.findings:   # the analysis's own findings win: said, never silently
        print(f"experiments.run: note: {cfg.where}: [report] findings is not used: the analysis of kind "
              f"{cfg['kind']!r} writes its own findings ({_shorter(analysed.findings)}); drop findings from the "
              f"TOML, or return none from analyse() to use the template", file=sys.stderr)
    buf = io.StringIO()
    summary.to_csv(buf, index=False, float_format="%.10g")
    write_atomic(target / "summary.csv", buf.getvalue())
    write_atomic(target / "summary.md", f"# {cfg['title']}\n\n" + to_markdown(summary, units=units))
    raise_if_signalled()  # before meta.json: a study whose outputs are not all written is not up to date
    write_atomic(target / "meta.json", json_text(meta, indent=1) + "\n")
    outputs.remove_leftover_tmp(target)
    bad = ", ".join(f"{v} {k}" for k, v in meta["status_counts"].items() if k != "ok")
    log(f"-> {target}/results.csv ({len(df)} rows" + (f": {bad}" if bad else "") +
        f"; rows run in {counts['wall_s']:.1f} s), summary.csv, summary.md, meta.json")
    return target


def _records_config_file(cfg, out: Path, target: Path) -> bool:
    """Whether the study's ``meta.json`` in ``target`` records the TOML this run loaded (:func:`config_file`)."""
    try:
        meta = json_value((Path(target) / "meta.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    want = config_file(cfg, out)
    return isinstance(meta, dict) and all(meta.get(k) == v for k, v in want.items())


def config_file(cfg, out: Path) -> dict[str, str]:
    """The TOML a study was loaded from, as ``meta.json`` records it (what ``experiments.verify`` and the report's
    commands run again; ``experiments.verdict.recorded_config`` reads it back): ``config_file``, with
    ``config_file_relative_to`` saying from where. A project study's relative to the checkout
    (``experiments/configs/NAME.toml``); any other relative to the results folder ``out`` (``../studies/NAME.toml``)
    when the TOML lies in the folder that holds ``out`` or, with ``out``, in the current folder, so that a results
    folder committed with its TOML names no folder of the author's machine; else by its absolute path. The file is
    the one the run was given (``cfg.file``): a link to a TOML of another name is recorded as the link."""
    from experiments.provenance import REPO
    path = Path(cfg.folder).resolve() / f"{cfg['name']}.toml"
    if is_project_study(cfg):
        try:
            return {"config_file": path.relative_to(REPO).as_posix(), "config_file_relative_to": "checkout"}
        except ValueError:
            pass
    path = cfg.file if getattr(cfg, "file", None) is not None else path
    results = Path(out).resolve()
    for base in (results.parent, Path.cwd().resolve()):
        if path.is_relative_to(base) and results.is_relative_to(base):
            return {"config_file": Path(os.path.relpath(path, results)).as_posix(),
                    "config_file_relative_to": "results folder"}
    return {"config_file": str(path)}


def _shorter(text, limit: int = 80) -> str:
    text = " ".join(str(text).split())
    return repr(text if len(text) <= limit else text[:limit - 1] + "…")


def usable_jobs(jobs: int, log=print) -> int:
    """``jobs``, capped at the cores this process may use (more workers only compete for them)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:
        cores = os.cpu_count() or 1
    if jobs > cores:
        log(f"--jobs {jobs} capped at {cores}: the cores available to this run")
        return cores
    return jobs


#: where studies that are not the project's own go when no --out is given (``results/`` and ``paper/`` hold the
#: project's committed studies and report: a personal study never joins them unasked)
USER_OUT = DEFAULT_OUT / "user"


def is_project_study(cfg) -> bool:
    """Whether a loaded study is one of the project's own (its TOML in ``experiments/configs/``)."""
    return Path(cfg.folder).resolve() == configs.CONFIG_DIR


def output_folder(out: str | None, cfgs: list, quick: bool) -> tuple[Path, str | None]:
    """(the run's output folder, a note to print or None). ``--out`` when given (an empty one is refused: an unset
    shell variable would be the current folder, and the report would overwrite ``paper/`` there); else ``results/``
    (``results/quick/`` with ``--quick``) for the project's studies, and ``results/user/`` (``results/user/quick/``)
    when a study is not one of them: ``results/`` and ``paper/`` are the committed results and report, which a
    personal study must not join (it would renumber the report's tables). The project's results folders given as
    ``--out`` with such a study are refused for the same reason."""
    foreign = [c for c in cfgs if not is_project_study(c)]
    if out is not None:
        out = os.fspath(out)
        if not out.strip():
            raise InvalidInputError("--out is empty (an unset shell variable?); give a folder, or leave --out out "
                                    "for the default (results/)")
        if foreign:
            from experiments.report import is_default_results
            if is_default_results(Path(out)):
                c = foreign[0]
                from experiments.provenance import REPO
                inside = Path(out).resolve().parent in (REPO, REPO / "results")
                what = ("holds the project's committed results, from which the report paper/ is rebuilt" if inside
                        else "is reserved for the project's studies: results/ and results/quick/ of the current folder "
                             "are where python -m experiments.run writes them without --out, with their report "
                             "paper/ beside")
                raise InvalidInputError(
                    f"--out {out} {what}; {c['name']} ({c.where}) is not one of the project's studies "
                    f"(experiments/configs/): leave --out out (its outputs then go to "
                    f"{USER_OUT / 'quick' if quick else USER_OUT}/) or give another folder")
        from experiments.report import committed_clash
        if clash := committed_clash(Path(out), project=not foreign):
            raise InvalidInputError(f"--out {out} {clash}; give another folder, or leave --out out (the outputs then go "
                                    f"to {(USER_OUT if foreign else DEFAULT_OUT) / ('quick' if quick else '')}/)")
        return Path(out), None
    if not foreign:
        return (DEFAULT_OUT / "quick" if quick else DEFAULT_OUT), None   # a quick grid never joins the full results
    folder = USER_OUT / "quick" if quick else USER_OUT
    names = ", ".join(c["name"] for c in foreign)
    return folder, (f"{names} {'is' if len(foreign) == 1 else 'are'} not one of the project's studies "
                    f"(experiments/configs/): this run writes into {folder}/ and its report into {folder / 'paper'}/, "
                    f"not into results/ and paper/ (--out DIR to choose)")


def check_out(out: Path) -> None:
    """--out must be a folder we can write into (created when missing)."""
    try:
        if out.exists() and not out.is_dir():
            raise InvalidInputError(f"--out {out} is a file, not a folder; give a folder")
        out.mkdir(parents=True, exist_ok=True)
        probe = out / f".write-test-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        shown = str(out) if len(str(out)) <= 80 else f"{str(out)[:40]}...{str(out)[-30:]} ({len(str(out))} characters)"
        raise InvalidInputError(f"--out {shown} cannot be written ({exc.strerror}); give a folder you can write") from None


#: the lock file of an --out folder (one run at a time writes into it)
LOCK_NAME = ".experiments-run.lock"
_LOCKS: list = []
#: the files a run reads (a previous run's) and writes in ``OUT`` and in each ``OUT/STUDY`` (:func:`check_outputs`)
OUT_FILES = (LOCK_NAME, "verify.json")
STUDY_FILES = ("meta.json", "results.csv", "summary.csv", "summary.md", "report.json", "rows.sqlite",
               "rows.sqlite-wal", "rows.sqlite-shm", "rows.sqlite-journal")


def check_outputs(out: Path, study_names: list[str]) -> None:
    """Refuse, before anything is read or locked, a file the run reads and writes that exists and is not a regular
    file (a FIFO, a device, a folder, a socket, or a symlink to one): reading a FIFO at ``OUT/STUDY/meta.json`` or
    ``OUT/verify.json`` blocked the run forever, and SQLite said "free the space" of a ``rows.sqlite`` folder. A
    study's folder must be a folder."""
    for name in study_names:
        folder = out / name
        if folder.exists() and not folder.is_dir():
            raise InvalidInputError(f"{folder}: is not a folder; the run writes the outputs of study {name!r} in it: "
                                    f"remove it, or give another --out")
    for path in [out / n for n in OUT_FILES] + [out / s / n for s in study_names for n in STUDY_FILES]:
        try:
            check_regular(path)   # follows a symlink; a path that does not exist is fine
        except NotRegularFileError as exc:
            what = str(exc).rsplit("; ", 1)[0]   # "PATH: is a FIFO (named pipe), not a regular file"
            raise InvalidInputError(f"{what}; the run reads and writes this file: remove it, or give another "
                                    f"--out") from None


def check_inputs_not_written(out: Path, cfgs: list, report: bool) -> None:
    """Refuse, before any row, a study whose data file lies where the run writes: a study's folder ``OUT/STUDY``
    (results.csv, tables, figures), the report's ``OUT/paper`` (unless ``--no-report``) or the run's own files in
    ``OUT``. A data set at ``OUT/STUDY/results.csv`` had the measurement replaced by the results table, and the run
    then blamed the columns of the file it had written."""
    from experiments.compare import study_data_files
    places = [out.resolve() / cfg["name"] for cfg in cfgs] + ([out.resolve() / "paper"] if report else [])
    own = {(out / n).resolve() for n in OUT_FILES}
    for cfg in cfgs:
        for where, path in study_data_files(cfg):
            f = Path(path).resolve()
            place = next((p for p in places if f == p or p in f.parents), None)
            if place is not None or f in own:
                raise InvalidInputError(f"{getattr(cfg, 'where', cfg['name'])} {where}: {path} is a data file in "
                                        f"{place or out}, which this run writes (--out {out}): move the data out of "
                                        f"it, or give another --out")


def lock_out(out: Path):
    """Hold an exclusive lock on ``out`` for the rest of the run (``fcntl.flock``: :func:`main` releases it when it
    returns, and the kernel when the process ends, however it ends); a second run into the same folder gets one
    line and exit 2."""
    try:
        import fcntl
    except ImportError:  # not POSIX: no lock (documented)
        return None
    for _ in range(100):
        fh = open(out / LOCK_NAME, "a+")
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.seek(0)
            holder = fh.read().strip()
            fh.close()
            raise InvalidInputError(f"--out {out} is in use by another experiments.run ({holder or 'a running process'}); "
                                    f"wait for it to finish or give another --out") from None
        try:   # the run that held it removes the file before releasing it: a lock on a removed file locks nothing
            if os.stat(out / LOCK_NAME).st_ino == os.fstat(fh.fileno()).st_ino:
                break
        except FileNotFoundError:
            pass
        fh.close()
    fh.seek(0)
    fh.truncate()
    fh.write(f"pid {os.getpid()}")
    fh.flush()
    _LOCKS.append(fh)
    return fh


def _on_signal(signum, frame):
    """SIGINT (Ctrl-C), SIGTERM and SIGHUP: recorded, then raised in the main thread (KeyboardInterrupt, ``Terminated``,
    ``HungUp``: :data:`experiments.rows.STOPPING_SIGNALS`); :func:`experiments.rows.raise_if_signalled` raises it again
    at the run's safe points if code swallowed it."""
    exc_type = STOPPING_SIGNALS.get(signum, KeyboardInterrupt)
    note_signal(exc_type)
    raise exc_type()


@contextlib.contextmanager
def _interrupts_are_the_run_s():
    """The run's own handlers for SIGINT, SIGTERM and SIGHUP (main thread only; a SIGHUP ignored, as under ``nohup``,
    stays ignored), and quiet about an interrupt an exception callback swallowed (``Exception ignored in: ...
    KeyboardInterrupt``): the run raises it again itself."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {sig: signal.signal(sig, _on_signal) for sig in STOPPING_SIGNALS
                if sig == signal.SIGINT or signal.getsignal(sig) is not signal.SIG_IGN}
    hook = sys.unraisablehook

    def unraisable(info):
        if not (isinstance(info.exc_value, KeyboardInterrupt) and signalled()):
            hook(info)
    sys.unraisablehook = unraisable
    try:
        yield
    finally:
        sys.unraisablehook = hook
        for sig, handler in previous.items():
            signal.signal(sig, handler)


@contextlib.contextmanager
def plugin_warnings_once():
    """A plugin that fails to load (``methods.plugins.PluginLoadWarning``) is reported in one line
    ``fitbench: warning: ...``, once: not in ``warnings``' format (file, line, source), and the spawned worker
    processes, which load the plugins again, are told through PYTHONWARNINGS to ignore what this process
    already printed (a warning's filter matches the start of its message; fields end at ':' and ',')."""
    import re
    import warnings

    from methods.plugins import PluginLoadWarning
    shown, original, env = set(), warnings.showwarning, os.environ.get("PYTHONWARNINGS")

    def show(message, category, filename, lineno, file=None, line=None):
        if not issubclass(category, PluginLoadWarning):
            return original(message, category, filename, lineno, file, line)
        text = " ".join(str(message).split())
        if text in shown:
            return None
        shown.add(text)
        print(f"fitbench: warning: {text}", file=sys.stderr)
        prefix = re.split(r"[:,]", text)[0].strip()
        os.environ["PYTHONWARNINGS"] = ",".join(filter(None, [os.environ.get("PYTHONWARNINGS"),
                                                              f"ignore:{prefix}:Warning"]))
        return None
    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = original
        if env is None:
            os.environ.pop("PYTHONWARNINGS", None)
        else:
            os.environ["PYTHONWARNINGS"] = env


def release_locks(keep: int = 0) -> None:
    """Release the ``--out`` locks taken after the first ``keep``: the lock file is removed while still locked (no
    ``.experiments-run.lock`` is left in the folder; a run that opened it meanwhile sees it removed and opens the new
    one, :func:`lock_out`), then closing it releases its ``flock``."""
    while len(_LOCKS) > keep:
        fh = _LOCKS.pop()
        try:
            path = Path(fh.name)
            if os.stat(path).st_ino == os.fstat(fh.fileno()).st_ino:
                path.unlink()
        except OSError:
            pass
        fh.close()


def main(argv=None, prog: str = "python -m experiments.run") -> int:
    """The command line as a function (exit status returned; ``prog``: the command named in its usage, ``fitbench
    run`` from fitbench); the ``--out`` lock it takes is released when it returns, however it ends, so a second call
    in the same process can write to the same folder."""
    from fitbench.streams import OutputError, readers_may_go
    held = len(_LOCKS)
    try:   # `... | head -1`: the reader going ends what the run prints, not the run (its rows and outputs, exit 0)
        with readers_may_go(), plugin_warnings_once(), fewer_collections():
            return _main(argv, prog)
    except OutputError as exc:   # `> /dev/full`, found when the last lines are written
        print(f"experiments.run: error: cannot write {exc.filename}: {exc.strerror}; the finished rows and outputs are "
              f"kept", file=sys.stderr)
        return 2
    finally:
        release_locks(held)


def _main(argv=None, prog: str = "python -m experiments.run") -> int:
    parser = argparse.ArgumentParser(prog=prog, description="Run fitbench studies.")
    parser.add_argument("--version", action="version", version=f"%(prog)s (fitbench {__version__})")
    parser.add_argument("names", nargs="*", metavar="NAME", help="studies (names or .toml paths); default: the default studies")
    parser.add_argument("--list", action="store_true", help="list the studies, one line each")
    parser.add_argument("--quick", action="store_true", help="the reduced grid of each study (CI size)")
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1),
                        help="parallel workers (default: 2; capped at the cores available)")
    parser.add_argument("--executor", choices=("local", "dask"), default="local",
                        help="local processes, or Dask distributed (a LocalCluster unless --scheduler)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="a Dask scheduler, e.g. tcp://host:8786")
    parser.add_argument("--out", default=None,
                        help="output folder (default: results/ in the current folder, results/quick/ with --quick; "
                             "results/user/ for a study that is not one of the project's)")
    parser.add_argument("--force", action="store_true", help="recompute rows that are already stored")
    parser.add_argument("--seed", type=int, help="override the studies' base seed")
    parser.add_argument("--max-rows", type=int, default=configs.MAX_ROWS,
                        help=f"refuse a study with more rows than this (default: {configs.MAX_ROWS:,})")
    parser.add_argument("--row-timeout", type=float, metavar="SECONDS",
                        help="end a row that runs longer (status timeout) and run rows in worker processes "
                             "(default: the study's row_timeout, else none)")
    parser.add_argument("--no-report", action="store_true", help="do not rebuild the report after the studies")
    args = parser.parse_args(argv)
    clear_signal()
    with _interrupts_are_the_run_s():
        return _run(args)


def _run(args) -> int:
    _FAILED.clear()
    try:
        if args.list:
            try:
                for name in configs.available():
                    cfg = configs.load(name)
                    print(f"{name:<18} {'default' if cfg.get('default') else '       '}  {cfg['title']}")
                sys.stdout.flush()
            except BrokenPipeError:   # `--list | head -1`: the reader has all it wanted (as `fitbench list | head`)
                os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())   # nothing left to flush at exit
            return 0
        if args.jobs < 1:
            raise InvalidInputError(f"--jobs must be at least 1, got {args.jobs}")
        if args.max_rows < 1:
            raise InvalidInputError(f"--max-rows must be at least 1, got {args.max_rows}")
        if args.row_timeout is not None and not (args.row_timeout > 0 and args.row_timeout < 1e7):
            raise InvalidInputError(f"--row-timeout must be a positive number of seconds, got {args.row_timeout:g}")
        if args.scheduler is not None and args.executor != "dask":
            raise InvalidInputError("--scheduler needs --executor dask")
        if args.scheduler is not None and not args.scheduler.strip():
            raise InvalidInputError("--scheduler is empty; give an address such as tcp://host:8786, "
                                    "or leave it out for a local Dask cluster")
        names = args.names or default_studies()
        checked = []
        for name in names:  # validate every config, its size and its data before running any
            cfg = configs.load(name, quick=args.quick, seed=args.seed)
            for note in configs.plugin_notes(cfg):   # plugin methods a family wildcard takes: said first
                print(f"experiments.run: note: {note}", file=sys.stderr)
            check_ready(cfg, args.max_rows)
            checked.append(cfg)
        args.out, note = output_folder(args.out, checked, args.quick)
        if note:
            print(f"experiments.run: note: {note}", file=sys.stderr)
        for cfg in checked:
            confined(args.out, cfg["name"])
        check_out(args.out)
        check_outputs(args.out, [cfg["name"] for cfg in checked])
        check_inputs_not_written(args.out, checked, report=not args.no_report)
        lock_out(args.out)
        jobs = args.jobs if args.scheduler else usable_jobs(args.jobs)
        t0 = time.perf_counter()
        workers = kept_workers(jobs) if args.executor == "local" and jobs > 1 else contextlib.nullcontext()
        with workers, tempfile.TemporaryDirectory(prefix="fitbench-reference-") as ref_dir:
            loaded = [configs.load(n, quick=args.quick, seed=args.seed) for n in names]
            study_names = [c["name"] for c in loaded]
            if args.force or any(not (args.out / n / "meta.json").is_file() for n in study_names):
                start_kept_workers()  # a study never run here runs rows: the workers import meanwhile
            refs = compare.reference_snapshot(args.out, study_names, args.quick, Path(ref_dir),
                                              {c["name"]: compare.inputs(c) for c in loaded})
            for i, name in enumerate(names):
                if i == len(names) - 1:
                    last_study()
                run_study(name, args.out, quick=args.quick, jobs=jobs, executor=args.executor,
                          scheduler=args.scheduler, force=args.force, seed=args.seed, max_rows=args.max_rows,
                          row_timeout=args.row_timeout)
                raise_if_signalled()
            print(f"done: {len(names)} {'study' if len(names) == 1 else 'studies'} in {time.perf_counter() - t0:.0f} s")
            compare.verdict_after_run(args.out, study_names, refs)  # results of another seed or config: not compared
            raise_if_signalled()
        if not args.no_report:
            from experiments.report import build, default_out
            paper = default_out(args.out)   # paper/ for results/, else OUT/paper: where experiments.report puts it
            t1 = time.perf_counter()
            print("report ...")
            build(args.out, paper)
            raise_if_signalled()
            print(f"report done ({time.perf_counter() - t1:.0f} s)")
        for line in _FAILED:
            print(f"experiments.run: error: {line}", file=sys.stderr)
        if _FAILED:
            return 1
    except InvalidInputError as exc:
        print(f"experiments.run: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # disk full, a file-size limit, an I/O error while writing the outputs
        where = f" {exc.filename}" if exc.filename else ""
        print(f"experiments.run: error: cannot write{where}: {exc.strerror or exc}; the finished rows are kept, "
              f"fix the cause and run the same command again", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        signum = exc.signum if isinstance(exc, Terminated) else signal.SIGINT
        what = f"terminated ({signal.Signals(signum).name})" if isinstance(exc, Terminated) else "interrupted"
        store = _CURRENT.get("store")
        kept = f"finished rows are kept in {store}" if store else "no rows had run"
        print(f"\nexperiments.run: {what}; {kept}; run the same command again to resume", file=sys.stderr)
        return 128 + signum
    return 0


if __name__ == "__main__":  # the command ends once its outputs are written, without the interpreter's teardown
    from experiments.localworkers import exit_now
    signal.signal(signal.SIGINT, signal.default_int_handler)  # main's own handling from here (_interrupts_are_the_run_s)
    for _sig in (signal.SIGTERM, getattr(signal, "SIGHUP", None)):
        if _sig is not None and signal.getsignal(_sig) is _stopped_while_starting:
            signal.signal(_sig, signal.SIG_DFL)
    exit_now(main(), as_python_does=True)
