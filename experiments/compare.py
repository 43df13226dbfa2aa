"""The comparison behind the reproducibility verdict: every non-timing column of each study's ``results.csv``
against a reference run's, with the tolerances declared with the metrics (``experiments.metrics.TOLERANCES``:
exact for ids, statuses and counts; relative + absolute per metric). Rows are matched by their identity
(study, data set, data stream, repetition, seed, method, parameters). A row with the same status other than
"ok" in both runs (an iteration that did not converge) is compared by its status and counts only: its values
are where the iteration stopped, not a result.

:func:`verify` serves ``python -m experiments.verify`` (:mod:`experiments.verify`), :func:`reference_snapshot`
and :func:`verdict_after_run` the end of ``python -m experiments.run``; both commands import this module, which
imports neither (so the two commands do not import each other). The run's verdict is written atomically to
``OUT/verify.json``; ``experiments.verify`` writes ``RESULTS/verify.json`` only with ``--write-verdict``
(:mod:`experiments.verdict` reads the file for the report).
"""
from __future__ import annotations

import datetime as _dt
import hashlib
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd

from experiments.jsontext import json_value
from experiments.metrics import CHAOTIC, tolerance as declared_tolerance
from experiments.provenance import write_atomic
from experiments.verdict import VERDICT_FILE, last_verdict, results_sha256
from methods import InvalidInputError

#: columns that identify a row (those present are used; data_* and param_* columns are added)
IDENTITY = ("study", "dataset", "data_stream", "repetition", "seed", "method", "params")
WORST_ROWS = 3
#: the columns that say where an iteration stopped: its status and flags, and its counts
STOPPING = frozenset({"status", "converged", "success", "iterations", "nfev"})
BACKEND_WHY = ("an iterative method whose path runs near its stopping test stops at another iteration, or on the "
               "other side of the test (a run-away start converging or not), when its sums differ in the last bits, "
               "as the compiled kernels' and NumPy's do (docs/speed.md)")


def tolerance(column: str, study: str = "", method: str = ""):
    """The declared tolerance of ``column`` (``experiments.metrics.tolerance``), the study kinds' own columns
    included (``Study.tolerances``)."""
    from experiments import studies
    return declared_tolerance(column, study, method, own=studies.tolerances())


def _read(folder: Path, study: str, which: str) -> pd.DataFrame:
    path = folder / study / "results.csv"
    if not path.is_file():
        raise InvalidInputError(f"{which} {folder} has no {study}/results.csv; run python -m experiments.run {study}"
                                f" --out {folder} first, or name the studies it has")
    try:
        df = pd.read_csv(path, dtype=str, keep_default_na=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError, OSError) as exc:
        raise InvalidInputError(f"{path} cannot be read as a table ({type(exc).__name__}: {str(exc).splitlines()[0]})") from None
    if "status" not in df.columns or "method" not in df.columns:
        raise InvalidInputError(f"{path} is not a results table of experiments.run (no status/method column)")
    if df.empty:
        raise InvalidInputError(f"{path} has a header but no rows; run python -m experiments.run {study} again "
                                "(an interrupted or failed run leaves no rows)")
    return df


def identity_columns(df: pd.DataFrame) -> list[str]:
    return [c for c in df.columns if c in IDENTITY or c.startswith(("data_", "param_"))]


def _keyed(df: pd.DataFrame, ident: list[str]) -> pd.DataFrame:
    df = df.copy()
    shown = [c for c in ident if c != "study"]
    key = pd.Series([""] * len(df), index=df.index)
    for k, c in enumerate(shown):  # "a=1, b=2": column by column, not a Python join per row
        key = key + (", " if k else "") + c + "=" + _identity_text(df[c].astype(str))
    df["_occurrence"] = key.groupby(key).cumcount()  # rows with one identity: matched in order
    df["_key"] = key + " #" + df["_occurrence"].astype(str)
    return df.set_index("_key")


def _identity_text(values: pd.Series) -> pd.Series:
    """An identity column's texts with each float in the text ``results.csv`` writes now
    (:func:`experiments.csvtext.float_texts`: ``0.005``), also from a file of an earlier format (``%.17g``:
    ``0.0050000000000000001``), so that the same parameter is the same identity; integers and other texts as they are
    (a seed beyond 2**53 stays exact)."""
    floats = values.str.fullmatch(r"[-+]?(\d+\.\d*|\.\d+|\d+(\.\d*)?[eE][-+]?\d+)")
    if not floats.any():
        return values
    from experiments.csvtext import float_texts
    out = values.copy()
    out[floats] = float_texts(values[floats].astype(float).to_numpy())
    return out


def _number(values: pd.Series) -> np.ndarray | None:
    """The column as floats ('' is NaN), or None when it is not numeric."""
    v = values.replace({"": "nan", "True": "1", "False": "0"})
    try:
        return v.astype(float).to_numpy()
    except (TypeError, ValueError):
        return None


def _unit(cfg: dict | None, column: str) -> str:
    """The unit of ``column``'s values (``experiments.units.value_unit``: a length in the study's unit of lengths, mm
    for the machine-tool data), from the study's config as ``meta.json`` records it; without the config a length is in
    the data's unit; '' for a count, a flag or a text."""
    from experiments.units import DATA_UNITS, LENGTH_UNITS, column_unit, value_unit
    if isinstance(cfg, dict):
        return value_unit(cfg, column)
    return DATA_UNITS if column_unit(column) in LENGTH_UNITS else value_unit({}, column)


def compare_study(study: str, committed: pd.DataFrame, fresh: pd.DataFrame,
                  kernels: tuple[str, str] | None = None, cfg: dict | None = None) -> dict:
    """Every column outside its tolerance, with its worst rows: {study, rows, columns, problems: [...]}; each problem
    with the ``unit`` of its column's values (and of its atol), from the study's config ``cfg`` (:func:`_unit`).

    ``kernels``: the kernel backends (``meta.json`` ``kernels``) of the committed run and of this one. When they
    differ (compiled against ``FITBENCH_KERNELS=numpy``), the differences that backend explains are listed apart,
    in ``kernel_differences``, not in ``problems``: of an iterative method, its status, flags and counts
    (:data:`STOPPING`), and every value of a row whose status differs between the runs (:data:`BACKEND_WHY`). A
    value of a row that has the same status in both runs, a closed-form or convex method, a missing row or column
    stays a problem; with one backend on both sides nothing is set apart."""
    ident = identity_columns(committed)
    a, b = _keyed(committed, ident), _keyed(fresh, [c for c in ident if c in fresh.columns])
    problems = []
    missing = a.index.difference(b.index)
    extra = b.index.difference(a.index)
    for label, keys in (("row missing in this run", missing), ("row not in the committed results", extra)):
        if len(keys):
            problems.append({"column": "(rows)", "n_rows": int(len(keys)), "problem": label,
                             "worst": [{"row": k, "committed": "", "this_run": "", "difference": ""}
                                       for k in list(keys)[:WORST_ROWS]]})
    common = a.index.intersection(b.index)
    a, b = a.loc[common], b.loc[common]
    compared = 0
    # A row that did not converge (the same status other than "ok" in both runs) carries no geometric result: its values
    # are where the iteration stopped, which rounding moves; its status and counts are compared, its values are not.
    if "status" in a and "status" in b:
        st_a, st_b = a["status"].astype(str).to_numpy(), b["status"].astype(str).to_numpy()
        stopped = np.asarray((st_a == st_b) & (st_a != "ok"), dtype=bool)
    else:
        stopped = np.zeros(len(a), dtype=bool)
    not_compared = 0
    # a column that one side lacks is a difference (a table that lost radius or every metric never agrees)
    for col in [c for c in fresh.columns if c not in committed.columns and not c.startswith("_")]:
        if tolerance(col, study) is not None:
            problems.append({"column": col, "n_rows": int(len(b)), "problem": "column missing in the committed results",
                             "worst": []})
    methods = _method_kinds(a["method"] if "method" in a else pd.Series([""] * len(a), index=a.index))
    other_backend = bool(kernels) and kernels[0] != kernels[1]
    if other_backend:
        iterative = np.array([_iterative(m) for m in methods[0]], dtype=bool)[methods[1]]
        flipped = (np.asarray(a["status"].astype(str).to_numpy() != b["status"].astype(str).to_numpy(), dtype=bool)
                   if "status" in a and "status" in b else np.zeros(len(a), dtype=bool))
    explained_problems, explained_rows = [], np.zeros(len(a), dtype=bool)
    for col in committed.columns:
        if col.startswith("_") or (col in ident and col in fresh.columns):
            continue
        if col not in b.columns:
            if tolerance(col, study) is not None:
                problems.append({"column": col, "n_rows": int(len(a)), "problem": "column missing in this run", "worst": []})
            continue
        tol_of, keep, skipped, (rtol, atol) = _compared_rows(study, col, methods, stopped)
        not_compared += skipped
        if not keep.any():
            continue
        compared += 1
        old, new = a[col], b[col]
        x, y = _number(old), _number(new)
        if x is not None and y is not None:
            both_nan = np.isnan(x) & np.isnan(y)
            diff = np.abs(y - x)
            ok = both_nan | (diff <= atol + rtol * np.abs(x))
            excess = np.where(ok, 0.0, np.where(np.isnan(diff), np.inf, diff / np.maximum(atol + rtol * np.abs(x), 1e-300)))
        else:
            ok = (old.to_numpy() == new.to_numpy())
            excess = np.where(ok, 0.0, np.inf)
            diff = None
        bad = ~ok & keep
        explained = np.zeros(len(bad), dtype=bool)
        if other_backend:
            explained = bad & iterative & (flipped | (col in STOPPING))
            explained_rows |= explained
        for rows, into in ((bad & ~explained, problems), (explained, explained_problems)):
            if rows.any():
                order = np.argsort(-excess[rows], kind="stable")[:WORST_ROWS]
                idx = np.flatnonzero(rows)[order]
                t = tol_of[methods[1][idx[0]]]   # the worst row's method's tolerance
                into.append({
                    "column": col, "n_rows": int(rows.sum()),
                    "problem": "differs" if t.rtol == t.atol == 0 else f"outside rtol={t.rtol:g}, atol={t.atol:g}",
                    "unit": "" if diff is None else _unit(cfg, col),
                    "worst": [{"row": a.index[i], "committed": old.iloc[i], "this_run": new.iloc[i],
                               "difference": "" if diff is None else f"{diff[i]:.3g}"} for i in idx]})
    out = {"study": study, "rows": int(len(committed)), "columns": compared, "agree": not problems,
           "problems": problems, "not_converged_values": not_compared}
    if other_backend:
        out["kernels"] = {"committed": kernels[0], "this_run": kernels[1]}
        out["kernel_differences"] = explained_problems
        out["kernel_rows"] = int(explained_rows.sum())
        out["kernel_methods"] = sorted({methods[0][k] for k in methods[1][explained_rows]})
    return out


def _iterative(method_id: str) -> bool:
    """Whether ``method_id`` is registered as iterative (an unknown id is not: its differences stay problems)."""
    from methods import UnknownMethodError, get
    try:
        return get(method_id).kind == "iterative"
    except (UnknownMethodError, ValueError):
        return False


def _method_kinds(methods: pd.Series) -> tuple[list, np.ndarray]:
    """(the distinct methods, each row's index among them): made once for all the columns of a table."""
    row_kind, kinds = pd.factorize(methods.astype(str).to_numpy())
    return list(kinds), row_kind


def _compared_rows(study: str, col: str, method_kinds: tuple[list, np.ndarray], stopped: np.ndarray):
    """(each distinct method's tolerance, which rows are compared, how many values of rows that stopped in both runs
    are not, each row's (rtol, atol)) of one column: one tolerance per distinct method (:func:`_method_kinds`; row i's
    is ``tol_of[row_kind[i]]``), spread to the rows as arrays (not one lookup or list entry per row and column)."""
    kinds, row_kind = method_kinds
    tol_of = [tolerance(col, study, m) for m in kinds]
    keep = np.array([t is not None for t in tol_of], dtype=bool)[row_kind]
    inexact = np.array([t is not None and (t.rtol, t.atol) != (0.0, 0.0) for t in tol_of], dtype=bool)[row_kind]
    skipped = int((keep & inexact & stopped).sum())
    bounds = (np.array([t.rtol if t else 0.0 for t in tol_of])[row_kind], np.array([t.atol if t else 0.0 for t in tol_of])[row_kind])
    return tol_of, keep & ~(inexact & stopped), skipped, bounds


def self_comparison(study: str, folder: Path) -> dict:
    """What :func:`compare_study` says of ``folder/study/results.csv`` compared with itself (a reference byte for byte
    the same: a re-run whose rows all came from the store), from the table's header and its method and status
    columns: every row agrees; the compared columns and the values of rows that did not converge are counted as
    :func:`compare_study` counts them."""
    path = Path(folder) / study / "results.csv"
    header = pd.read_csv(path, dtype=str, keep_default_na=False, nrows=0).columns
    if "status" not in header or "method" not in header:
        _read(folder, study, "--out")  # the one-line error of a table that is not a results table
    df = pd.read_csv(path, dtype=str, keep_default_na=False, usecols=["method", "status"])
    if df.empty:
        _read(folder, study, "--out")  # the one-line error of a table without rows
    stopped = np.asarray(df["status"].to_numpy() != "ok", dtype=bool)
    ident = identity_columns(pd.DataFrame(columns=header))
    compared = not_compared = 0
    methods = _method_kinds(df["method"])
    for col in header:
        if col.startswith("_") or col in ident:
            continue
        _, keep, skipped, _ = _compared_rows(study, col, methods, stopped)
        not_compared += skipped
        compared += bool(keep.any())
    return {"study": study, "rows": int(len(df)), "columns": compared, "agree": True, "problems": [],
            "not_converged_values": not_compared}


def _table(problems: list[tuple[str, dict]]) -> str:
    head = ["study", "column", "rows outside", "problem", "worst row (identity)", "committed", "this run", "|difference|"]
    lines = []
    for study, p in problems:
        worst = p["worst"] or [{"row": "", "committed": "", "this_run": "", "difference": ""}]
        unit = p.get("unit") or ""
        with_unit = (lambda v: f"{v} {unit}" if unit and str(v) not in ("", "nan") else str(v))  # noqa: E731
        problem = p["problem"] + (f" {unit}" if unit and p["problem"].startswith("outside rtol=") else "")  # the atol's
        for k, w in enumerate(worst):
            lines.append([study if k == 0 else "", p["column"] if k == 0 else "", str(p["n_rows"]) if k == 0 else "",
                          problem if k == 0 else "", w["row"], with_unit(w["committed"]), with_unit(w["this_run"]),
                          with_unit(w["difference"])])
    widths = [max(len(h), *(len(r[i]) for r in lines)) for i, h in enumerate(head)]
    fmt = lambda r: "  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip()  # noqa: E731
    return "\n".join([fmt(head), fmt(["-" * w for w in widths])] + [fmt(r) for r in lines])


def _shown(path: Path) -> str:
    """``path`` as a verdict records it (the file may be committed): relative to the current folder when inside
    it (``results/quick``), else its last two parts after ``.../`` (``.../review-q/noise``), saying that the
    folders of this machine before them are left out (``review-q/noise`` alone reads as a relative path that
    leads nowhere)."""
    p = Path(path).resolve()
    try:
        return p.relative_to(Path.cwd().resolve()).as_posix() or "."
    except ValueError:
        return ".../" + Path(*p.parts[-2:]).as_posix()


def _meta(folder: Path) -> dict | None:
    path = folder / "meta.json"
    if not path.is_file():  # a FIFO or a device would block the read: no meta.json to use
        return None
    try:
        meta = json_value(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return meta if isinstance(meta, dict) else None


def _kernels(committed: Path, fresh: Path) -> tuple[str, str] | None:
    """(committed, this run) kernel backends as their ``meta.json`` record them (``environment.kernels``), None when either
    does not say."""
    pair = tuple(((m or {}).get("environment") or {}).get("kernels") if isinstance((m or {}).get("environment"), dict)
                 else None for m in (_meta(committed), _meta(fresh)))
    return pair if all(isinstance(k, str) and k for k in pair) else None


def kernel_note(report: dict) -> str:
    """What a study's verdict adds when the two runs used other kernel backends ('' when they used one): which
    differences that explains (or that none remain)."""
    k = report.get("kernels")
    if not k:
        return ""
    head = f"; committed with the {k['committed']} kernels, this run with the {k['this_run']} kernels"
    diffs = report.get("kernel_differences") or []
    if not diffs:
        return head + ": no value differs between them"
    n = sum(p["n_rows"] for p in diffs)
    cols = ", ".join(dict.fromkeys(p["column"] for p in diffs))
    return (f"{head}: besides, {n} value(s) in {report.get('kernel_rows', '?')} row(s) of the iterative "
            f"{', '.join(report.get('kernel_methods', []))} differ ({cols}) where the backends' last bits move an "
            f"iteration near its stopping test (listed below; expected between backends, never within one)")


def _same_inputs(committed: Path, fresh: Path) -> None:
    """Refuse (one line) to compare two runs of a study whose ``meta.json`` record other inputs (another seed,
    other repetitions or grid, edited data): their rows differ by design, not by the code."""
    old, new = _meta(committed), _meta(fresh)
    if old is None or new is None:
        return
    changes = changed_inputs(old, recorded_inputs(new))
    if changes:
        raise InvalidInputError(f"{fresh} holds a run of another config or data than {committed} "
                                f"({'; '.join(changes)}): other rows by design, nothing to compare; compare runs of "
                                f"one config, or regenerate the committed results with python -m experiments.run")


def verify(studies: list[str], results: Path, against: Path, log=print, write: bool = False,
           against_name: str | None = None) -> dict:
    """Compare ``against`` with the committed ``results``; the verdict dict. Only with ``write`` is it recorded
    in ``RESULTS/verify.json`` (the verdict the report of ``results`` shows): a check leaves both folders as
    they were unless asked. ``against_name`` names ``against`` when it is a temporary run (default: its path)."""
    reports = []
    date = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    for study in studies:
        committed = _read(results, study, "--results")
        fresh = _read(against, study, "--against")
        _same_inputs(results / study, against / study)
        reports.append({**compare_study(study, committed, fresh, _kernels(results / study, against / study),
                                        (_meta(results / study) or {}).get("config")), "date": date,
                        "results_sha256": results_sha256(results / study),   # what this verdict judged
                        "fingerprint": _fingerprint(results / study),
                        "reference_fingerprint": _fingerprint(against / study),
                        "against_sha256": results_sha256(against / study),
                        "reference": against_name or f"the run in {_shown(against / study)}"})
    for r in reports:
        n_bad = sum(p["n_rows"] for p in r["problems"])
        skipped = (f"; {r['not_converged_values']} value(s) of rows that did not converge in both runs not compared "
                   "(their status and counts are)") if r["not_converged_values"] else ""
        log(f"{r['study']}: " + ((f"agree except where the kernel backends part ({r['rows']} rows, {r['columns']} "
                                   f"columns; every other value within its tolerance{skipped})")
                                  if r["agree"] and r.get("kernel_differences") else
                                  f"agree ({r['rows']} rows, {r['columns']} columns within their tolerances{skipped})"
                                  if r["agree"] else
                                  f"DIFFER: {len(r['problems'])} column(s) outside tolerance, {n_bad} value(s){skipped}")
            + kernel_note(r))
    bad = [(r["study"], p) for r in reports for p in r["problems"]]
    if bad:
        log("")
        log(_table(bad))
    by_kernels = [(r["study"], p) for r in reports for p in r.get("kernel_differences", [])]
    if by_kernels:
        log("")
        log(f"Differences the other kernel backend explains (not counted above; why: {BACKEND_WHY}):")
        log(_table(by_kernels))
    if CHAOTIC:
        by_reason: dict[str, list[str]] = {}
        for (s, m, c), t in CHAOTIC.items():
            by_reason.setdefault(t.why, []).append(f"{s}/{m}/{c} rtol={t.rtol:g} atol={t.atol:g}")
        log("wider tolerances declared for methods chaotic by nature: " +
            "; ".join(f"{', '.join(cols)} (why: {why})" for why, cols in by_reason.items()))
    verdict = {"agree": not bad, "date": date, "results": _shown(results), "against": against_name or _shown(against),
               "studies": reports}
    if write:
        write_atomic(results / VERDICT_FILE, json.dumps(verdict, indent=1, default=str) + "\n")
    return verdict


def _committed(path: Path) -> bool:
    """Whether ``path`` is tracked by git and unchanged since the last commit."""
    import subprocess
    try:
        tracked = subprocess.run(["git", "ls-files", "--error-unmatch", "--", path.name], cwd=path.parent,
                                 capture_output=True, timeout=10)
        same = subprocess.run(["git", "diff", "--quiet", "HEAD", "--", path.name], cwd=path.parent,
                              capture_output=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return False
    return tracked.returncode == 0 and same.returncode == 0


#: config keys that only present or schedule a study's rows, never change them: a change of these keeps the
#: previous results comparable
PRESENTATION = frozenset({"title", "description", "default", "report", "tables", "figures", "summary_by",
                          "max_jobs", "chunk_rows", "row_timeout"})


def study_data_files(cfg: dict) -> list[tuple[str, str]]:
    """[("datasets[i]", path)] of the files the study's data sets read (a ``file`` source, a published set;
    ``Study.data_sets``: its ``[[datasets]]`` unless its own tasks read others)."""
    from experiments.codekeys import data_files
    from experiments.engine import expand_datasets
    from experiments.studies import study_of
    specs = study_of(cfg["kind"]).data_sets(cfg)
    return [(f"datasets[{spec['entry']}]", f)
            for spec in (specs if specs is not None else expand_datasets(cfg, getattr(cfg, "where", cfg.get("name", "?"))))
            for f in data_files(spec)]


def _data_files(cfg: dict) -> dict[str, str]:
    """{"datasets[i] NAME": SHA-256} of the files the study's data sets read (:func:`study_data_files`), named without
    the folders of this machine."""
    out = {}
    for where, f in study_data_files(cfg):
        digest = hashlib.sha256()
        with open(f, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
        out[f"{where} {Path(f).name}"] = digest.hexdigest()
    return out


def inputs(cfg: dict) -> dict:
    """What a study's rows are computed from besides the code (``meta.json`` records it): its config without the
    keys that only present or schedule the rows (:data:`PRESENTATION`), seed and repetitions included, and the
    SHA-256 of each data file it reads. Two runs with the same inputs ask for the same rows from the same data;
    the code may differ (that is what a verdict checks)."""
    config = json.loads(json.dumps(dict(cfg), sort_keys=True, default=str))
    return {"config": {k: v for k, v in config.items() if k not in PRESENTATION}, "data_files": _data_files(cfg)}


def _short(value) -> str:
    text = json.dumps(value, sort_keys=True, default=str)
    return text if len(text) <= 40 else text[:37] + "..."


def recorded_inputs(meta: dict) -> dict:
    """The inputs a ``meta.json`` records (:func:`inputs`); one written before they were recorded gives its config
    (without :data:`PRESENTATION`) and ``data_files`` None (unknown)."""
    recorded = meta.get("inputs")
    if isinstance(recorded, dict) and isinstance(recorded.get("config"), dict):
        files = recorded.get("data_files")
        return {"config": recorded["config"], "data_files": files if isinstance(files, dict) else None}
    config = meta.get("config")
    return {"config": {k: v for k, v in config.items() if k not in PRESENTATION} if isinstance(config, dict) else {},
            "data_files": None}


def changed_inputs(old_meta: dict, now: dict) -> list[str]:
    """What differs between the inputs of a previous run (its ``meta.json``) and ``now`` (:func:`inputs`, or
    :func:`recorded_inputs` of another run), one phrase each ("repetitions 250, now 200", "data file datasets[0]
    trace.csv changed"); empty when they are the same. Data files are compared where both runs recorded them."""
    old = recorded_inputs(old_meta)
    old_cfg, old_files, new_cfg, new_files = old["config"], old["data_files"], now["config"], now["data_files"]
    changes = [(f"{k} {_short(old_cfg[k])}, now {_short(new_cfg[k])}" if k in old_cfg and k in new_cfg else
                f"{k} {'added' if k in new_cfg else 'removed'}")
               for k in sorted(set(old_cfg) | set(new_cfg)) if old_cfg.get(k) != new_cfg.get(k)]
    if isinstance(old_files, dict) and isinstance(new_files, dict):
        by_change: dict[str, list[str]] = {}
        for k in sorted(set(old_files) | set(new_files), key=_natural):
            if old_files.get(k) != new_files.get(k):
                how = "changed" if k in old_files and k in new_files else "added" if k in new_files else "removed"
                by_change.setdefault(how, []).append(k)
        for how, keys in by_change.items():  # a long list is named by its first three
            named = ", ".join(keys[:3]) + (f" and {len(keys) - 3} more" if len(keys) > 3 else "")
            changes.append(f"data file {named} {how}" if len(keys) == 1 else f"data files {named} {how}")
    return changes


def _natural(key: str) -> list:
    """A sort key putting datasets[2] before datasets[10]."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", key)]


def reference_snapshot(out: Path, names: list[str], quick: bool, into: Path,
                       inputs_now: dict[str, dict] | None = None) -> dict[str, dict]:
    """Before ``experiments.run`` writes into ``out``: for each study, a copy (under ``into``) of the results the
    fresh run will be compared with, and how to name them. The reference is the study's results already in
    ``out`` (a rerun), else the committed ones in ``results/`` (``results/quick/`` with ``--quick``) of the
    current folder; only a run of the same grid (quick or full) and, when ``inputs_now`` gives the study's
    :func:`inputs`, of the same inputs is a reference (other repetitions, another seed or edited data give other
    rows by design). A study whose only previous results are of other inputs gets ``{"other": why}``: not
    compared."""
    refs = {}
    committed_root = Path("results/quick" if quick else "results")
    for name in names:
        for folder in (Path(out) / name, committed_root / name):
            csv, meta_path = folder / "results.csv", folder / "meta.json"
            if not csv.is_file() or not meta_path.is_file():
                continue
            try:
                meta = json_value(meta_path.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                continue
            if not isinstance(meta, dict) or bool(meta.get("quick")) != quick:
                continue
            changes = changed_inputs(meta, inputs_now[name]) if inputs_now and name in inputs_now else []
            if changes:
                refs.setdefault(name, {"other": f"the previous results in {_shown(folder)} are of another config or data "
                                                f"({'; '.join(changes)})"})
                continue
            (into / name).mkdir(parents=True, exist_ok=True)
            (into / name / "results.csv").write_bytes(csv.read_bytes())
            commit = str(meta.get("git_commit") or "?")[:10]
            what = "the committed tables" if _committed(csv) else "the previous results"
            (into / name / "meta.json").write_bytes(meta_path.read_bytes())  # its kernel backend, for the verdict
            refs[name] = {"folder": into,
                          "reference": f"{what} ({_shown(folder)}, commit {commit}, {meta.get('date', '?')})"}
            break
    return refs


OTHER_CODE = (", computed by other code or config (the study's fingerprint changed since: what changed may "
              "explain it; a reproducibility verdict compares runs of one code)")


def other_code(entry: dict) -> bool:
    """Whether a verdict compared results of other code or config (both fingerprints recorded, and they differ)."""
    a, b = entry.get("fingerprint"), entry.get("reference_fingerprint")
    return isinstance(a, str) and isinstance(b, str) and a != b


def _fingerprint(folder: Path) -> str | None:
    """The fingerprint ``meta.json`` records for a study's outputs (its rows' keys, config and the code that analyses
    them, this module included: ``experiments.engine.fingerprint``), None when there is none."""
    path = Path(folder) / "meta.json"
    if not path.is_file():
        return None
    try:
        value = json_value(path.read_text(encoding="utf-8")).get("fingerprint")
    except (OSError, ValueError, AttributeError):
        return None
    return value if isinstance(value, str) else None


def verdict_after_run(out: Path, names: list[str], refs: dict[str, dict], log=print) -> dict:
    """After ``experiments.run``: compare each fresh study in ``out`` with its reference (``reference_snapshot``)
    and record the verdicts in ``out/verify.json`` (other studies' entries are kept; each names the SHA-256 of
    the results it judged), with the run's date and studies (the report says which results are older)."""
    date = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    old = last_verdict(out) or {}
    entries = {s["study"]: s for s in old.get("studies", []) if isinstance(s, dict) and isinstance(s.get("study"), str)}
    for name in names:
        before = entries.pop(name, None)
        ref = refs.get(name)
        if ref is None:
            log(f"verify: {name}: no committed results to compare with (results/{name} of the same grid)")
            continue
        if "other" in ref:
            log(f"verify: {name}: not compared: {ref['other']}; other rows by design")
            continue
        fresh_sha, ref_sha = results_sha256(Path(out) / name), results_sha256(ref["folder"] / name)
        judged = {"results_sha256": fresh_sha, "reference_sha256": ref_sha, "reference": ref["reference"],
                  "fingerprint": _fingerprint(Path(out) / name),
                  "reference_fingerprint": _fingerprint(ref["folder"] / name)}
        if (isinstance(before, dict) and judged["fingerprint"] and fresh_sha
                and all(before.get(k) == v for k, v in judged.items())):
            r = before  # the same two tables judged by the same code (the study's fingerprint): the same verdict
        else:
            try:
                if fresh_sha is not None and fresh_sha == ref_sha:
                    r = self_comparison(name, Path(out))  # the same bytes: the verdict of a table on itself, cheaply
                else:
                    r = compare_study(name, _read(ref["folder"], name, "reference"), _read(Path(out), name, "--out"),
                                      _kernels(ref["folder"] / name, Path(out) / name),
                                      (_meta(Path(out) / name) or {}).get("config"))
            except InvalidInputError as exc:
                log(f"verify: {name}: not compared ({exc})")
                continue
            r = {**r, "date": date, **judged}
        entries[name] = r
        log(f"verify: {name}: " + ("reproduces " + ref["reference"] + kernel_note(r) if r["agree"] else
                                   f"DIFFERS from {ref['reference']}{OTHER_CODE if other_code(r) else ''} in: "
                                   + ", ".join(dict.fromkeys(f"{p['n_rows']} {p['problem'].replace('row ', 'rows ', 1)}"
                                                             if p["column"] == "(rows)" else p["column"]
                                                             for p in r["problems"]))))
    studies = list(entries.values())
    # no study compared: "agree" is null, never true over nothing (the file still records the run for the report)
    verdict = {"agree": all(s.get("agree") for s in studies) if studies else None, "date": date, "results": _shown(out),
               "studies": studies, "run": {"date": date, "studies": list(names)}}
    write_atomic(Path(out) / VERDICT_FILE, json.dumps(verdict, indent=1, default=str) + "\n")
    return verdict
