"""``python -m experiments.report [--results DIR] [--out DIR]``: the comparison report, built only from
the studies' output in ``results/`` (default ``results/`` -> ``paper/``).

Writes ``report.md``, a self-contained ``report.html`` (images embedded), LaTeX table fragments
``tables/*.tex`` (booktabs) and every figure as PNG and PDF under ``figures/``. A study that is missing
or whose rows failed is shown as such, never dropped. Also run at the end of ``python -m experiments.run``.
"""
from __future__ import annotations

import argparse
import base64
import html
import json
import re
import shutil
import sys
from pathlib import Path

import pandas as pd

from experiments import config as configs
from experiments.provenance import REPO, write_atomic

#: the studies in reading order, by source paper
SECTIONS = [
    ("Roundness paper (Pınar & Güllü): least squares, minimum zone, MIC, MCC",
     ["published", "nist_circle", "noise", "convergence", "scaling"]),
    ("Circle/ellipse paper (Glavonjić): circular tests, ellipse fits", ["circular_test", "ellipse_angle"]),
    ("Positioning paper (Kureková et al.): ISO 230-2 and the polynomial model", ["positioning"]),
    ("Magnification paper (Ibaraki & Matsubara)", ["magnification"]),
    ("Multilateration paper (Holub et al.): the four schemes, two better ones, the 21 errors", ["multilateration"]),
]


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


def study_tables(name: str, folder: Path, meta: dict) -> list[tuple[str, pd.DataFrame]]:
    """The tables a reader wants from each study (captions first)."""
    f = meta.get("findings", {})
    out = []
    if name == "published":
        rows = [{"set": r["dataset"] + ("" if r["variant"] == "as published" else f" ({r['variant']})"),
                 "column": r["column"], "published": r["published"], "reproduced": round(r["reproduced_value"], 7),
                 "difference": round(r["difference"], 7),
                 "explanation": "reproduced" if r["reproduced"] else
                 (f"rounding of the printed coordinates: 99 % range {r['rounding_p0_5']:.6f}..{r['rounding_p99_5']:.6f}, "
                  f"published at the {r['published_percentile']:.0f}th percentile" if r["explained_by_rounding"]
                  else "NOT explained")}
                for r in f.get("published_vs_reproduced", [])]
        out.append(("Roundness paper, table 1: published against reproduced circularity [mm]", pd.DataFrame(rows)))
    elif name == "nist_circle":
        rows = [{"method": k, "max error [mm]": v["max_error"], "median error [mm]": v["median_error"],
                 "sets > 1e-9": v["sets_over_1e-9"], "not converged": v["not_converged"]}
                for k, v in f.get("summary", {}).items()]
        out.append(("NIST Circle2d (30 sets): error against the reference least-squares circle", pd.DataFrame(rows)))
    elif name == "noise":
        t = pd.read_csv(folder / "kcr.csv")
        t = t[(t["noise"] == t["noise"].max()) & (t["n"] == t["n"].max())]
        piv = t.pivot_table(index="method", columns="arc_deg", values="radius_rmse_over_kcr", sort=False)
        piv = piv[sorted(piv.columns, reverse=True)].reset_index()
        piv.columns = ["method"] + [f"{c:.0f}° arc" for c in piv.columns[1:]]
        out.append((f"Radius RMSE / KCR bound at sigma = {t['noise'].max():g} R, N = {t['n'].max()} (1 = the statistical limit)",
                    piv.round(2)))
    elif name == "convergence":
        t = pd.read_csv(folder / "success.csv")
        for arc, g in t.groupby("arc_deg", sort=False):
            piv = g.pivot_table(index=["method", "params"], columns="start_distance", values="success_rate", sort=False)
            piv.columns = [f"{c:g} R" for c in piv.columns]
            piv = piv.reset_index()
            piv["method"] = piv["method"] + piv["params"].map(lambda p: "" if p == "{}" else " " + p.replace('"', ""))
            out.append((f"Convergence from distant starts ({arc:.0f}° arc): success rate by start distance",
                        piv.drop(columns=["params"]).round(2)))
    elif name == "scaling":
        t = pd.read_csv(folder / "runtime_table.csv")
        t = t.rename(columns={t.columns[0]: "method"})
        for c in t.columns[1:-1]:
            t[c] = (t[c] * 1e3).round(3)
        t.columns = ["method"] + [f"N={int(float(c))} [ms]" for c in t.columns[1:-1]] + ["slope"]
        out.append(("Median runtime per fit against N, and the log-log slope for N >= 1000", t.round(3)))
    elif name == "ellipse_angle":
        out.append(("Angle of a near-circle: RMS angle error [deg] against a - b, and the first-order prediction",
                    pd.DataFrame(f.get("summary", [])).round(4)))
    elif name == "circular_test":
        iso = f.get("iso230_4", {})
        pub = f.get("iso230_4_published_um", {})
        rows = [{"figure": k, "synthetic scenario [um]": round(iso[k] * 1e3, 2), "published [um]": pub.get(k, "")}
                for k in ("G_cw", "G_ccw", "G_b", "H", "F_max", "F_min", "mean_radial_deviation") if k in iso]
        out.append(("ISO 230-4 figures of the synthetic LOLA HBG 130 test (the paper's measured data are not published)",
                    pd.DataFrame(rows)))
        dg, inj = f.get("diagnostics", {}), f.get("injected", {})
        rows = [{"source": k, "estimate": round(v["value"], 3) if v["value"] is not None else "",
                 "u": round(v["u"], 3) if v["u"] is not None else "", "unit": v["unit"],
                 "injected": round(inj[k], 3) if k in inj else ""} for k, v in dg.items()]
        out.append(("Diagnostics: error sources estimated from the two runs against the injected ones", pd.DataFrame(rows)))
    elif name == "positioning":
        t = pd.DataFrame(f.get("coverage", []))
        if len(t):
            t = t.rename(columns={"dataset": "scenario", "method": "band", "halfwidth_um": "half-width [um]",
                                  "error_rms_um": "RMS error [um]"}).round(3)
        out.append(("Coverage of the true deviation curve by the bands (1000 synthetic axes per scenario)", t))
    elif name == "magnification":
        df = pd.read_csv(folder / "results.csv")
        df["cell"] = df.apply(lambda r: "skipped" if r["status"] != "ok" else f"{r['continuity']:.2f} / {int(r['loops'])}", axis=1)
        piv = df.pivot_table(index="dataset", columns="method", values="cell", aggfunc="first", sort=False).reset_index()
        out.append(("Continuity (about 1 or less: continuous) / loops of the magnified trajectories", piv))
    elif name == "multilateration":
        st = f.get("stations_table", {})
        t = pd.DataFrame(st.get("rows", []))
        if len(t):
            t = t[t["method"] != "truth"][["method", "station", "dx_um", "dy_um", "dz_um", "dL_um"]].round(3)
            out.append((f"Stations located by each scheme, one campaign ({st.get('scenario', '')}): difference from the "
                        "truth [um] (the paper's tables 5-9; the joint adjustment in its gauge)", t))
        acc = pd.DataFrame(f.get("accuracy", []))
        if len(acc):
            keep = ["dataset", "stations", "method", "runs", "station_error_um", "volumetric_error_rms_um",
                    "aligned_error_rms_um", "model_error_rms_um", "kappa_stations", "kappa_stations_theorem1",
                    "kappa_points", "kappa_points_theorem1"]
            acc = acc[[c for c in keep if c in acc.columns]].rename(columns={
                "dataset": "scenario", "stations": "stations are", "station_error_um": "station [um]",
                "volumetric_error_rms_um": "vol. RMS [um]", "aligned_error_rms_um": "aligned RMS [um]",
                "model_error_rms_um": "21-error map RMS [um]", "kappa_stations": "kappa st.",
                "kappa_stations_theorem1": "Thm 1 st.", "kappa_points": "kappa pt.", "kappa_points_theorem1": "Thm 1 pt."})
            for c in acc.columns[4:]:
                acc[c] = acc[c].map(lambda v: "" if pd.isna(v) else f"{v:.3g}")
            out.append(("Median over the Monte Carlo runs: largest station error, volumetric-error error (RMS, and after "
                        "the best rigid alignment), error of the map from the 21 identified errors, condition numbers", acc))
        out.append(("Most accurate scheme per scenario (median aligned RMS [um])", pd.DataFrame(f.get("winner", [])).round(3)))
        r = pd.DataFrame(f.get("rounding", []))
        if len(r):
            for c in r.columns[2:]:
                r[c] = r[c].map(lambda v: f"{v:.3g}")
            out.append(("Exact lengths: what the published Case B's conditioning costs in double precision (its points "
                        "against the centred solution of the same equations) and its error against the truth [um]", r))
    return [(c, t) for c, t in out if t is not None and len(t)]


# ---------------------------------------------------------------- figures

def figure_files(folder: Path, meta: dict) -> list[Path]:
    names = []
    for key, value in meta.get("findings", {}).items():
        if key in ("figure", "example") and isinstance(value, str):
            names.append(value)
    return [folder / n for n in names if (folder / n).exists()]


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


def study_status(folder: Path) -> tuple[str, dict | None]:
    if not (folder / "meta.json").exists() or not (folder / "results.csv").exists():
        return "missing", None
    meta = json.loads((folder / "meta.json").read_text())
    counts = meta.get("status_counts", {})
    if counts.get("error"):
        return f"failed rows: {counts['error']} of {meta.get('n_rows')}", meta
    return "ok", meta


def build(results: Path, out: Path, log=print) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    (out / "tables").mkdir(exist_ok=True)
    known = {n: configs.load(n) for n in configs.available()}
    present = {p.name for p in results.iterdir() if p.is_dir()} if results.exists() else set()
    listed = [s for _, studies in SECTIONS for s in studies]
    extra = sorted(present - set(listed))
    md = ["# fitbench: comparison report", "",
          f"Built from `{_shown(results)}` by `python -m experiments.report`; reproduce everything with "
          "`python -m experiments.run` (the default studies) and "
          "`FITBENCH_NIST_DIR=... python -m experiments.run nist_circle`.", ""]
    # --- hook of experiments.verify (engine): the last reproducibility verdict, when there is one
    from experiments.verify import verdict_markdown
    md += verdict_markdown(results) + [""]
    # --- end of hook
    html_parts = []
    provenance = None
    for title, studies in SECTIONS + ([("Other studies", extra)] if extra else []):
        md += [f"## {title}", ""]
        if not studies:
            md += ["*No study yet: this part of the framework is not built (see the issue tracker).*", ""]
            continue
        for name in studies:
            cfg_title = known.get(name, {}).get("title", name)
            status, meta = study_status(results / name)
            md += [f"### {cfg_title} (`{name}`)", ""]
            if meta is None:
                default = known.get(name, {}).get("default", False)
                md += [f"**Missing**: no results in `{_shown(results / name)}`. Run `python -m experiments.run {name}`"
                       + ("" if default else " (not a default study)") + ".", ""]
                continue
            provenance = provenance or meta
            if status != "ok":
                md += [f"**{status}**: the table below holds what ran; the failed rows are in `results.csv`.", ""]
            md += [f"{meta.get('n_rows')} rows; commit `{(meta.get('git_commit') or '?')[:10]}`"
                   f"{' (dirty)' if meta.get('git_dirty') else ''}, {meta.get('date')}, config hash `{meta.get('config_hash')}`.", ""]
            for k, (caption, table) in enumerate(study_tables(name, results / name, meta)):
                label = f"{name}-{k + 1}"
                write_atomic(out / "tables" / f"{label}.tex", latex_table(table, caption, label))
                md += [f"*Table {label}: {caption}*", "", md_table(table), ""]
            for k, png in enumerate(figure_files(results / name, meta)):
                stem = f"{name}-{png.stem}"
                dst_png, _ = export_figure(png, out / "figures", stem)
                md += [f"![{name}: {png.stem}](figures/{dst_png.name})", ""]
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
    log(f"report: {out / 'report.md'}, {out / 'report.html'}, {len(list((out / 'tables').glob('*.tex')))} LaTeX tables, "
        f"{len(list((out / 'figures').glob('*.png'))) if (out / 'figures').exists() else 0} figures")
    return out


def to_html(markdown: str, out: Path) -> str:
    """A small Markdown-to-HTML rendering (headings, paragraphs, tables, images embedded as data URIs)."""
    body, table = [], []

    def inline(s):
        s = html.escape(s)
        s = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", s)
        s = re.sub(r"\*(.+?)\*", r"<em>\1</em>", s)
        return re.sub(r"`(.+?)`", r"<code>\1</code>", s)

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
            body.append(f"<h{level}>{inline(line[level:].strip())}</h{level}>")
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
    parser.add_argument("--out", type=Path, default=REPO / "paper")
    args = parser.parse_args(argv)
    if not args.results.is_dir():
        print(f"experiments.report: error: no results folder {args.results}; run python -m experiments.run first",
              file=sys.stderr)
        return 2
    build(args.results, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
