"""The real report of a quick run, as a reviewer reads it: every LaTeX fragment of the built
report compiles on A4 (2.5 cm margins) with no overfull box wider than 1 pt, ``report.tex`` compiles with its
table of contents, and the HTML report in headless Chromium has numbered figure/table captions, a table of
contents whose links all have targets, images that load, coloured method tables and the cross-study rankings.

The report is built from a quick run of the studies that declare rankings (published, noise, scaling;
about a minute). ``FITBENCH_REPORT_RESULTS=DIR`` reuses an existing results folder instead (e.g. a full
``python -m experiments.run --quick --out DIR``).
"""
from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from experiments import report
from experiments.render.latex import compile_pdf, standalone_document
from experiments.render.rankings import collect
from experiments.render.report_tables import html_table, latex_fragments
from tests.report_checks import check_html_report, chromium, ranked_quick_run

pytestmark = pytest.mark.system  # builds the report of a quick run, compiles it with TeX, renders it in Chromium

REPO = Path(__file__).resolve().parents[1]
PDFLATEX = shutil.which("pdflatex")
needs_pdflatex = pytest.mark.skipif(PDFLATEX is None, reason="pdflatex is not installed (Debian: apt-get install "
                                    "texlive-latex-base texlive-latex-recommended texlive-latex-extra texlive-science lmodern)")
needs_chromium = pytest.mark.skipif(chromium() is None, reason="no chromium/chromium-browser on PATH")
MAX_OVERFULL_PT = 1.0


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """The report the quick run built (``RESULTS/paper``, what tests/test_explorer.py reads too), copied, since the
    TeX test compiles into it; with FITBENCH_REPORT_RESULTS, the report of that folder, built here."""
    given = os.environ.get("FITBENCH_REPORT_RESULTS")
    out = tmp_path_factory.mktemp("paper")
    if given:
        report.build(Path(given), out, log=lambda *a: None)
    else:
        shutil.copytree(ranked_quick_run(tmp_path_factory) / "paper", out, dirs_exist_ok=True)
    return out


def _overfull(result):
    return [o for o in result["overfull"] if o[1] > MAX_OVERFULL_PT]


@needs_pdflatex
def test_every_fragment_fits_a4(built, tmp_path):
    fragments = sorted((built / "tables").glob("*.tex"))
    assert len(fragments) >= 5, fragments
    doc = standalone_document([f.read_text(encoding="utf-8") for f in fragments])
    result = compile_pdf(doc, tmp_path, name="fragments")
    assert result["ok"], result["errors"] or result["log"][-2000:]
    assert not _overfull(result), _overfull(result)[:5]
    # every table is numbered and made of siunitx S columns for its numbers, units as \si
    text = "\n".join(f.read_text(encoding="utf-8") for f in fragments)
    assert "S[table-format=" in text and "e+0" not in text


@needs_pdflatex
def test_report_tex_compiles_with_contents(built):
    tex = (built / "report.tex").read_text(encoding="utf-8")
    inputs = re.findall(r"\\input\{(tables/[^}]+)\}", tex)
    assert sorted(inputs) == sorted(f"tables/{p.name}" for p in (built / "tables").glob("*.tex"))
    assert len(re.findall(r"\\includegraphics", tex)) == len(list((built / "figures").glob("*.png")))
    result = compile_pdf(tex, built, name="report_check", runs=2)
    assert result["ok"], result["errors"] or result["log"][-2000:]
    assert not _overfull(result), _overfull(result)[:5]
    toc = (built / "report_check.toc").read_text(encoding="latin-1")
    # the studies' section(s) and the rankings (a report of these three studies holds no other section)
    assert "Rankings across data sets" in toc and toc.count("\\contentsline {section}") >= 2


@needs_chromium
def test_html_report_in_chromium(built):
    problems = check_html_report(built / "report.html", min_figures=3, min_tables=3)
    assert problems == [], problems
    page = (built / "report.html").read_text(encoding="utf-8")
    assert 'id="rankings-across-data-sets"' in page and "Performance profiles of the methods" in page
    assert 'class="ranked"' in page and "background-color" in page     # a coloured method table
    assert page.count("<strong>Findings.</strong>") >= 2


def test_rankings_pool_studies_and_keep_methods_not_run_everywhere(tmp_path):
    def study(name, methods, costs, decl):
        folder = tmp_path / name
        folder.mkdir()
        rows = pd.DataFrame({"study": name, "dataset": "d", "data_stream": [f"s{i // len(methods)}" for i in range(len(costs))],
                             "repetition": 0, "method": methods * (len(costs) // len(methods)), "params": "{}",
                             "status": "ok", "err": costs})
        rows.to_csv(folder / "results.csv", index=False)
        return name, folder, {"config": {"rankings": [decl]}}
    decl = {"profile": "error", "metric": "err", "methods": "c.*"}
    a = study("a", ["c.x", "c.y"], [1.0, 2.0, 4.0, 1.0], decl)
    b = study("b", ["c.x", "c.y", "c.z"], [3.0, 3.0, 1.0], decl)
    r = collect([a, b])["error"]
    assert r.studies == ["a", "b"] and r.left_out == []
    assert r.table.shape == (3, 3)                      # 2 problems of a + 1 of b, methods x, y and z
    assert r.table.loc["b | d | s0 | 0"].tolist() == [3.0, 3.0, 1.0]
    assert r.runs == {"c.x": 3, "c.y": 3, "c.z": 1}     # z ran on b's problem only: absent elsewhere, not failed
    bad = study("c", ["c.x"], [1.0], {"profile": "error", "metric": "nope"})
    with pytest.raises(ValueError, match="nope"):
        collect([bad])


@needs_pdflatex
def test_wide_table_is_split_never_overflowing(tmp_path):
    df = pd.DataFrame({"scenario": [f"a long scenario name number {i}" for i in range(6)]}
                      | {f"method_{k}_name": np.linspace(0.001, 123.0, 6) * (k + 1) for k in range(24)})
    frags = latex_fragments(df, caption="wide", label="wide", unit="um", digits=4)
    assert len(frags) >= 2 and all("scenario" in f for f in frags)
    result = compile_pdf(standalone_document(frags), tmp_path)
    assert result["ok"] and not _overfull(result), _overfull(result)[:3]


def test_html_table_colours_only_declared_comparisons():
    df = pd.DataFrame({"data set": ["p", "q"], "m1": [1.0, 4.0], "m2": [2.0, 2.0]})
    coloured = html_table(df, caption="Table 1: x", unit="um", colour="lower_is_better")
    assert "2<br><small>2×</small>" in coloured and "<caption>Table 1: x</caption>" in coloured and "µm" in coloured
    assert "background-color" in coloured
    plain = html_table(df, caption="Table 1: x", unit="um")
    assert "background-color" not in plain and "<small>" not in plain and "<caption>Table 1: x</caption>" in plain


def test_schema_knows_colour_and_rankings():
    """A table's colour is one the report knows, checked by the generated schema before any row."""
    import tomllib
    from experiments.study import ConfigError
    from experiments.schema import check_structure
    cfg = tomllib.loads((REPO / "experiments" / "configs" / "noise.toml").read_text(encoding="utf-8"))
    cfg.pop("kind", None)   # the generic study: its own keys only
    cfg = {k: v for k, v in cfg.items() if k in ("name", "title", "seed", "repetitions", "datasets", "methods",
                                                 "summary_by", "report", "rankings")}
    table = {"caption": "c", "rows": "m", "values": "v", "colour": "lower_is_better"}
    check_structure({**cfg, "tables": [table]}, "x")
    with pytest.raises(ConfigError, match="rainbow"):
        check_structure({**cfg, "tables": [{**table, "colour": "rainbow"}]}, "x")
