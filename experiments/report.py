"""``python -m experiments.report [--results DIR] [--out DIR]``: the comparison report, built only from
the studies' output in ``results/`` (default ``results/`` of the current folder -> ``paper/``; another folder
``DIR`` -> ``DIR/paper``, as ``experiments.run --out DIR`` does).

Writes ``report.md``, a self-contained ``report.html`` (images embedded, numbered captions, nav#toc, coloured
method tables), ``report.tex`` (compiles on A4) with the LaTeX table fragments ``tables/*.tex`` (siunitx,
split when too wide; ``experiments.render``) and every figure as PNG, with the vector PDF its study saved, under
``figures/``, and the section
"Rankings across data sets" (performance profiles of every ranking the studies declare, ``[[rankings]]``). A study
that is missing or whose rows failed is shown as such, never dropped; each study shows its current
reproducibility verdict (``experiments.verdict``). Also run at the end of ``python -m experiments.run``.

User text (titles, sections, captions, findings, labels) is text: it never names a file (figures are embedded
from the files this builder wrote), it is escaped for Markdown, HTML and LaTeX (``experiments.render.page``,
``experiments.render.text``). A build deletes only the files its previous build listed in ``.report-build.json``.
The report is built in a hidden folder and moved into place whole (:func:`build`): an error, Ctrl-C, SIGTERM or SIGHUP
leaves the folder as it was.
"""
from __future__ import annotations

if __name__ == "__main__":   # Ctrl-C, SIGTERM, SIGHUP while the command imports its modules: one line, no traceback
    from fitbench.stopping import quiet_while_starting
    quiet_while_starting("experiments.report")

import argparse
import hashlib
import json
import re
import sys
from pathlib import Path

import pandas as pd

from experiments import config as configs
from experiments.provenance import REPO
from experiments.jsontext import json_value
from methods import InvalidInputError
from methods.files import write_atomic

# ---------------------------------------------------------------- figures

def export_figure(png: Path, out_dir: Path, stem: str) -> tuple[Path, Path]:
    """Copy the PNG and, when the study saved one beside it (``experiments.render.style.save``), its vector
    PDF; return (PNG, the file the LaTeX report includes: the vector PDF, else the PNG)."""
    dst_png = out_dir / f"{stem}.png"
    write_atomic(dst_png, png.read_bytes())
    vector = png.with_suffix(".pdf")
    if vector.is_file() and not vector.is_symlink():
        data = vector.read_bytes()
        if data.startswith(b"%PDF-"):
            write_atomic(out_dir / f"{stem}.pdf", data)
            return dst_png, out_dir / f"{stem}.pdf"
    return dst_png, dst_png


# ---------------------------------------------------------------- assembly

def _shown(path: Path) -> str:
    """A folder as a report names it (the report is shared: no folder of this machine): relative to the checkout
    or the current folder when inside one, else ``.../`` and its last part."""
    p = Path(path).resolve()
    for base in (REPO, Path.cwd().resolve()):
        try:
            return p.relative_to(base).as_posix() or "."
        except ValueError:
            continue
    return ".../" + p.name


def _command_folder(path: Path) -> str:
    """A folder as a command in the report names it: :func:`_shown`, or its name alone when outside the checkout
    and the current folder (``--out r7plug_out``: run where that folder is, or name another)."""
    shown = _shown(path)
    return Path(path).resolve().name if shown.startswith(".../") else shown


def study_command_names(results: Path, names: list[str], known: dict) -> dict[str, str]:
    """{study: how a command names it}: a project study by its name; any other (also one named like a project
    study: ``experiments.verdict.is_project_study``) by the TOML file its ``meta.json`` records (``config_file``),
    relative to the current folder when it lies inside it, else by its file name (``NAME.toml``: the report names
    no folder of this machine), quoted for a shell."""
    import shlex
    from experiments.verdict import is_project_study, recorded_config
    out = {}
    for n in names:
        if is_project_study(results / n, known):
            out[n] = n
            continue
        path, shown = recorded_config(results / n), f"{n}.toml"
        if path is not None:
            try:
                shown = (path.parent.resolve() / path.name).relative_to(Path.cwd().resolve()).as_posix()
            except ValueError:
                pass
        out[n] = shlex.quote(shown)
    return out


def _reproduce(names: list[str], known: dict, quick: bool, folder_arg: str, called: dict | None = None) -> str:
    """The command(s) that reproduce the studies of this report (Markdown): the default studies' own command when
    the report holds just them in their folder, else one per study: a known study by name, a user's study by its
    TOML file (``called``: :func:`study_command_names`; ``meta.json`` records the config it ran)."""
    from experiments.render.markdown import md_code
    from experiments.render.page import md_escape
    if not names:   # every study of the folder is broken or unfinished: no command made what is shown
        return "no study in it is finished, so none can be reproduced from it (each study below says why)"
    called = {n: (n if n in known else f"{n}.toml") for n in names} | (called or {})
    q, out = (" --quick" if quick else ""), (f" --out{folder_arg}" if folder_arg else "")
    defaults = {n for n, c in known.items() if c.get("default")}
    every_default = bool(defaults) and defaults <= set(names)
    rest = [n for n in names if not (every_default and n in defaults)]
    commands = [f"{md_code(f'python -m experiments.run{q}{out}')} (the default studies)"] if every_default else []
    if rest:   # a command is shown literally (a code span), never Markdown-escaped: it is copied into a shell
        commands.append(md_code(f"python -m experiments.run {' '.join(called[n] for n in rest)}{q}{out}"))
    own = [n for n in names if n not in known]
    # the files' names are user text (escaped); `meta.json` is the builder's own code span
    note = (f" ({md_escape(', '.join(called[n] for n in own))}: the study's TOML file, wherever it is; the config "
            f"it ran is recorded in {'its' if len(own) == 1 else 'each'} `meta.json`)") if own else ""
    return f"reproduce {'it' if len(names) == 1 else 'them'} with " + " and ".join(commands) + note


PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


class BrokenStudy(Exception):
    """A study folder the report cannot use; the message says why."""


def _read_json(path: Path) -> dict:
    if not path.is_file():
        raise BrokenStudy(f"{path.name} is not a regular file")   # a FIFO would block the read
    try:
        data = json_value(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise BrokenStudy(f"{path.name} is unreadable ({type(exc).__name__}: {exc})") from None
    if not isinstance(data, dict):
        raise BrokenStudy(f"{path.name} is not a JSON object")
    return data


def is_study_folder(folder: Path) -> bool:
    """A folder the runner wrote (not, e.g., a paper/ build under the same --out)."""
    return folder.is_dir() and any((folder / f).exists() for f in ("meta.json", "results.csv", "rows.sqlite"))


def load_study(folder: Path) -> tuple[dict, dict]:
    """(meta, manifest) of a finished study; BrokenStudy says what is wrong."""
    if not (folder / "meta.json").exists() or not (folder / "results.csv").exists():
        raise BrokenStudy("unfinished: no meta.json or results.csv (the run was interrupted; run it again)")
    meta = _read_json(folder / "meta.json")
    if not (folder / "results.csv").is_file():
        raise BrokenStudy("results.csv is not a regular file")
    try:
        with open(folder / "results.csv", "rb") as fh:
            digest = hashlib.sha256(fh.read()).hexdigest()
    except OSError as exc:
        raise BrokenStudy(f"results.csv is unreadable ({exc})") from None
    if meta.get("results_sha256") and meta["results_sha256"] != digest:
        raise BrokenStudy("results.csv does not match meta.json (truncated or edited after the run)")
    if not (folder / "report.json").exists():
        raise BrokenStudy("no report.json (written by an older runner; run the study again)")
    return meta, _read_json(folder / "report.json")


#: what a row of each status other than "ok" is, in the report's words (label, what it is); the statuses of the engine
#: (``experiments.rows``: error, and the environment's timeout, crashed, unavailable), of a family's contract (invalid)
#: and of the studies (not converged, skipped); any other status is named as it is. The values of the tables and
#: figures are those of the "ok" rows (a share of ok rows counts the others as failures).
_AGAIN = "the next `python -m experiments.run` runs them again"
LEFT_OUT = {
    "error": ("failed rows", "the method raised an error: no result (the messages are in `results.csv`)"),
    "invalid": ("invalid results", "results that broke their family's contract: not used (the reasons are in "
                                   "`results.csv`)"),
    "timeout": ("timed-out rows", f"ended at the row time-out: no result ({_AGAIN})"),
    "crashed": ("crashed rows", f"the worker process running them died: no result ({_AGAIN})"),
    "unavailable": ("unavailable rows", "the method could not run here (a kernel not built, a module that does not "
                                        f"import): no result ({_AGAIN})"),
    "not converged": ("rows not converged", "the method reported no converged result (an iteration that stopped, a "
                                            "solution that does not exist): their values are not a result (the "
                                            "reasons are in `results.csv`)"),
    "skipped": ("skipped rows", "the method does not apply to these data: no result (the reasons are in "
                                "`results.csv`)"),
}


def left_out_rows(folder: Path, meta: dict) -> list[tuple[str, str, str]]:
    """[(label, what they are, the rows of each method)] for each status other than "ok" among a study's rows (the
    status counts of ``meta.json``): how many rows of how many, what they are (:data:`LEFT_OUT`) and how many of them
    each method has (read from ``results.csv`` only when there are such rows)."""
    counts = meta.get("status_counts") if isinstance(meta.get("status_counts"), dict) else {}
    other = {str(k): v for k, v in counts.items() if k != "ok" and isinstance(v, int) and v > 0}
    if not other:
        return []
    order = [k for k in LEFT_OUT if k in other] + sorted(k for k in other if k not in LEFT_OUT)
    try:
        rows = pd.read_csv(folder / "results.csv", usecols=["method", "status"], dtype=str, keep_default_na=False)
        by_method = rows[rows["status"] != "ok"].groupby(["status", "method"], sort=True).size()
    except (OSError, ValueError, pd.errors.ParserError):
        by_method = None
    out = []
    for status in order:
        label, what = LEFT_OUT.get(status, (f"rows with status '{status}'", "not an ok result (the messages are in "
                                                                          "`results.csv`)"))
        methods = ""
        if by_method is not None and status in by_method.index.get_level_values(0):
            methods = ", ".join(f"{m} {int(n)}" for m, n in by_method.loc[status].items())
        out.append((f"{label}: {other[status]} of {meta.get('n_rows')}", what, methods))
    return out


def _figure_path(folder: Path, name) -> Path:
    """A declared figure, confined to the study folder, checked to be a PNG."""
    if not isinstance(name, str):
        raise BrokenStudy(f"figure entry {name!r} is not a file name")
    path = (folder / name).resolve()
    if folder.resolve() not in path.parents:
        raise BrokenStudy(f"figure {name!r} lies outside the study folder")
    if not path.exists():
        raise BrokenStudy(f"figure {name!r} is missing")
    if not path.is_file():
        raise BrokenStudy(f"figure {name!r} is not a regular file")   # a FIFO would block the read
    try:
        with open(path, "rb") as fh:
            head = fh.read(8)
    except OSError:
        raise BrokenStudy(f"figure {name!r} cannot be read") from None
    if head != PNG_MAGIC:
        raise BrokenStudy(f"figure {name!r} is not a PNG")
    return path


def _anchor(text: str) -> str:
    """An HTML id / LaTeX label from any text: lower-case ASCII letters, digits and hyphens."""
    slug = re.sub(r"[^a-z0-9]+", "-", str(text).lower()).strip("-")
    return slug or "s-" + hashlib.sha256(str(text).encode("utf-8")).hexdigest()[:10]


def latex_fragments(table: pd.DataFrame, caption: str, label: str, unit: str = "", digits: int = 4,
                    decimals: dict | None = None, exact=()) -> list[str]:
    """The table as LaTeX fragments that fit an A4 page (``experiments.render.report_tables``), with the
    columns' declared formats."""
    from experiments.render.report_tables import latex_fragments as fragments
    return fragments(table, caption=caption, label=label, unit=unit, digits=digits, decimals=decimals, exact=exact)


def declared_formats(entry: dict, table: pd.DataFrame) -> dict:
    """The declared column formats of a table entry of ``report.json`` (``study.Table``'s ``decimals`` {column:
    n} and ``exact`` [column]) as keyword arguments of the renderers; a declaration that is not a number column
    of ``table`` or not 0..15 decimals is a broken table (``BrokenStudy``), never silently ignored."""
    decimals, exact = entry.get("decimals") or {}, entry.get("exact") or []
    if not isinstance(decimals, dict) or not isinstance(exact, list) or not all(
            isinstance(n, int) and not isinstance(n, bool) and 0 <= n <= 15 for n in decimals.values()):
        raise BrokenStudy(f"table {entry.get('file')!r}: decimals must map columns to 0..15, exact list columns")
    bad = [str(c) for c in [*decimals, *exact]
           if c not in table.columns or not pd.api.types.is_numeric_dtype(table[c])]
    if bad:
        raise BrokenStudy(f"table {entry.get('file')!r} declares the format of {', '.join(map(repr, bad))}, "
                          "not a number column of it")
    return {k: v for k, v in (("decimals", decimals), ("exact", exact)) if v}


def _with_unit(caption: str, unit: str) -> str:
    """The caption with 'Unit: U.' unless it already names every unit of ``unit`` in brackets ('... [mm]')."""
    from experiments.render.text import human_unit
    caption = caption.rstrip()
    units = [u.strip() for u in unit.split(",") if u.strip()]
    if units and all(f"[{u}]" in caption or f"[{human_unit(u)}]" in caption for u in units):
        return caption
    if unit:
        caption += ("" if caption.endswith(".") else ".") + f" Unit: {human_unit(unit)}."
    return caption


BUILD_MANIFEST = ".report-build.json"   #: the files the last build wrote under --out (all it may delete later)


def _previous_build(out: Path) -> list[str]:
    """Files the previous build listed in its manifest (relative paths, inside ``out``)."""
    try:
        listed = json.loads((out / BUILD_MANIFEST).read_text(encoding="utf-8")).get("files", [])
    except (OSError, ValueError, AttributeError):
        return []
    return [f for f in listed if isinstance(f, str) and re.fullmatch(r"(tables|figures)/[\w.-]+|report\.\w+|explorer\.html", f)]


def _clear_previous_build(out: Path, listed: list[str], keep=()) -> None:
    """Remove what the previous build wrote (``listed`` in its manifest: :func:`_previous_build`) but ``keep`` (the new
    build's files) and nothing else: a user's file in ``tables/`` or ``figures/`` is never touched; a listed name that
    is now a link or not a regular file is left alone."""
    root = out.resolve()
    for rel in listed:
        p = out / rel
        if rel not in keep and not p.is_symlink() and p.is_file() and root in p.resolve().parents:
            p.unlink()


def _write_build_manifest(out: Path, files: list[str]) -> None:
    write_atomic(out / BUILD_MANIFEST, json.dumps({"written_by": "python -m experiments.report", "files": sorted(files)},
                                                  indent=1) + "\n")


def _move_into_place(stage: Path, out: Path, files: list[str], done: list) -> None:
    """Move the build in ``stage`` (``files``, relative paths, and its manifest, last) onto ``out``, then remove what
    the previous build listed and this one did not write, with the stopping signals deferred until all is done
    (:func:`fitbench.stopping.signals_deferred`): the folder holds the previous report or the whole new one. Each
    file replaces its target as :func:`methods.files.write_atomic` does (through a symlink to a regular file, keeping
    an existing file's mode; a target that is not a regular file is refused). ``done`` gets True once all is in place,
    before a deferred signal stops the command."""
    import errno
    import os
    import stat
    from fitbench.stopping import signals_deferred
    from methods.files import writable_target
    previous, moves = _previous_build(out), []   # the manifest is replaced below
    for rel in [*files, BUILD_MANIFEST]:   # every target checked before the first is replaced
        (out / rel).parent.mkdir(exist_ok=True)
        moves.append((stage / rel, writable_target(out / rel)))
    with signals_deferred():
        for src, target in moves:
            try:
                os.chmod(src, stat.S_IMODE(os.stat(target).st_mode))
            except OSError:
                pass   # a new file: the mode it was written with
            try:
                os.replace(src, target)
            except OSError as exc:
                if exc.errno != errno.EXDEV:   # a symlink to another file system: copied there, atomically
                    raise
                write_atomic(target, src.read_bytes())
        _clear_previous_build(out, previous, set(files))
        done.append(True)


def is_default_results(results: Path) -> bool:
    """Whether ``results`` is a folder ``python -m experiments.run`` fills by default (``results/`` or
    ``results/quick/`` of the current folder or of the repository)."""
    here = Path(results).resolve()
    return any(here == (base / sub).resolve() for base in (Path("."), REPO) for sub in ("results", "results/quick"))


def build(results: Path, out: Path, log=print, *, render_latex=latex_fragments, render_md=None) -> Path:
    """Build the report from every study folder in ``results``; in a default results folder
    (``is_default_results``) every default study it lacks is shown as missing. ``render_latex(table, caption, label, unit, digits, [decimals=, exact=]) -> [fragment]`` and
    ``render_md(table, fmt)`` render one table (swap in another renderer).

    Writes report.md, report.html (numbered <figcaption>/<caption>, nav#toc, images embedded), report.tex
    (every table fragment and figure) with tables/*.tex and figures/*.{png,pdf}, and the manifest of what it
    wrote (the next build deletes only those files). User text is text: see ``experiments.render.page``.

    The whole report is built in a hidden folder in ``out`` and moved into place when it is complete
    (:func:`_move_into_place`): an error, Ctrl-C or SIGTERM before leaves ``out`` as it was (a folder it created
    removed again); the exception then says whether the report was in place (``report_written``)."""
    import tempfile
    out = Path(out)
    made, done = not out.exists(), []
    out.mkdir(parents=True, exist_ok=True)
    try:
        with tempfile.TemporaryDirectory(prefix=".report-build-", dir=out) as stage:
            written, n_table, n_figure = _build(results, Path(stage), render_latex, render_md)
            _write_build_manifest(Path(stage), written)
            _move_into_place(Path(stage), out, written, done)
    except BaseException as exc:
        exc.report_written = bool(done)   # a signal deferred while the report moved into place: it is all there
        if made and not done:
            for folder in (out / "tables", out / "figures", out):
                try:
                    folder.rmdir()   # only when nothing else is in it
                except OSError:
                    pass
        raise
    log(f"report: {out / 'report.md'}, {out / 'report.html'}, {out / 'report.tex'}, {n_table} tables, {n_figure} figures")
    return out


def _build(results: Path, out: Path, render_latex, render_md) -> tuple[list[str], int, int]:
    """The report of ``results`` written into the empty folder ``out`` (:func:`build`): (the files written, relative
    to ``out``; the number of tables; of figures)."""
    from markupsafe import Markup
    from experiments.render.document import write_report_tex
    from experiments.render.markdown import md_code
    from experiments.render.page import Document, markdown_table, md_escape
    from experiments.render.report_tables import html_table, text_frame
    from experiments.verdict import study_verdicts

    render_md = render_md or markdown_table
    (out / "tables").mkdir(exist_ok=True)
    written: list[str] = []
    known = {}
    for n in configs.available():
        try:
            known[n] = configs.load(n)
        except InvalidInputError:
            continue
    present = sorted(p.name for p in results.iterdir() if is_study_folder(p)) if results.exists() else []
    # a user's study named like a project study is not that study (its meta.json records its own TOML): its
    # commands name that TOML, and the project study's declarations and default flag are not its own
    from experiments.verdict import is_project_study
    known = {n: c for n, c in known.items() if n not in present or is_project_study(results / n, known)}
    # a report of a results folder holds the studies in it; only the default folders (results/, results/quick/),
    # which a run of the default studies fills, name the default studies they lack as missing
    names = present + ([n for n, c in known.items() if c.get("default") and n not in present]
                       if is_default_results(results) else [])
    entries = []  # (section, order, name, title, meta | None, manifest | None, problem | None)
    for name in names:
        cfg = known.get(name, {})
        problem, meta, manifest = None, None, None
        if name not in present:
            problem = "missing"
        else:
            try:
                meta, manifest = load_study(results / name)
            except BrokenStudy as exc:
                problem = str(exc)
        decl = manifest or {**cfg.get("report", {}), "title": cfg.get("title", name)}
        entries.append((str(decl.get("section", "Other studies")), decl.get("order", 1000), name,
                        str(decl.get("title", name)), meta, manifest, problem))
    section_order = {}
    for sec, order, name, *_ in sorted(entries, key=lambda e: (e[1] if isinstance(e[1], int) else 1000, e[2])):
        section_order.setdefault(sec, len(section_order))
    entries.sort(key=lambda e: (section_order[e[0]], e[1] if isinstance(e[1], int) else 1000, e[2]))
    ranked = [(e[2], results / e[2], e[4]) for e in entries if e[4] is not None]
    rankings, ranking_problem = {}, None
    try:
        from experiments.render.rankings import collect
        rankings = collect(ranked)
    except (ValueError, KeyError, TypeError) as exc:
        ranking_problem = str(exc)
    has_rankings = bool(rankings) or ranking_problem is not None
    called = study_command_names(results, [e[2] for e in entries if e[4] is not None], known)
    verdicts = study_verdicts(results, [e[2] for e in entries if e[4] is not None],
                              {n: "not a default study" for n in present if not known.get(n, {}).get("default")},
                              quick={e[2]: bool(e[4].get("quick")) for e in entries if e[4] is not None},
                              shown=_command_folder(results), commands=called)

    # the command that fills a missing study into this folder: its --quick grid when the folder's studies are
    # quick runs, and this folder as --out unless it is the grid's default (results/, results/quick/)
    folder_quick = any(e[4] and e[4].get("quick") for e in entries)
    from experiments.verdict import grid_options
    quick_flag, folder_arg = grid_options(results, folder_quick, _command_folder(results))
    missing_args = quick_flag + (f" --out{folder_arg}" if folder_arg else "")

    doc = Document()
    doc.heading(1, "fitbench: comparison report")
    done_names = [e[2] for e in entries if e[4] is not None]
    doc.prose(f"Built from {md_code(_shown(results))} by `python -m experiments.report`; "
              f"{_reproduce(done_names, known, folder_quick, folder_arg, called)}. "
              "Interactive explorer (offline): [explorer.html](explorer.html).")
    abstract_at = len(doc.parts)
    from experiments.verdict import verdict_markdown
    doc.prose(" ".join(verdict_markdown(results, folder_quick, _command_folder(results))))
    quick_note = None
    if folder_quick:
        quick_note = ("studies marked quick run ran the reduced --quick grid; their numbers are not the "
                      "published comparison.")
        doc.prose("**Note:** studies marked *quick run* ran the reduced `--quick` grid; their numbers are not the "
                  "published comparison.")
    toc_md, toc_html = ["## Contents", ""], [Markup('<nav id="toc"><h2>Contents</h2><ul>')]
    toc_sections = list(section_order) + ([RANKINGS_SECTION] if has_rankings else [])
    for sec in toc_sections:
        toc_md.append(f"- [{md_escape(sec)}](#{_anchor(sec)})")
        toc_html.append(Markup('<li><a href="#{}">{}</a>').format(_anchor(sec), sec))
        subs = [(e[3], f"study-{_anchor(e[2])}") for e in entries if e[0] == sec]
        toc_md += [f"  - [{md_escape(t)}](#{a})" for t, a in subs]
        if subs:
            toc_html.append(Markup("<ul>") + Markup("").join(Markup('<li><a href="#{}">{}</a></li>').format(a, t)
                                                             for t, a in subs) + Markup("</ul>"))
        toc_html.append(Markup("</li>"))
    toc_html.append(Markup("</ul></nav>"))
    doc.block(Markup("").join(toc_html), "\n".join(toc_md))
    provenance = None
    explorer_tables: list[dict] = []
    n_table = n_figure = 0
    tex_sections = []

    def add_table(table, caption, unit, digits, colour="", declared=None):
        nonlocal n_table
        n_table += 1
        label = f"table-{n_table}"
        caption = _with_unit(caption, unit)
        declared = declared or {}       # the columns' declared formats: {"decimals": {column: n}, "exact": [column]}
        fragments = render_latex(table, f"{caption}", label, unit, digits, **declared)
        files = []
        for k, frag in enumerate(fragments):
            name = f"{label}.tex" if len(fragments) == 1 else f"{label}-{k + 1}.tex"
            write_atomic(out / "tables" / name, frag)
            files.append(f"tables/{name}")
        save_csv_plain(table, out / "tables" / f"{label}.csv")
        explorer_tables.append({"caption": f"Table {n_table}: {caption}", "data": table, "unit": unit,
                                "digits": digits, "colour": colour, **declared})
        written.extend(files + [f"tables/{label}.csv"])
        fmt = f".{int(digits or 7)}g"
        doc.block(Markup(html_table(table, caption=f"Table {n_table}: {caption}", unit=unit, digits=digits,
                                    colour=colour, table_id=label, **declared)),
                  f"*Table {n_table}: {md_escape(caption)}*\n\n"
                  + render_md(text_frame(table, unit=unit, digits=digits, **declared), fmt))
        return [{"kind": "table", "file": f} for f in files]

    def add_figure(png, caption):
        nonlocal n_figure
        n_figure += 1
        dst_png, included = export_figure(png, out / "figures", f"figure-{n_figure}")
        written.extend(sorted({f"figures/{dst_png.name}", f"figures/{included.name}"}))
        doc.figure(dst_png, n_figure, caption, f"figures/{dst_png.name}")
        return [{"kind": "figure", "file": f"figures/{included.name}", "caption": caption, "label": f"figure-{n_figure}"}]

    for sec in section_order:
        doc.heading(2, sec, _anchor(sec))
        tex_studies = []
        for sec_, _, name, title, meta, manifest, problem in entries:
            if sec_ != sec:
                continue
            doc.heading(3, title, f"study-{_anchor(name)}", code=name)
            items = []
            tex_studies.append({"title": title, "findings": "", "items": items})
            if problem == "missing":
                default = known.get(name, {}).get("default", False)
                command = f"python -m experiments.run {name}{missing_args}"
                doc.prose(f"**Missing**: no results in {md_code(_shown(results / name))}. Run "
                          f"{md_code(command)}" + ("" if default else " (not a default study)") + ".")
                # the PDF names the folder in words: a long path is one unbreakable word on the page
                tex_studies[-1]["findings"] = (f"Missing: no results. Run python -m experiments.run {name}"
                                               f"{' --quick' if folder_quick else ''}"
                                               + ("" if "--out" not in missing_args else " with this results folder as --out")
                                               + ".")
                continue
            if problem:
                doc.prose(f"**Broken**: {md_escape(problem)}.")
                tex_studies[-1]["findings"] = f"Broken: {problem}."
                continue
            provenance = provenance or meta
            for label, what, per_method in left_out_rows(results / name, meta):  # every row the tables do not hold
                by = f"; by method: {per_method}" if per_method else ""
                doc.prose(f"**{md_escape(label)}**: {what}{md_escape(by)}.")  # what: the builder's own words
                tex_studies[-1].setdefault("notes", []).append(f"{label}: {what.replace('`', '')}{by}.")
            plugins = meta.get("plugins") if isinstance(meta.get("plugins"), dict) else {}
            doc.prose(md_escape(f"{meta.get('n_rows')} rows{'; quick run (reduced grid)' if meta.get('quick') else ''}; "
                                f"commit {str(meta.get('git_commit') or '?')[:10]}"
                                f"{' (dirty)' if meta.get('git_dirty') else ''}, {meta.get('date')}, config hash "
                                f"{meta.get('config_hash')}"
                                + (f"; plugins: {', '.join(f'{k} {v}' for k, v in plugins.items())}" if plugins else "")
                                + "."))
            if meta.get("quick"):
                tex_studies[-1].setdefault("notes", []).append(f"Quick run (reduced grid): {meta.get('n_rows')} rows.")
            for label, sentence in verdicts.get(name, []):
                doc.prose(f"**{md_escape(label)}.** {md_escape(sentence)}")
                tex_studies[-1].setdefault("notes", []).append(f"{label}. {sentence}")
            if manifest.get("findings"):
                doc.prose(f"**Findings.** {md_escape(manifest['findings'])}")
                tex_studies[-1]["findings"] = str(manifest["findings"])
            for t in manifest.get("tables", []) if isinstance(manifest.get("tables"), list) else []:
                try:
                    path = (results / name / t["file"]).resolve()
                    if (results / name).resolve() not in path.parents:
                        raise BrokenStudy(f"table {t['file']!r} lies outside the study folder")
                    if not path.is_file():
                        raise BrokenStudy(f"table {t['file']!r} is not a regular file")
                    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
                    digits = int(t.get("digits") or 7)
                    declared = declared_formats(t, table)
                except (OSError, ValueError, KeyError, TypeError, BrokenStudy, pd.errors.ParserError) as exc:
                    doc.prose(f"**Broken table**: {md_escape(exc)}.")
                    continue
                items += add_table(table, str(t.get("caption", "")), str(t.get("unit") or ""), digits,
                                   str(t.get("colour", "")), declared)
            for f in manifest.get("figures", []) if isinstance(manifest.get("figures"), list) else []:
                try:
                    png = _figure_path(results / name, f.get("file") if isinstance(f, dict) else None)
                except BrokenStudy as exc:
                    doc.prose(f"**Broken figure**: {md_escape(exc)}.")
                    continue
                items += add_figure(png, str(f.get("caption", "")) or f"{title}: {f.get('file')}")
        tex_sections.append({"title": sec, "label": _anchor(sec), "studies": tex_studies})
    if has_rankings:
        tex_studies = _rankings_section(rankings, ranking_problem, out, add_table, add_figure, doc)
        tex_sections.append({"title": RANKINGS_SECTION, "label": _anchor(RANKINGS_SECTION), "studies": tex_studies})
    provenance_text = None
    if provenance:
        v = provenance.get("versions", {}) if isinstance(provenance.get("versions"), dict) else {}
        machine = (f"Machine: {provenance.get('cpu')} ({provenance.get('cores')} cores), {provenance.get('platform')}; "
                   f"BLAS {provenance.get('blas')}.")
        versions = "Versions: " + ", ".join(f"{k} {val}" for k, val in v.items()) + "."
        provenance_text = f"{machine} {versions}"
        doc.heading(2, "Provenance")
        doc.prose(md_escape(machine))
        doc.prose(md_escape(versions))
        doc.prose("Each study's `meta.json` holds its own commit, date, configuration and hash.")
    from experiments.verdict import carried_over
    abstract = _abstract(entries, verdicts, *carried_over(results))
    if abstract:
        from experiments.render.page import Part, prose_html
        md_abstract = "**Abstract.** " + md_escape(abstract)
        doc.parts.insert(abstract_at, Part("prose", md_abstract, prose_html(md_abstract)))
    from experiments.render.explorer import write_explorer
    write_explorer(out, rankings, explorer_tables, {e[2]: results / e[2] for e in entries if e[4] is not None},
                   {e[2]: e[4] for e in entries if e[4] is not None})
    written.append("explorer.html")
    write_atomic(out / "report.md", doc.markdown())
    write_atomic(out / "report.html", doc.html("fitbench comparison report"))
    write_report_tex(out, tex_sections, provenance=provenance_text, abstract=abstract, note=quick_note,
                     title="fitbench: comparison report" + (" (quick run, reduced grid)" if folder_quick else ""))
    written += ["report.md", "report.html", "report.tex"]
    return sorted(set(written)), n_table, n_figure


def first_clause(findings: str) -> str:
    """A findings text's first sentence, or its part before the first '; ' when that part is a statement of its own;
    a '; ' after a ':' separates the items of a list ("...: nearest: 3 of 8; offset ...: 4 of 4."), which ends with the
    sentence, not at its first item."""
    sentence = re.split(r"(?<=\.)\s", findings.strip(), maxsplit=1)[0]
    head = sentence.split("; ", 1)[0]
    return (sentence if ":" in head else head).rstrip(".;")


def _abstract(entries, verdicts, carried: dict | None = None, run_date: str | None = None) -> str:
    """What was compared, the main numbers (each study's findings, first sentence) and what reproduced: the verdicts
    the last run made apart from those it carried over from an earlier one (``carried``: study -> verdict entry,
    ``experiments.verdict.carried_over``), which it did not reproduce."""
    done = [e for e in entries if e[4] is not None]
    if not done:
        return ""
    n_rows = sum(int(e[4].get("n_rows") or 0) for e in done if str(e[4].get("n_rows", "")).isdigit())
    parts = [f"{len(done)} {'study' if len(done) == 1 else 'studies'} ({n_rows:,} runs) "
             f"{'compares' if len(done) == 1 else 'compare'} the fitting methods."]
    for e in done:
        findings = str((e[5] or {}).get("findings") or "").strip()
        if findings:
            first = first_clause(findings)
            parts.append(f"{e[3].split(':')[0].strip()}: {first}.")
    judged = {k: lines[0][0] for k, lines in verdicts.items() if lines[0][0].startswith("Reproducibility")
              and not lines[0][0].endswith("out of date")}
    changed = [k for k, lines in verdicts.items() if lines[0][0].startswith("Changed since")]
    carried = {k: e for k, e in (carried or {}).items() if k in judged}
    here = {k: label for k, label in judged.items() if k not in carried}
    if here:
        differ = [k for k, label in here.items() if label.endswith("differs")]
        parts.append(f"Reproduced: {len(here) - len(differ)} of {len(here)} studies with a current verdict"
                     + (f" made by the last run ({run_date})" if carried else "")
                     + (f" (differ: {', '.join(differ)})" if differ else "") + ".")
    if carried:
        parts.append("Carried over from an earlier verdict, not reproduced by the last run: "
                     + ", ".join(f"{k} ({'agreed' if e.get('agree') else 'differed'}, {e.get('date', '?')})"
                                 for k, e in carried.items()) + ".")
    if changed:
        parts.append(f"Changed since the results compared with (other code or config, not a reproducibility check): "
                     f"{', '.join(changed)}.")
    return " ".join(parts)


RANKINGS_SECTION = "Rankings across data sets"


def ranking_findings(rankings) -> list[str]:
    """Per ranking, the method(s) best on the largest share of its problems; methods whose costs tie within
    the profiles' tie tolerance are all best there, and a shared top share names every one of them."""
    from experiments.render.profiles import TIE_RTOL, performance_ratios
    words = []
    for name, r in rankings.items():
        if r.table is None or not len(r.table):
            continue
        best1 = (performance_ratios(r.table) == 1.0).mean(axis=0)
        top = float(best1.max())
        winners = [str(m) for m, share in best1.items() if share == top]
        tied = f" (tied within {TIE_RTOL:g} relative)" if len(winners) > 1 else ""
        words.append(f"{name}: {' and '.join(winners)} {'are' if len(winners) > 1 else 'is'} best{tied} on "
                     f"{100 * top:.0f} % of {len(r.table)} problems")
    return words


def _rankings_section(rankings, problem, out, add_table, add_figure, doc):
    """Performance profiles of every declared ranking (one panel each) and, per ranking, the median cost of
    each method per data set coloured relative to the row's best."""
    from experiments.render.page import md_escape
    doc.heading(2, RANKINGS_SECTION, _anchor(RANKINGS_SECTION))
    doc.heading(3, "Performance profiles", f"study-{_anchor('performance profiles')}")
    intro = ("Dolan–Moré performance profiles pool every study that declares a ranking ([[rankings]] in its "
             "configuration): for each problem (study, data set, data stream, repetition) the ratio "
             "τ = cost / best cost over the methods, and ρ(τ) = the share of problems on which a method is within "
             "τ of the best (ρ(1): share of problems where it is best; a failure never reaches any τ).")
    items = []
    if problem:
        doc.prose(f"**Broken ranking**: {md_escape(problem)}.")
        return [{"title": "Performance profiles", "findings": f"Broken ranking: {problem}.", "items": items}]
    doc.prose(md_escape(intro))
    words = ranking_findings(rankings)
    findings = ("; ".join(words) + ".") if words else "No problem is shared by the methods of a ranking."
    doc.prose(f"**Findings.** {md_escape(findings)}")
    import textwrap
    tables = {textwrap.fill(n, 34): r.table for n, r in rankings.items() if r.table is not None and len(r.table)}
    if tables:
        import matplotlib
        matplotlib.use("Agg")
        from experiments.render.profiles import plot_profiles
        png = out / "figures" / ".profiles-source.png"      # and its vector PDF beside it; both removed below
        png.parent.mkdir(parents=True, exist_ok=True)
        plot_profiles(tables, png)
        sources = "; ".join(f"{n}: studies {', '.join(r.studies)}, {len(r.table)} problems"
                            + (f", left out (not run in every study): {', '.join(r.left_out)}" if r.left_out else "")
                            + (f", {r.unsolved} solved by no method left out" if r.unsolved else "")
                            + "".join(f"; {m} ran on {k} of them" for m, k in r.runs.items() if k < len(r.table))
                            for n, r in rankings.items())
        tex_items = add_figure(png, "Performance profiles of the methods: share of problems ρ(τ) on which a "
                                      "method's cost is within a factor τ of the best (log₂ τ on the x axis; higher "
                                      f"and further left is better). {sources}.")
        png.unlink(missing_ok=True)
        png.with_suffix(".pdf").unlink(missing_ok=True)
        items += tex_items
    for name, r in rankings.items():
        if r.by_dataset is None or r.by_dataset.empty:
            continue
        units = r.unit_words()
        fewer = r.dataset_notes
        tex_items = add_table(r.by_dataset.reset_index(),
                                     f"Median {name} per data set and method over the data set's problems that "
                                     "every method of the row ran on (failed: it failed on at least half of them, – in the Markdown and LaTeX "
                                     "tables; –: not run on the data set); "
                                     "colour in the HTML report: ratio to the best method of the row"
                                     + (f". Fewer problems than the data set's (those every method of the row ran on): {'; '.join(fewer)}"
                                        if fewer else "")
                                     + (f". Units by study (the data set's prefix): {units}" if units else ""),
                                     r.unit, 3, "lower_is_better")
        items += tex_items
    return [{"title": "Performance profiles", "findings": intro + " Findings: " + findings, "items": items}]


def save_csv_plain(df: pd.DataFrame, path: Path) -> None:
    import io
    buf = io.StringIO()
    df.to_csv(buf, index=False, float_format="%.10g")
    write_atomic(path, buf.getvalue())


def default_out(results: Path) -> Path:
    """Where the report of ``results`` goes unless told: ``paper/`` beside the default ``results/`` of the current
    folder (the committed report), else ``RESULTS/paper``, inside the folder (``results/quick/paper``, ``DIR/paper``:
    two results folders never share one report). ``python -m experiments.run --out DIR`` writes its report there
    too."""
    return Path("paper") if Path(results).resolve() == Path("results").resolve() else Path(results) / "paper"


def committed_clash(out: Path, project: bool) -> str | None:
    """What of the committed report (``paper/``) or results (``results/``) of the repository or of the current
    folder (as :func:`is_default_results`) ``experiments.run --out out`` would write into, as words for a refusal,
    or None. Its report goes to :func:`default_out`, so ``--out`` of the checkout itself puts it in ``paper/``. A
    study that is not the project's (``project`` False) stays out of ``results/`` too, except ``results/user/``,
    where its outputs go by default."""
    here, report = Path(out).resolve(), default_out(out).resolve()
    for base in (REPO, Path(".").resolve()):
        paper, results = base / "paper", base / "results"
        what = ("the committed report", "the committed results") if base == REPO else \
            ("the report of results/ of the current folder", "reserved for the project's studies")
        if report == paper and not (project and here == results):
            return f"would put the run's report into paper/, {what[0]} (the report of --out DIR goes to DIR/paper)"
        if here.is_relative_to(paper):
            return f"lies inside paper/, {what[0]}"
        if not project and here.is_relative_to(results) and not here.is_relative_to(results / "user"):
            return f"lies inside results/, {what[1]} (a personal study goes to results/user/)"
    return None


def _holds_study(folder: Path) -> bool:
    """A folder the runner wrote a study into: its row store (a run under way or interrupted), or its ``meta.json``
    and ``results.csv`` (finished). Stricter than :func:`is_study_folder`: a folder the user keeps a ``results.csv``
    in is no study to keep a report out of."""
    try:
        return (folder / "rows.sqlite").exists() or ((folder / "meta.json").is_file()
                                                     and (folder / "results.csv").exists())
    except OSError:
        return False


def _holds_studies(folder: Path) -> bool:
    """A results folder: a folder holding a study folder (:func:`_holds_study`)."""
    try:
        return folder.is_dir() and any(_holds_study(p) for p in folder.iterdir() if p.is_dir())
    except OSError:
        return False


def _named(path: Path) -> str:
    """A folder as a refusal names it: relative to the current folder when inside it, else as it is."""
    try:
        return path.relative_to(Path.cwd().resolve()).as_posix() or "."
    except ValueError:
        return str(path)


def report_clash(results: Path, out: Path) -> str | None:
    """Why the report of ``results`` must not go to ``out``, as words for a refusal, or None (checked before anything
    is written; every path resolved, so a symlink is the folder it names):

    * ``out`` inside a ``paper/`` that is the report of another results folder: the repository's or the current
      folder's (the committed report) or one with a ``results/`` beside it (another checkout), while ``results`` is
      not that ``results/``: a user's study would replace that report (and its build delete the figures the previous
      one listed). :func:`committed_clash` guards ``experiments.run --out`` the same way;
    * ``out``, or a folder above it, that exists and is not a folder (``--out report.md``);
    * ``out`` in a study folder (``--out results/noise``): the report's tables, figures and pages among the study's;
    * ``out`` inside the results folder read other than its report folder (:func:`default_out`: ``RESULTS/paper``),
      or the results folder read itself: the report's files beside the studies, where a study's folder goes;
    * ``out`` that is another results folder (a folder holding a study) or lies in one beside its studies (its
      ``paper/``: the report of those results)."""
    given, here, source = out, Path(out).resolve(), Path(results).resolve()
    leave = f"leave --out out (the report then goes to {default_out(results)}/) or give another folder"
    bases = [(REPO, "the committed report, built from the project's results/"),
             (Path(".").resolve(), "the report of results/ of the current folder")]
    bases += [(p.parent, f"the report of {_named(p.parent / 'results')}/ beside it")
              for p in (here, *here.parents) if p.name == "paper" and (p.parent / "results").is_dir()]
    for base, what in bases:
        if here.is_relative_to(base / "paper") and source != base / "results":
            return f"--out {given} writes into paper/, {what}, not the report of --results {results}; {leave}"
    for p in (here, *here.parents):
        if p.exists() or p.is_symlink():
            if not p.is_dir():
                kind = "a file" if p.is_file() else "not a folder"
                where = "" if p == here else f" ({_named(p)} is {kind})"
                return (f"--out {given} is {kind if p == here else 'no folder'}{where}: the report is a folder of "
                        f"files (report.md, report.html, report.tex, tables/, figures/); {leave}")
            break
    def alias(p: Path) -> str:   # the folder's name when --out names it otherwise (a symlink, another spelling)
        return "" if _named(p) == str(given) else f" ({_named(p)})"
    study = next((p for p in (here, *here.parents) if _holds_study(p)), None)
    if study is not None:
        where = f"is a study folder{alias(here)}" if study == here else f"lies in the study folder {_named(study)}"
        return f"--out {given} {where}: the report's pages, tables/ and figures/ would mix with its files; {leave}"
    if here == source or here.is_relative_to(source):
        if here == default_out(results).resolve():
            return None
        where = "is the results folder read" if here == source else "lies inside the results folder read"
        return f"--out {given} {where} (--results {results}), where the studies' folders are; {leave}"
    if _holds_studies(here):
        return f"--out {given} is the results folder of other studies{alias(here)}; {leave}"
    if _holds_studies(here.parent):
        return (f"--out {given} lies in {_named(here.parent)}, the results folder of other studies, beside their folders"
                f"{' (its paper/ is their report)' if here.name == 'paper' else ''}; {leave}")
    return None


def main(argv=None, prog: str = "python -m experiments.report") -> int:
    """The command (``prog``: the command named in its usage, ``fitbench report`` from fitbench). A reader of its
    output that goes (``| head -1``) ends what it prints, not the build (:func:`fitbench.streams.readers_may_go`);
    Ctrl-C, SIGTERM and SIGHUP end it with one line and 128 + the signal (:func:`fitbench.stopping.stopping_signals`),
    the report folder as it was (:func:`build`)."""
    from fitbench.stopping import stopped_status, stopping_signals
    from fitbench.streams import OutputError, readers_may_go
    try:
        with readers_may_go():
            try:
                with stopping_signals():
                    return _main(argv, prog)
            except KeyboardInterrupt as exc:
                what, status = stopped_status(exc)
                state = ("after the report was written" if getattr(exc, "report_written", False) else
                         "; no report written (the folder is as it was)")
                print(f"{chr(10) if status == 130 else ''}experiments.report: {what}"
                      f"{' ' if state[0] != ';' else ''}{state}", file=sys.stderr)
                return status
    except OutputError as exc:   # `> /dev/full`: what it printed is lost, the report is as the build left it
        print(f"experiments.report: error: cannot write {exc.filename}: {exc.strerror}", file=sys.stderr)
        return 2


def _main(argv, prog: str) -> int:
    parser = argparse.ArgumentParser(prog=prog, description="Build paper/ from results/.")
    from fitbench import __version__
    parser.add_argument("--version", action="version", version=f"%(prog)s (fitbench {__version__})")
    parser.add_argument("--results", type=Path, default=Path("results"),
                        help="the results folder (default: results/ in the current folder)")
    parser.add_argument("--out", type=Path, help="default: paper/ for results/ of the current folder, else RESULTS/paper")
    args = parser.parse_args(argv)
    if args.out is None:
        args.out = default_out(args.results)
    if clash := report_clash(args.results, args.out):
        print(f"experiments.report: error: {clash}", file=sys.stderr)
        return 2
    if not args.results.is_dir():
        print(f"experiments.report: error: no results folder {args.results}; run python -m experiments.run first",
              file=sys.stderr)
        return 2
    try:
        present = any(is_study_folder(p) for p in args.results.iterdir())
    except OSError as exc:
        print(f"experiments.report: error: cannot read the results folder {args.results}: "
              f"{exc.strerror or exc}", file=sys.stderr)
        return 2
    if not present:   # a typo'd folder (results/quick/paper): no report of nothing, exit 0
        print(f"experiments.report: error: no study in {args.results} (no folder holding a study's meta.json, "
              f"results.csv or rows.sqlite); give --results the folder python -m experiments.run wrote (its --out)",
              file=sys.stderr)
        return 2
    try:
        build(args.results, args.out)
    except (OSError, InvalidInputError) as exc:   # a folder not writable, a full disk, a target not a regular file
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        why = (exc.strerror or exc) if isinstance(exc, OSError) else exc
        print(f"experiments.report: error: cannot write the report into {args.out}: {where}{why}; no report written "
              "(the folder is as it was)", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    from fitbench.stopping import started
    started()
    sys.exit(main())
