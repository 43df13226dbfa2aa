"""``python -m experiments.report [--results DIR] [--out DIR]``: the comparison report, built only from
the studies' output in ``results/`` (default ``results/`` -> ``paper/``).

Writes ``report.md``, a self-contained ``report.html`` (images embedded), LaTeX table fragments
``tables/*.tex`` (booktabs) and every figure as PNG and PDF under ``figures/``. A study that is missing
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

import pandas as pd

from experiments import config as configs
from experiments.provenance import REPO, write_atomic
from methods import InvalidInputError

# ---------------------------------------------------------------- tables

def latex_table(df: pd.DataFrame, caption: str, label: str, floatfmt: str = ".7g") -> str:
    """A booktabs table fragment (\\begin{table}...\\end{table}); needs \\usepackage{booktabs}."""
    def esc(v):
        if isinstance(v, float):
            v = "" if v != v else format(v, floatfmt)
        s = str(v)
        for a, b in (("\\", r"\textbackslash{}"), ("&", r"\&"), ("%", r"\%"), ("$", r"\$"), ("#", r"\#"),
                     ("_", r"\_"), ("{", r"\{"), ("}", r"\}"), ("~", r"\textasciitilde{}"), ("^", r"\^{}")):
            s = s.replace(a, b)
        return s.replace("±", r"$\pm$").replace("µ", r"$\mu$").replace("°", r"$^\circ$").replace("≥", r"$\geq$")
    cols = "l" * len(df.columns)
    lines = [r"\begin{table}[htbp]", r"\centering", r"\small", f"\\begin{{tabular}}{{{cols}}}", r"\toprule",
             " & ".join(esc(c) for c in df.columns) + r" \\", r"\midrule"]
    lines += [" & ".join(esc(v) for v in row) + r" \\" for row in df.itertuples(index=False)]
    lines += [r"\bottomrule", r"\end{tabular}", f"\\caption{{{esc(caption)}}}", f"\\label{{tab:{label}}}",
              r"\end{table}", ""]
    return "\n".join(lines)


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
    for sub, patterns in (("tables", ("*.tex",)), ("figures", ("*.png", "*.pdf"))):
        for pattern in patterns:
            for p in (out / sub).glob(pattern) if (out / sub).is_dir() else []:
                p.unlink()
    for p in out.glob(".*.tmp"):
        p.unlink()


def build(results: Path, out: Path, log=print, *, render_latex=latex_table, render_md=md_table) -> Path:
    """Build the report from every study folder in ``results`` and every default study (missing ones
    are shown as missing). ``render_latex``/``render_md`` render one table (swap in another renderer)."""
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

    md = ["# fitbench: comparison report", "",
          f"Built from `{_shown(results)}` by `python -m experiments.report`; reproduce everything with "
          "`python -m experiments.run` (the default studies) and "
          "`FITBENCH_NIST_DIR=... python -m experiments.run nist_circle`.", ""]
    # --- hook of experiments.verify (engine): the last reproducibility verdict, when there is one
    from experiments.verify import verdict_markdown
    md += verdict_markdown(results) + [""]
    # --- end of hook
    if any(e[4] and e[4].get("quick") for e in entries):
        md += ["**Note:** studies marked *quick run* ran the reduced `--quick` grid; their numbers are not the "
               "published comparison.", ""]
    md += ["## Contents", ""]
    for sec in section_order:
        md.append(f"- [{sec}](#{_anchor(sec)})")
        md += [f"  - [{e[3]}](#study-{_anchor(e[2])})" for e in entries if e[0] == sec]
    md.append("")
    provenance = None
    n_table = n_figure = 0
    for sec in section_order:
        md += [f"## {sec} {{#{_anchor(sec)}}}", ""]
        for sec_, _, name, title, meta, manifest, problem in entries:
            if sec_ != sec:
                continue
            md += [f"### {title} (`{name}`) {{#study-{_anchor(name)}}}", ""]
            if problem == "missing":
                default = known.get(name, {}).get("default", False)
                md += [f"**Missing**: no results in `{_shown(results / name)}`. Run `python -m experiments.run {name}`"
                       + ("" if default else " (not a default study)") + ".", ""]
                continue
            if problem:
                md += [f"**Broken**: {problem}.", ""]
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
            for t in manifest.get("tables", []):
                try:
                    path = (results / name / t["file"]).resolve()
                    if (results / name).resolve() not in path.parents:
                        raise BrokenStudy(f"table {t['file']!r} lies outside the study folder")
                    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
                except (OSError, ValueError, KeyError, TypeError, BrokenStudy, pd.errors.ParserError) as exc:
                    md += [f"**Broken table**: {exc}.", ""]
                    continue
                n_table += 1
                caption = str(t.get("caption", "")).rstrip()
                if t.get("unit"):
                    caption += ("" if caption.endswith(".") else ".") + f" Unit: {t['unit']}."
                fmt = f".{int(t.get('digits', 7))}g"
                write_atomic(out / "tables" / f"table-{n_table}.tex", render_latex(table, caption, f"table-{n_table}", fmt))
                md += [f"*Table {n_table}: {caption}*", "", render_md(table, fmt), ""]
            for f in manifest.get("figures", []):
                try:
                    png = _figure_path(results / name, f.get("file") if isinstance(f, dict) else None)
                except BrokenStudy as exc:
                    md += [f"**Broken figure**: {exc}.", ""]
                    continue
                n_figure += 1
                dst_png, _ = export_figure(png, out / "figures", f"figure-{n_figure}")
                md += [f"![Figure {n_figure}: {f.get('caption', '')}](figures/{dst_png.name})", ""]
    if provenance:
        v = provenance.get("versions", {})
        md += ["## Provenance", "",
               f"Machine: {provenance.get('cpu')} ({provenance.get('cores')} cores), {provenance.get('platform')}; "
               f"BLAS {provenance.get('blas')}.", "",
               "Versions: " + ", ".join(f"{k} {val}" for k, val in v.items()) + ".", "",
               "Each study's `meta.json` holds its own commit, date, configuration and hash.", ""]
    text = "\n".join(md)
    write_atomic(out / "report.md", text)
    write_atomic(out / "report.html", to_html(text, out))
    log(f"report: {out / 'report.md'}, {out / 'report.html'}, {n_table} tables, {n_figure} figures")
    return out


def to_html(markdown: str, out: Path) -> str:
    """A small Markdown-to-HTML rendering (headings, paragraphs, tables, images embedded as data URIs)."""
    body, table = [], []

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
            body.append(f'<figure><img alt="{html.escape(m.group(1))}" src="data:image/png;base64,{data}">'
                        f"<figcaption>{html.escape(m.group(1))}</figcaption></figure>")
        elif line.strip():
            body.append(f"<p>{inline(line)}</p>")
    flush()
    script = ("<script>window.addEventListener('load',function(){var im=document.images,ok=0;"
              "for(var i=0;i<im.length;i++){if(im[i].complete&&im[i].naturalWidth>0)ok++;}"
              "document.body.setAttribute('data-images',ok+'/'+im.length);});</script>")
    style = ("<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}"
             "table{border-collapse:collapse;margin:1em 0;font-size:0.85em}th,td{border:1px solid #bbb;padding:3px 6px}"
             "th{background:#eee}img{max-width:100%}figure{margin:1em 0}figcaption{font-size:0.8em;color:#555}</style>")
    return ("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>fitbench comparison report</title>"
            + style + script + "</head><body>" + "\n".join(body) + "</body></html>\n")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m experiments.report", description="Build paper/ from results/.")
    from experiments.verify import _version  # --version (engine)
    parser.add_argument("--version", action="version", version=f"%(prog)s (fitbench {_version()})")
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
