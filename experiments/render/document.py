"""``paper/report.tex``: the LaTeX document that ``\\input``s the table fragments and includes the figures,
from the jinja2 template ``templates/report.tex.j2`` (delimiters ``((( )))`` and ``((* *))`` so that TeX
braces need no escaping).

    write_report_tex(out_dir, sections=[{"title": ..., "label": ..., "studies": [
        {"title": ..., "findings": "text with $maths$", "items": [
            {"kind": "table", "file": "tables/noise-1.tex"},
            {"kind": "figure", "file": "figures/noise.pdf", "caption": "...", "label": "noise"}]}]}])

Text (titles, findings, captions) is escaped by ``text.tex`` (``$...$`` kept as maths); file paths are
relative to ``out_dir`` and must exist.
"""
from __future__ import annotations

import datetime as _dt
from pathlib import Path

import jinja2

from experiments.render.latex import PREAMBLE
from experiments.render.text import tex

TEMPLATE = Path(__file__).with_name("templates") / "report.tex.j2"


def _environment() -> jinja2.Environment:
    return jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATE.parent)), block_start_string="((*",
                              block_end_string="*))", variable_start_string="(((", variable_end_string=")))",
                              comment_start_string="((=", comment_end_string="=))", autoescape=False,
                              undefined=jinja2.StrictUndefined, trim_blocks=True, lstrip_blocks=True)


def render_report_tex(sections: list[dict], *, title: str = "fitbench: comparison report", date: str | None = None,
                      provenance: str | None = None) -> str:
    """The document's source (see the module docstring for ``sections``)."""
    clean = []
    for s in sections:
        studies = []
        for st in s.get("studies", []):
            items = []
            for it in st.get("items", []):
                if it.get("kind") not in ("table", "figure"):
                    raise ValueError(f"report item {it!r}: kind must be 'table' or 'figure'")
                if it["kind"] == "figure" and not it.get("caption"):
                    raise ValueError(f"figure {it.get('file')!r} has no caption: say what is shown, on what data, "
                                     "in which units and what to look for")
                items.append({**it, "caption": tex(it.get("caption", "")), "width": it.get("width")})
            studies.append({"title": tex(st["title"]), "findings": tex(st.get("findings") or ""), "items": items})
        clean.append({"title": tex(s["title"]), "label": s.get("label"), "studies": studies})
    return _environment().get_template(TEMPLATE.name).render(
        preamble=PREAMBLE, title=tex(title), date=tex(date or _dt.date.today().isoformat()), sections=clean,
        provenance=tex(provenance) if provenance else None)


def write_report_tex(out_dir, sections: list[dict], **kw) -> Path:
    """Write ``out_dir/report.tex`` atomically; every referenced file must exist under ``out_dir``."""
    import os
    out_dir = Path(out_dir)
    missing = [it["file"] for s in sections for st in s.get("studies", []) for it in st.get("items", [])
               if not (out_dir / it["file"]).exists()]
    if missing:
        raise FileNotFoundError(f"report.tex would reference missing file(s) under {out_dir}: {missing[:5]}")
    path = out_dir / "report.tex"
    tmp = path.with_name(".report.tex.tmp")
    tmp.write_text(render_report_tex(sections, **kw), encoding="utf-8")
    os.replace(tmp, path)
    return path
