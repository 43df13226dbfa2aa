"""The reproducibility verdicts the report shows, read from ``RESULTS/verify.json``.

``python -m experiments.verify --write-verdict`` and the end of ``python -m experiments.run`` write that file; each study's
entry names the SHA-256 of the ``results.csv`` it judged (``results_sha256``, the file in the folder that holds
``verify.json``). The report shows a verdict only while that file is unchanged: after the study is run again
with other numbers the old verdict is reported as out of date, never as agreement.

This module only reads (the report does not depend on the command that runs studies).
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

from experiments.jsontext import json_value
from methods.files import open_regular

VERDICT_FILE = "verify.json"


def results_sha256(folder: Path) -> str | None:
    """SHA-256 of ``folder/results.csv`` (None when it cannot be read), read a block at a time."""
    try:
        with open(Path(folder) / "results.csv", "rb") as fh:
            digest = hashlib.sha256()
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
            return digest.hexdigest()
    except OSError:
        return None


def recorded_config(study_folder: Path) -> Path | None:
    """The TOML file a study's ``meta.json`` records it ran from (``config_file``, ``experiments.run.config_file``:
    a project study's relative to the checkout; another relative to the results folder that holds
    ``study_folder`` when ``config_file_relative_to`` says so, else absolute), None when it records none or is
    unreadable."""
    from experiments.provenance import REPO
    try:
        with open_regular(Path(study_folder) / "meta.json") as fh:
            meta = json_value(fh.read())
        value, base = meta.get("config_file"), meta.get("config_file_relative_to")
    except (OSError, ValueError, AttributeError):
        return None
    if not isinstance(value, str) or not value.endswith(".toml"):
        return None
    path = Path(value)
    if path.is_absolute():
        return path
    if base != "results folder":
        return REPO / path
    path = Path(study_folder).parent / path   # its folder resolved (a link before '..'), the file itself kept: a link
    return path.parent.resolve() / path.name  # to a TOML of another name is the file the run was given


def is_project_study(study_folder: Path, known) -> bool:
    """Whether the study in ``study_folder`` is the project's study of its name (``known``: the project's study
    names): its ``meta.json`` records the project's ``experiments/configs/NAME.toml``, or no TOML (a run older than
    that record: the name decides). A user's TOML may bear a project study's name (a config's name is only
    required to match its file's): its results are not the project study's, and are rerun from that TOML."""
    name = Path(study_folder).name
    if name not in known:
        return False
    recorded = recorded_config(study_folder)
    return recorded is None or recorded.resolve() == (_CONFIG_DIR / f"{name}.toml").resolve()


#: the project's study configs (``experiments.config.CONFIG_DIR``, the same folder; not imported from there: the config
#: module imports the engine, which imports this module)
_CONFIG_DIR = Path(__file__).resolve().parent / "configs"


def last_verdict(results: Path) -> dict | None:
    """The verdict file of ``results`` (None when there is none or it is unreadable)."""
    try:   # a regular file only: a FIFO there blocked the report (NotRegularFileError is a ValueError)
        with open_regular(Path(results) / VERDICT_FILE) as fh:
            verdict = json.loads(fh.read())
    except (OSError, ValueError):
        return None
    return verdict if isinstance(verdict, dict) and "agree" in verdict and isinstance(verdict.get("studies"), list) \
        else None


def current_entries(results: Path) -> tuple[dict, dict]:
    """({study: entry} whose judged results.csv is still the one in ``results``, {study: entry} out of date)."""
    v = last_verdict(results)
    current, stale = {}, {}
    for s in (v or {}).get("studies", []):
        if not isinstance(s, dict) or not isinstance(s.get("study"), str):
            continue
        judged = s.get("results_sha256")
        now = results_sha256(Path(results) / s["study"])
        (current if judged and judged == now else stale)[s["study"]] = s
    return current, stale


def carried_over(results: Path) -> tuple[dict, str | None]:
    """({study: entry} of the current verdicts the last ``experiments.run`` into ``results`` did not make, the date of
    that run): a study it did not run (its data not available there, not asked for) keeps the verdict of an earlier run
    or check, which is not a reproduction by that run. ({}, None) when the verdict file is not a run's."""
    v = last_verdict(results) or {}
    run = v.get("run")
    if not isinstance(run, dict) or not isinstance(run.get("studies"), list):
        return {}, None
    current, _ = current_entries(results)
    return {k: e for k, e in current.items() if k not in run["studies"]}, str(run.get("date") or "?")


def _columns(entry: dict) -> str:
    cols = [str(p.get("column")) for p in entry.get("problems", []) if isinstance(p, dict)]
    return ", ".join(cols[:8]) + (f" and {len(cols) - 8} more" if len(cols) > 8 else "")


def study_sentence(entry: dict) -> str:
    """One sentence (plain text) for a current verdict: reproduces, or which columns differ."""
    ref = entry.get("reference") or "the committed tables"
    when = entry.get("date") or "?"
    kernels, by_kernels = entry.get("kernels"), entry.get("kernel_differences") or []
    if entry.get("agree") and isinstance(kernels, dict) and by_kernels:
        cols = ", ".join(dict.fromkeys(str(p.get("column")) for p in by_kernels if isinstance(p, dict)))
        return (f"Verdict ({when}): this run reproduces {ref} within the declared tolerances "
                f"({entry.get('rows', '?')} rows, {entry.get('columns', '?')} columns) except where the kernel "
                f"backends part: {ref} used the {kernels.get('committed', '?')} kernels, this run the "
                f"{kernels.get('this_run', '?')} kernels, and {entry.get('kernel_rows', '?')} row(s) of the iterative "
                f"{', '.join(map(str, entry.get('kernel_methods', [])))} differ in {cols} (an iteration near its "
                f"stopping test; details: verify.json).")
    if entry.get("agree"):
        return (f"Verdict ({when}): this run reproduces {ref} within the declared tolerances "
                f"({entry.get('rows', '?')} rows, {entry.get('columns', '?')} columns).")
    if _other_code(entry):
        return (f"Verdict ({when}): this run differs from {ref} in: {_columns(entry)}; those results were computed "
                f"by other code or another config (the study's fingerprint changed since), so the change may "
                f"explain the difference: this is not a reproducibility check (details: verify.json).")
    return f"Verdict ({when}): this run differs from {ref} in: {_columns(entry)} (details: verify.json)."


def _other_code(entry: dict) -> bool:
    """A verdict between results of other code or config (``experiments.compare.other_code``; read here without
    importing the comparison)."""
    a, b = entry.get("fingerprint"), entry.get("reference_fingerprint")
    return isinstance(a, str) and isinstance(b, str) and a != b


def grid_options(results: Path, quick: bool, shown: str | None = None) -> tuple[str, str]:
    """(' --quick' or '', ' DIR' or '') of the commands that write or check the results in ``results``: the
    folder is named unless it is the default of its grid (``results/``; ``results/quick/`` with --quick),
    as ``shown`` (default: the path as given), quoted for a shell."""
    import shlex
    default = Path("results/quick" if quick else "results")
    same = Path(results).resolve() == default.resolve()
    return (" --quick" if quick else ""), ("" if same else " " + shlex.quote(shown or str(results)))


def study_verdicts(results: Path, studies: list[str], reasons: dict[str, str] | None = None,
                   quick: dict[str, bool] | None = None, shown: str | None = None,
                   commands: dict[str, str] | None = None) -> dict[str, list[tuple[str, str]]]:
    """{study: [(label, plain sentence), ...]} for the report: the current verdict, an out-of-date one said to
    be out of date, and a study not in the last ``experiments.run`` said to come from an earlier run
    (``reasons``: why that run did not include it, e.g. "not a default study"). The commands it suggests
    regenerate or check these results: with --quick where the study ran the quick grid (``quick``: study ->
    bool), the folder (``shown``: how to name ``results``) unless it is the grid's default, and the study as a
    command names it (``commands``: study -> its name, or its TOML file for a study that is not the project's;
    default: the name)."""
    current, stale = current_entries(results)
    v = last_verdict(results) or {}
    run = v.get("run") if isinstance(v.get("run"), dict) else None
    out: dict[str, list[tuple[str, str]]] = {}
    for name in studies:
        lines = []
        q, folder = grid_options(results, bool((quick or {}).get(name)), shown)
        called = (commands or {}).get(name, name)
        if name in current:
            e = current[name]
            lines.append(("Reproducibility" if e.get("agree") else
                          "Changed since the compared results" if _other_code(e) else "Reproducibility: differs",
                          study_sentence(e)))
        elif name in stale:
            lines.append(("Reproducibility: out of date",
                          f"The last verification ({stale[name].get('date', '?')}) judged other results than these "
                          f"(results.csv changed since); run python -m experiments.verify {called}{q}"
                          f"{' --results' + folder if folder else ''} --write-verdict again."))
        if run and name not in run.get("studies", []):
            lines.append(("Older results", f"These results are older than the last run ({run.get('date', '?')}), which "
                          f"did not include this study ({(reasons or {}).get(name, 'not among the studies it ran')}); "
                          f"rerun it with python -m experiments.run {called}{q}"
                          f"{' --out' + folder if folder else ''}."))
        if lines:
            out[name] = lines
    return out


def verdict_markdown(results: Path, quick: bool = False, shown: str | None = None) -> list[str]:
    """Lines for the report: the current verdicts in one sentence (out-of-date ones are not counted). The command it
    suggests checks ``results`` (``shown``: how to name it; with --quick for a folder of quick runs)."""
    from experiments.render.markdown import md_code
    from experiments.render.page import md_escape
    current, stale = current_entries(results)
    if not current:
        q, folder = grid_options(results, quick, shown)
        command = f"python -m experiments.verify{q}{' --results' + folder if folder else ''} --write-verdict"
        return [f"No current reproducibility verdict: run {md_code(command)}"
                + (f" (the last one judged other results for {len(stale)} "
                   f"{'study' if len(stale) == 1 else 'studies'})" if stale else "") + "."]
    changed = [k for k, e in current.items() if not e.get("agree") and _other_code(e)]
    current = {k: e for k, e in current.items() if k not in changed}
    differ = [k for k, e in current.items() if not e.get("agree")]
    tail = f" ({len(stale)} older verdicts are out of date and not counted)" if stale else ""
    head = [f"{md_escape(', '.join(changed))} {'differs' if len(changed) == 1 else 'differ'} from the results "
            f"{'it was' if len(changed) == 1 else 'they were'} compared with, which other code or another config "
            f"computed (not a reproducibility check; see `verify.json`)."] if changed else []
    if not current:
        return head
    carried, run_date = carried_over(results)
    carried = {k: e for k, e in carried.items() if k in current}
    if carried:   # verdicts the last run did not make: counted apart, never as reproduced by it
        tail += (f"; {len(current) - len(carried)} of them checked by the last run ({run_date}), {len(carried)} "
                 f"carried over from an earlier verdict, not rerun by it: "
                 + md_escape(", ".join(f"{k} ({'agrees' if e.get('agree') else 'differs'}, {e.get('date', '?')})"
                                       for k, e in carried.items())))
    if not differ:
        return [f"Reproducibility: all {len(current)} verified {'study agrees' if len(current) == 1 else 'studies agree'} "
                f"with these results within the declared "
                f"tolerances{tail}."] + head
    return [f"Reproducibility: {len(differ)} of {len(current)} verified studies differ beyond the declared tolerances "
            f"({md_escape(', '.join(differ))}); see `verify.json`{tail}."] + head
