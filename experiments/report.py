"""``python -m experiments.report [--results DIR] [--out DIR]``: the comparison report, built only from
the studies' output in ``results/`` (default ``results/`` -> ``paper/``).

Writes ``report.md``, a self-contained ``report.html`` (images embedded, numbered captions, nav#toc, coloured
method tables), ``report.tex`` (compiles on A4) with the LaTeX table fragments ``tables/*.tex`` (siunitx,
split when too wide; ``experiments.render``) and every figure as PNG and PDF under ``figures/``, and the section
"Rankings across data sets" (performance profiles of every ranking the studies declare, ``[[rankings]]``). A study that is missing
or whose rows failed is shown as such, never dropped. Also run at the end of ``python -m experiments.run``.
"""
from __future__ import annotations

import argparse
import base64
import hashlib
import html
import json
import re
import shutil
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from experiments import config as configs
from experiments.provenance import REPO, write_atomic
from methods import InvalidInputError

# ---------------------------------------------------------------- tables

def md_table(df: pd.DataFrame, floatfmt: str = ".7g") -> str:
    def fmt(v):
        return ("" if v != v else format(v, floatfmt)) if isinstance(v, float) else str(v)
    out = ["| " + " | ".join(map(str, df.columns)) + " |", "|" + "---|" * len(df.columns)]
    out += ["| " + " | ".join(fmt(v) for v in row) + " |" for row in df.itertuples(index=False)]
    return "\n".join(out)


# ---------------------------------------------------------------- figures

def export_figure(png: Path, out_dir: Path, stem: str) -> tuple[Path, Path]:
    """Copy the PNG and write a PDF of it (for authors' own documents)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt
    out_dir.mkdir(parents=True, exist_ok=True)
    dst_png = out_dir / f"{stem}.png"
    shutil.copyfile(png, dst_png)
    img = mpimg.imread(png)
    h, w = img.shape[:2]
    fig = plt.figure(figsize=(w / 100, h / 100), dpi=100)
    fig.figimage(img, 0, 0)
    dst_pdf = out_dir / f"{stem}.pdf"
    fig.savefig(dst_pdf, dpi=100)
    plt.close(fig)
    return dst_png, dst_pdf


# ---------------------------------------------------------------- assembly

def _shown(path: Path) -> str:
    try:
        return str(Path(path).resolve().relative_to(REPO))
    except ValueError:
        return str(path)


PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


class BrokenStudy(Exception):
    """A study folder the report cannot use; the message says why."""


def _read_json(path: Path) -> dict:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
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


def _figure_path(folder: Path, name) -> Path:
    """A declared figure, confined to the study folder, checked to be a PNG."""
    if not isinstance(name, str):
        raise BrokenStudy(f"figure entry {name!r} is not a file name")
    path = (folder / name).resolve()
    if folder.resolve() not in path.parents:
        raise BrokenStudy(f"figure {name!r} lies outside the study folder")
    try:
        with open(path, "rb") as fh:
            head = fh.read(8)
    except OSError:
        raise BrokenStudy(f"figure {name!r} is missing") from None
    if head != PNG_MAGIC:
        raise BrokenStudy(f"figure {name!r} is not a PNG")
    return path


def _anchor(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")


def _clear_previous_build(out: Path) -> None:
    """Tables and figures of an earlier build never mix with this one."""
    for sub, patterns in (("tables", ("*.tex", "*.csv")), ("figures", ("*.png", "*.pdf"))):
        for pattern in patterns:
            for p in (out / sub).glob(pattern) if (out / sub).is_dir() else []:
                p.unlink()
    for p in out.glob(".*.tmp"):
        p.unlink()


def latex_fragments(table: pd.DataFrame, caption: str, label: str, unit: str = "", digits: int = 4) -> list[str]:
    """The table as LaTeX fragments that fit an A4 page (``experiments.render.report_tables``)."""
    from experiments.render.report_tables import latex_fragments as fragments
    return fragments(table, caption=caption, label=label, unit=unit, digits=digits)


def _with_unit(caption: str, unit: str) -> str:
    from experiments.render.text import human_unit
    caption = caption.rstrip()
    if unit:
        caption += ("" if caption.endswith(".") else ".") + f" Unit: {human_unit(unit)}."
    return caption


def build(results: Path, out: Path, log=print, *, render_latex=latex_fragments, render_md=md_table) -> Path:
    """Build the report from every study folder in ``results`` and every default study (missing ones
    are shown as missing). ``render_latex(table, caption, label, unit, digits) -> [fragment]`` and
    ``render_md(table, fmt)`` render one table (swap in another renderer).

    Writes report.md, report.html (numbered <figcaption>/<caption>, nav#toc, images embedded), report.tex
    (every table fragment and figure) with tables/*.tex and figures/*.{png,pdf}."""
    from experiments.render.document import write_report_tex
    from experiments.render.report_tables import html_table

    out.mkdir(parents=True, exist_ok=True)
    (out / "tables").mkdir(exist_ok=True)
    _clear_previous_build(out)
    known = {}
    for n in configs.available():
        try:
            known[n] = configs.load(n)
        except InvalidInputError:
            continue
    present = sorted(p.name for p in results.iterdir() if is_study_folder(p)) if results.exists() else []
    names = present + [n for n, c in known.items() if c.get("default") and n not in present]
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
        entries.append((decl.get("section", "Other studies"), decl.get("order", 1000), name,
                        decl.get("title", name), meta, manifest, problem))
    section_order = {}
    for sec, order, name, *_ in sorted(entries, key=lambda e: (e[1], e[2])):
        section_order.setdefault(sec, len(section_order))
    entries.sort(key=lambda e: (section_order[e[0]], e[1], e[2]))
    ranked = [(e[2], results / e[2], e[4]) for e in entries if e[4] is not None]
    rankings, ranking_problem = {}, None
    try:
        from experiments.render.rankings import collect
        rankings = collect(ranked)
    except (ValueError, KeyError, TypeError) as exc:
        ranking_problem = str(exc)
    has_rankings = bool(rankings) or ranking_problem is not None

    blocks: dict[str, str] = {}      # HTML that replaces a marked markdown block in report.html

    def block(html_text: str, md_lines: list[str]) -> list[str]:
        key = f"b{len(blocks)}"
        blocks[key] = html_text
        return [f"<!--block:{key}-->", *md_lines, "<!--/block-->"]

    md = ["# fitbench: comparison report", "",
          f"Built from `{_shown(results)}` by `python -m experiments.report`; reproduce everything with "
          "`python -m experiments.run` (the default studies; a study that is not default: "
          "`python -m experiments.run NAME`).", ""]
    # --- hook of experiments.verify (engine): the last reproducibility verdict, when there is one
    from experiments.verdict import verdict_markdown
    md += verdict_markdown(results) + [""]
    # --- end of hook
    if any(e[4] and e[4].get("quick") for e in entries):
        md += ["**Note:** studies marked *quick run* ran the reduced `--quick` grid; their numbers are not the "
               "published comparison.", ""]
    toc_md, toc_html = ["## Contents", ""], ['<nav id="toc"><h2>Contents</h2><ul>']
    toc_sections = list(section_order) + ([RANKINGS_SECTION] if has_rankings else [])
    for sec in toc_sections:
        toc_md.append(f"- [{sec}](#{_anchor(sec)})")
        toc_html.append(f'<li><a href="#{_anchor(sec)}">{html.escape(sec)}</a>')
        subs = [(e[3], f"study-{_anchor(e[2])}") for e in entries if e[0] == sec]
        toc_md += [f"  - [{t}](#{a})" for t, a in subs]
        if subs:
            toc_html.append("<ul>" + "".join(f'<li><a href="#{a}">{html.escape(t)}</a></li>' for t, a in subs) + "</ul>")
        toc_html.append("</li>")
    toc_html.append("</ul></nav>")
    md += block("".join(toc_html), toc_md + [""])
    provenance = None
    n_table = n_figure = 0
    tex_sections = []

    def add_table(table, caption, unit, digits, colour=""):
        nonlocal n_table
        n_table += 1
        label = f"table-{n_table}"
        caption = _with_unit(caption, unit)
        fragments = render_latex(table, f"{caption}", label, unit, digits)
        files = []
        for k, frag in enumerate(fragments):
            name = f"{label}.tex" if len(fragments) == 1 else f"{label}-{k + 1}.tex"
            write_atomic(out / "tables" / name, frag)
            files.append(f"tables/{name}")
        save_csv_plain(table, out / "tables" / f"{label}.csv")
        fmt = f".{int(digits or 7)}g"
        lines = block(html_table(table, caption=f"Table {n_table}: {caption}", unit=unit, digits=digits, colour=colour,
                                 table_id=label),
                      [f"*Table {n_table}: {caption}*", "", render_md(table, fmt)])
        return lines + [""], [{"kind": "table", "file": f} for f in files]

    def add_figure(png, caption):
        nonlocal n_figure
        n_figure += 1
        dst_png, dst_pdf = export_figure(png, out / "figures", f"figure-{n_figure}")
        return ([f"![Figure {n_figure}: {caption}](figures/{dst_png.name})", ""],
                [{"kind": "figure", "file": f"figures/{dst_pdf.name}", "caption": caption,
                  "label": f"figure-{n_figure}"}])

    for sec in section_order:
        md += [f"## {sec} {{#{_anchor(sec)}}}", ""]
        tex_studies = []
        for sec_, _, name, title, meta, manifest, problem in entries:
            if sec_ != sec:
                continue
            md += [f"### {title} (`{name}`) {{#study-{_anchor(name)}}}", ""]
            items, findings = [], ""
            tex_studies.append({"title": title, "findings": "", "items": items})
            if problem == "missing":
                default = known.get(name, {}).get("default", False)
                md += [f"**Missing**: no results in `{_shown(results / name)}`. Run `python -m experiments.run {name}`"
                       + ("" if default else " (not a default study)") + ".", ""]
                tex_studies[-1]["findings"] = f"Missing: no results. Run python -m experiments.run {name}."
                continue
            if problem:
                md += [f"**Broken**: {problem}.", ""]
                tex_studies[-1]["findings"] = f"Broken: {problem}."
                continue
            provenance = provenance or meta
            counts = meta.get("status_counts", {}) if isinstance(meta.get("status_counts"), dict) else {}
            if counts.get("error"):
                md += [f"**failed rows: {counts['error']} of {meta.get('n_rows')}**: the tables below hold what ran; "
                       "the failed rows are in `results.csv`.", ""]
            plugins = meta.get("plugins") or {}
            md += [f"{meta.get('n_rows')} rows{'; *quick run* (reduced grid)' if meta.get('quick') else ''}; "
                   f"commit `{(meta.get('git_commit') or '?')[:10]}`"
                   f"{' (dirty)' if meta.get('git_dirty') else ''}, {meta.get('date')}, config hash `{meta.get('config_hash')}`"
                   + (f"; plugins: {', '.join(f'{k} {v}' for k, v in plugins.items())}" if plugins else "") + ".", ""]
            if manifest.get("findings"):
                md += [f"**Findings.** {manifest['findings']}", ""]
                tex_studies[-1]["findings"] = str(manifest["findings"])
            for t in manifest.get("tables", []):
                try:
                    path = (results / name / t["file"]).resolve()
                    if (results / name).resolve() not in path.parents:
                        raise BrokenStudy(f"table {t['file']!r} lies outside the study folder")
                    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
                except (OSError, ValueError, KeyError, TypeError, BrokenStudy, pd.errors.ParserError) as exc:
                    md += [f"**Broken table**: {exc}.", ""]
                    continue
                lines, tex_items = add_table(table, str(t.get("caption", "")), t.get("unit") or "",
                                             int(t.get("digits") or 7), t.get("colour", ""))
                md += lines
                items += tex_items
            for f in manifest.get("figures", []):
                try:
                    png = _figure_path(results / name, f.get("file") if isinstance(f, dict) else None)
                except BrokenStudy as exc:
                    md += [f"**Broken figure**: {exc}.", ""]
                    continue
                lines, tex_items = add_figure(png, str(f.get("caption", "")) or f"{title}: {f.get('file')}")
                md += lines
                items += tex_items
        tex_sections.append({"title": sec, "label": _anchor(sec), "studies": tex_studies})
    if has_rankings:
        lines, tex_studies = _rankings_section(rankings, ranking_problem, out, add_table, add_figure)
        md += lines
        tex_sections.append({"title": RANKINGS_SECTION, "label": _anchor(RANKINGS_SECTION), "studies": tex_studies})
    provenance_text = None
    if provenance:
        v = provenance.get("versions", {})
        provenance_text = (f"Machine: {provenance.get('cpu')} ({provenance.get('cores')} cores), "
                           f"{provenance.get('platform')}; BLAS {provenance.get('blas')}. Versions: "
                           + ", ".join(f"{k} {val}" for k, val in v.items()) + ".")
        md += ["## Provenance", "",
               f"Machine: {provenance.get('cpu')} ({provenance.get('cores')} cores), {provenance.get('platform')}; "
               f"BLAS {provenance.get('blas')}.", "",
               "Versions: " + ", ".join(f"{k} {val}" for k, val in v.items()) + ".", "",
               "Each study's `meta.json` holds its own commit, date, configuration and hash.", ""]
    text = "\n".join(md)
    write_atomic(out / "report.md", re.sub(r"<!--/?block(:\w+)?-->\n", "", text))
    write_atomic(out / "report.html", to_html(text, out, blocks))
    write_report_tex(out, tex_sections, provenance=provenance_text)
    log(f"report: {out / 'report.md'}, {out / 'report.html'}, {out / 'report.tex'}, {n_table} tables, {n_figure} figures")
    return out


RANKINGS_SECTION = "Rankings across data sets"


def _rankings_section(rankings, problem, out, add_table, add_figure):
    """Performance profiles of every declared ranking (one panel each) and, per ranking, the median cost of
    each method per data set coloured relative to the row's best."""
    md = [f"## {RANKINGS_SECTION} {{#{_anchor(RANKINGS_SECTION)}}}", "",
          f"### Performance profiles {{#study-{_anchor('performance profiles')}}}", ""]
    intro = ("Dolan–Moré performance profiles pool every study that declares a ranking ([[rankings]] in its "
             "configuration): for each problem (study, data set, data stream, repetition) the ratio "
             "τ = cost / best cost over the methods, and ρ(τ) = the share of problems on which a method is within "
             "τ of the best (ρ(1): share of problems where it is best; a failure never reaches any τ).")
    items = []
    if problem:
        md += [f"**Broken ranking**: {problem}.", ""]
        return md, [{"title": "Performance profiles", "findings": f"Broken ranking: {problem}.", "items": items}]
    md += [intro, ""]
    words = []
    for name, r in rankings.items():
        best1 = (r.table.values == r.table.min(axis=1).values[:, None]).mean(axis=0) if len(r.table) else []
        if len(r.table):
            k = int(np.argmax(best1))
            words.append(f"{name}: {r.table.columns[k]} is best on {100 * best1[k]:.0f} % of {len(r.table)} problems")
    findings = ("; ".join(words) + ".") if words else "No problem is shared by the methods of a ranking."
    md += [f"**Findings.** {findings}", ""]
    import textwrap
    tables = {textwrap.fill(n, 34): r.table for n, r in rankings.items() if r.table is not None and len(r.table)}
    if tables:
        import matplotlib
        matplotlib.use("Agg")
        from experiments.render.profiles import plot_profiles
        from experiments.study import atomic_path
        png = out / "figures" / ".profiles-source.png"
        png.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(png) as tmp:
            plot_profiles(tables, tmp)
        sources = "; ".join(f"{n}: studies {', '.join(r.studies)}, {len(r.table)} problems"
                            + (f", left out (not run in every study): {', '.join(r.left_out)}" if r.left_out else "")
                            for n, r in rankings.items())
        lines, tex_items = add_figure(png, "Performance profiles of the methods: share of problems ρ(τ) on which a "
                                      "method's cost is within a factor τ of the best (log₂ τ on the x axis; higher "
                                      f"and further left is better). {sources}.")
        png.unlink(missing_ok=True)
        md += lines
        items += tex_items
    for name, r in rankings.items():
        if r.by_dataset is None or r.by_dataset.empty:
            continue
        lines, tex_items = add_table(r.by_dataset.reset_index(),
                                     f"Median {name} per data set and method over the data set's problems (failed, "
                                     "or -- in the LaTeX table: failed on at least half of them); colour in the HTML "
                                     "report: ratio to the best method of the row",
                                     r.unit, 3, "lower_is_better")
        md += lines
        items += tex_items
    return md, [{"title": "Performance profiles", "findings": intro + " Findings: " + findings, "items": items}]


def save_csv_plain(df: pd.DataFrame, path: Path) -> None:
    import io
    buf = io.StringIO()
    df.to_csv(buf, index=False, float_format="%.10g")
    write_atomic(path, buf.getvalue())


def to_html(markdown: str, out: Path, blocks: dict[str, str] | None = None) -> str:
    """A small Markdown-to-HTML rendering (headings, paragraphs, tables, images embedded as data URIs);
    a block ``<!--block:KEY-->...<!--/block-->`` is replaced by ``blocks[KEY]`` (ready HTML)."""
    body, table = [], []
    blocks = blocks or {}
    skipping = False

    def inline(s):
        s = html.escape(s)
        s = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", s)
        s = re.sub(r"\*(.+?)\*", r"<em>\1</em>", s)
        s = re.sub(r"`(.+?)`", r"<code>\1</code>", s)
        return re.sub(r"\[(.+?)\]\((#[\w-]+)\)", r'<a href="\2">\1</a>', s)

    def flush():
        if table:
            rows = [r.strip().strip("|").split("|") for r in table if not set(r.replace("|", "").strip()) <= {"-"}]
            head, *rest = rows
            body.append("<table><thead><tr>" + "".join(f"<th>{inline(c.strip())}</th>" for c in head) + "</tr></thead><tbody>"
                        + "".join("<tr>" + "".join(f"<td>{inline(c.strip())}</td>" for c in r) + "</tr>" for r in rest)
                        + "</tbody></table>")
            table.clear()

    for line in markdown.splitlines():
        mark = re.match(r"<!--block:(\w+)-->$", line)
        if mark:
            flush()
            body.append(blocks[mark.group(1)])
            skipping = True
            continue
        if line == "<!--/block-->":
            skipping = False
            continue
        if skipping:
            continue
        if line.startswith("|"):
            table.append(line)
            continue
        flush()
        m = re.match(r"!\[(.*?)\]\((.*?)\)", line)
        if line.startswith("#"):
            level = len(line) - len(line.lstrip("#"))
            head = re.match(r"(.*?)\s*\{#([\w-]+)\}$", line[level:].strip())
            text, ident = (head.group(1), head.group(2)) if head else (line[level:].strip(), "")
            body.append(f"<h{level}" + (f' id="{ident}"' if ident else "") + f">{inline(text)}</h{level}>")
        elif line.lstrip().startswith("- "):
            indent = len(line) - len(line.lstrip())
            body.append(f'<div style="margin-left:{indent}em">&bull; {inline(line.strip()[2:])}</div>')
        elif m:
            data = base64.b64encode((out / m.group(2)).read_bytes()).decode()
            body.append(f'<figure id="{Path(m.group(2)).stem}"><img alt="{html.escape(m.group(1))}" '
                        f'src="data:image/png;base64,{data}"><figcaption>{html.escape(m.group(1))}</figcaption></figure>')
        elif line.strip():
            body.append(f"<p>{inline(line)}</p>")
    flush()
    script = ("<script>window.addEventListener('load',function(){var im=document.images,ok=0;"
              "for(var i=0;i<im.length;i++){if(im[i].complete&&im[i].naturalWidth>0)ok++;}"
              "document.body.setAttribute('data-images',ok+'/'+im.length);});</script>")
    style = ("<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222;line-height:1.4}"
             "table{border-collapse:collapse;margin:1em 0;font-size:0.85em}th,td{border:1px solid #bbb;padding:3px 6px}"
             "td.num{text-align:right;font-variant-numeric:tabular-nums}"
             "caption{caption-side:top;text-align:left;font-size:0.95em;padding-bottom:4px}"
             "th{background:#eee}img{max-width:100%}figure{margin:1.5em 0}figcaption{font-size:0.9em;color:#333}"
             "nav#toc{background:#f6f6f6;padding:0.5em 1em;border:1px solid #ddd}nav#toc ul{margin:0.2em 0}</style>")
    return ("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>fitbench comparison report</title>"
            + style + script + "</head><body>" + "\n".join(body) + "</body></html>\n")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m experiments.report", description="Build paper/ from results/.")
    from fitbench import __version__
    parser.add_argument("--version", action="version", version=f"%(prog)s (fitbench {__version__})")
    parser.add_argument("--results", type=Path, default=REPO / "results")
    parser.add_argument("--out", type=Path, help="default: paper/ beside the results folder")
    args = parser.parse_args(argv)
    if args.out is None:
        args.out = args.results.resolve().parent / "paper"
    if not args.results.is_dir():
        print(f"experiments.report: error: no results folder {args.results}; run python -m experiments.run first",
              file=sys.stderr)
        return 2
    build(args.results, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
