"""LaTeX fragments of the report compile on A4 (2.5 cm margins) without an overfull box wider than 1 pt.

The tables are the report's hardest: the multilateration accuracy table (60 rows x 12 columns, long repeated
scenario names), the roundness paper's published-against-reproduced table, the magnification table with maths
in its headers. They are built from the committed results/ (skipped with the reason when a study is absent).
"""
from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from experiments.render.latex import Column as C, TableTooWide, compile_pdf, latex_table, standalone_document
from experiments.render.text import ordinal, percentile_phrase

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "results"
PDFLATEX = shutil.which("pdflatex")
needs_pdflatex = pytest.mark.skipif(PDFLATEX is None, reason="pdflatex is not installed (apt-get install "
                                    "texlive-latex-extra texlive-science for booktabs/siunitx/multirow)")
MAX_OVERFULL_PT = 1.0


def _csv(study, name):
    path = RESULTS / study / name
    if not path.exists():
        pytest.skip(f"{path} is missing: run python -m experiments.run {study}")
    return pd.read_csv(path)


def multilateration_tables() -> list[str]:
    """The 60 x 12 accuracy table as two tables (errors; condition numbers), scenarios as group rows."""
    acc = _csv("multilateration", "accuracy.csv")
    keys = [C("dataset", group=True), C("stations", group=True)]
    errors = latex_table(acc, keys + [
        C("method"), C("runs", kind="integer"), C("station_error_um", "largest station error", "µm"),
        C("dead_path_error_um", "dead path error", "µm"),
        C("volumetric_error_rms_um", "volumetric error RMS", "µm"),
        C("aligned_error_rms_um", "aligned RMS", "µm"), C("model_error_rms_um", "21-error map RMS", "µm")],
        caption="Multilateration: medians over the Monte Carlo runs of the errors against the simulator's truth",
        label="ml-errors", notes=["--: not applicable (stations given, so not located; or no machine errors, so "
                                  "no 21-error map)."])
    kappa = latex_table(acc, keys + [
        C("method"), C("kappa_stations", r"$\kappa_2$ stations"), C("kappa_stations_theorem1", "Theorem 1 stations"),
        C("kappa_points", r"$\kappa_2$ points"), C("kappa_points_theorem1", "Theorem 1 points")],
        caption=r"Multilateration: median condition numbers $\kappa_2$ (SVD) and the lower estimate of Theorem 1",
        label="ml-kappa", notes=["--: stations given, step 1 not run."])
    return [errors, kappa]


def published_table() -> str:
    meta = RESULTS / "published" / "meta.json"
    if not meta.exists():
        pytest.skip(f"{meta} is missing: run python -m experiments.run published")
    pub = pd.DataFrame(json.loads(meta.read_text())["findings"]["published_vs_reproduced"])
    pub["difference_um"] = 1e3 * pub["difference"]
    pub["set"] = pub["dataset"] + np.where(pub["variant"] == "as published", "", " (closing point dropped)")
    pub["explanation"] = [
        "reproduced" if r.reproduced else
        (f"printed digits allow {r.rounding_p0_5:.6f}..{r.rounding_p99_5:.6f} mm (99 %); published at "
         f"{percentile_phrase(r.published_percentile, 0)}" if r.explained_by_rounding else "not explained")
        for r in pub.itertuples()]
    return latex_table(pub, [C("set", group=True), C("column", width="3.3cm"), C("published", unit="mm", exact=True),
                        C("reproduced_value", "reproduced", "mm", decimals=7), C("difference_um", "difference", unit="µm", digits=2),
                        C("explanation", width="5.2cm")],
                       caption="Roundness paper, table 1: published against reproduced circularity",
                       label="published")


def magnification_table() -> str:
    df = _csv("magnification", "results.csv")
    df["cell"] = [("skipped" if s != "ok" else f"{c:.2f} / {int(lo)}")
                  for s, c, lo in zip(df["status"], df["continuity"], df["loops"])]
    piv = df.pivot_table(index="dataset", columns="method", values="cell", aggfunc="first", sort=False).reset_index()
    headers = {"nearest (conventional)": "nearest (conventional)",
               "offset as printed, delta = 10 e_max": r"offset as printed, $\delta = 10\,e_\mathrm{max}$",
               "offset same side, delta = 2 e_max": r"same side, $\delta = 2\,e_\mathrm{max}$",
               "offset same side, delta = 10 e_max": r"same side, $\delta = 10\,e_\mathrm{max}$",
               "offset same side, delta = 1.2 eta e_max": r"same side, $\delta = 1.2\,\eta\,e_\mathrm{max}$"}
    cols = [C("dataset", "example")] + [C(m, headers.get(m, m), width="2.1cm") for m in piv.columns[1:]]
    return latex_table(piv, cols, caption=r"Magnified contouring errors: continuity / loops of the magnified "
                                          r"trajectory ($\le 1$: continuous)", label="magnification")


def _assert_compiles_within_page(fragments, tmp_path, name):
    result = compile_pdf(standalone_document(fragments), tmp_path, name=name)
    assert result["ok"], f"pdflatex failed: {result['errors'][:3]}"
    wide = [(pt, line) for kind, pt, line in result["overfull"] if kind == "h" and pt > MAX_OVERFULL_PT]
    assert not wide, f"{len(wide)} overfull boxes wider than {MAX_OVERFULL_PT} pt, e.g. {wide[:3]}"
    return result


@needs_pdflatex
def test_overfull_detection_can_fail(tmp_path):
    """The check itself: a table wider than the page must be reported as overfull."""
    wide = "\\begin{tabular}{" + "l" * 12 + "}\n" + " & ".join(["a-very-wide-cell-text"] * 12) + r" \\" + "\n\\end{tabular}"
    result = compile_pdf(standalone_document([wide]), tmp_path, name="wide")
    assert result["ok"]
    assert max(pt for _, pt, _ in result["overfull"]) > 100


@needs_pdflatex
def test_multilateration_tables_fit_a4(tmp_path):
    _assert_compiles_within_page(multilateration_tables(), tmp_path, "ml")


@needs_pdflatex
def test_published_table_fits_a4(tmp_path):
    _assert_compiles_within_page([published_table()], tmp_path, "pub")


@needs_pdflatex
def test_magnification_table_fits_a4(tmp_path):
    _assert_compiles_within_page([magnification_table()], tmp_path, "mag")


@needs_pdflatex
def test_every_results_csv_renders_or_is_flagged(tmp_path):
    """Every committed table CSV under results/ either renders to a fragment that fits, or is refused as too
    wide with a message (never silently overflows)."""
    frags, flagged = [], []
    for path in sorted(RESULTS.glob("*/*.csv")):
        if path.name in ("results.csv",):
            continue
        df = pd.read_csv(path)
        try:
            frags.append(latex_table(df.head(80), caption=f"{path.parent.name}: {path.stem}", label=path.stem))
        except TableTooWide as exc:
            assert "split" in str(exc)
            flagged.append(path.name)
    if not frags:
        pytest.skip("no table CSV under results/")
    _assert_compiles_within_page(frags, tmp_path, "all")


def test_too_wide_table_is_flagged():
    df = pd.DataFrame({f"a long column header {k}": np.linspace(1, 2e3, 4) for k in range(16)})
    with pytest.raises(TableTooWide, match="split"):
        latex_table(df, caption="x", label="wide")


def test_numbers_units_and_text():
    df = pd.DataFrame({"method": ["circle.kasa", "circle.gauss_newton"], "kappa": [4.07e8, 70.9],
                       "err": [-0.0123, 12.5], "n": [10, 2000]})
    frag = latex_table(df, [C("method"), C("kappa", r"$\kappa_2$"), C("err", "error", "um"), C("n", kind="integer")],
                       caption=r"Errors at $\sigma = 0.01\,R$ in µm; 91st percentile", label="t")
    assert "4.07e8" in frag and "4.07e+08" not in frag
    exact = latex_table(pd.DataFrame({"p": [0.029807, 1.7487]}), [C("p", exact=True)], caption="x", label="x")
    assert "0.029807 \\" in exact and "1.7487 \\" in exact and "S[table-format=1.6]" in exact                 # siunitx parses and prints 4.07 x 10^8
    assert r"\si{\micro\metre}" in frag and " um" not in frag
    assert r"$\kappa_2$" in frag and r"$\sigma = 0.01\,R$" in frag    # maths kept
    assert r"circle.gauss\_newton" in frag and r"\textmu{}m" in frag
    assert "S[table-format=-2.4]" in frag or "S[table-format=-2.3]" in frag
    assert "S[table-format=4.0]" in frag
    assert r"\toprule" in frag and r"\bottomrule" in frag


def test_long_table_is_split_over_pages():
    df = pd.DataFrame({"k": np.arange(100), "v": np.linspace(0, 1, 100)})
    frag = latex_table(df, caption="long", label="long")
    assert r"\begin{longtable}" in frag and r"\endhead" in frag


def test_bad_column_is_a_clear_error():
    with pytest.raises(ValueError, match="no column"):
        latex_table(pd.DataFrame({"a": [1]}), [C("b")], caption="x", label="x")
    with pytest.raises(ValueError, match="kind must be"):
        C("a", kind="float")


def test_ordinal():
    assert [ordinal(k) for k in (1, 2, 3, 4, 11, 12, 13, 21, 22, 23, 72, 91, 101, 111, 112, 113)] == [
        "1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "23rd", "72nd", "91st", "101st",
        "111th", "112th", "113th"]
    assert percentile_phrase(90.3) == "percentile 90.3" and percentile_phrase(91) == "the 91st percentile"
    with pytest.raises(ValueError):
        ordinal(-1)


@pytest.mark.slow  # a figure drawn and two pdflatex runs: 3.1 s
@needs_pdflatex
def test_report_tex_includes_fragments_and_figures_and_compiles(tmp_path):
    """paper/report.tex from the jinja2 template: sections, findings text with maths, \\input tables,
    figures with captions; compiles (twice, for the table of contents) without an overfull box > 1 pt."""
    from experiments.studies.noise import kcr_figure
    from experiments.render.document import write_report_tex
    (tmp_path / "tables").mkdir()
    frags = {"ml-errors": multilateration_tables()[0], "published": published_table(),
             "magnification": magnification_table()}
    for name, frag in frags.items():
        (tmp_path / "tables" / f"{name}.tex").write_text(frag, encoding="utf-8")
    kcr_figure(_csv("noise", "kcr.csv"), tmp_path / "figures" / "noise.png")
    sections = [{"title": "Roundness paper (Pınar & Güllü)", "label": "roundness", "studies": [
        {"title": "Published data", "findings": "Sample findings text (not a result): Kåsa, 45°, "
                                                "maths $\\sigma = 0.05\\,R$ and 2 %.",
         "items": [{"kind": "table", "file": "tables/published.tex"},
                   {"kind": "figure", "file": "figures/noise.png", "label": "noise",
                    "caption": "Radius RMSE / KCR bound and radius bias / σ against σ / R (100 points)."}]}]},
        {"title": "Magnification and multilateration", "studies": [
            {"title": "Tables", "items": [{"kind": "table", "file": "tables/magnification.tex"},
                                          {"kind": "table", "file": "tables/ml-errors.tex"}]}]}]
    path = write_report_tex(tmp_path, sections, provenance="commit abc, 2 cores")
    src = path.read_text()
    assert r"\tableofcontents" in src and r"\input{tables/published.tex}" in src and r"\label{fig:noise}" in src
    assert "$\\sigma = 0.05\\,R$" in src and "Kåsa" in src
    result = compile_pdf(src, tmp_path, name="report", runs=2)
    assert result["ok"], result["errors"][:3]
    wide = [(pt, line) for kind, pt, line in result["overfull"] if kind == "h" and pt > MAX_OVERFULL_PT]
    assert not wide, wide[:3]
    assert (tmp_path / "report.toc").read_text().count("contentsline") >= 4


@needs_pdflatex
def test_prose_listing_method_ids_stays_inside_the_margins(tmp_path):
    """The committed noise findings list method ids (circle.levenberg_marquardt, ...), which TeX cannot hyphenate:
    in the abstract they ran 54 pt into the right margin, in the study's findings 30 pt. Abstract, findings and
    notes may break after an id's dots and underscores."""
    from experiments.render.document import render_report_tex
    findings = json.loads((REPO / "results" / "noise" / "report.json").read_text(encoding="utf-8"))["findings"]
    assert "circle.levenberg_marquardt" in findings
    src = render_report_tex([{"title": "Noise", "studies": [{"title": "Noise", "findings": findings, "notes": [findings],
                                                             "items": []}]}],
                            abstract="11 studies compare the fitting methods. Noise: " + findings, date="2026-01-01")
    result = compile_pdf(src, tmp_path, name="prose", runs=1)
    assert result["ok"], result["errors"][:3]
    wide = [(pt, line) for kind, pt, line in result["overfull"] if kind == "h" and pt > MAX_OVERFULL_PT]
    assert not wide, wide[:3]


def test_report_tex_refuses_missing_files_and_captionless_figures(tmp_path):
    from experiments.render.document import render_report_tex, write_report_tex
    with pytest.raises(FileNotFoundError, match="missing"):
        write_report_tex(tmp_path, [{"title": "A", "studies": [{"title": "s", "items": [
            {"kind": "table", "file": "tables/none.tex"}]}]}])
    with pytest.raises(ValueError, match="no caption"):
        render_report_tex([{"title": "A", "studies": [{"title": "s", "items": [
            {"kind": "figure", "file": "f.png"}]}]}])


def test_group_values_are_heading_rows():
    """The values of group columns are an italic heading row above each group, not a column."""
    df = pd.DataFrame({"scenario": ["six", "six", "six", "four", "four"], "stations": ["1", "1", "2", "2", "2"],
                       "method": ["a", "b", "c", "a", "b"], "error": [1.5, 2.25, 30.0, 0.001, 4e-6]})
    frag = latex_table(df, [C("scenario", group=True), C("stations", group=True), C("method"), C("error", unit="µm")],
                       caption="grouped", label="g")
    body = frag.split("\\midrule\n")[1].split("\\bottomrule")[0].splitlines()
    headings = [r.split("\\itshape ")[1].split("}")[0] for r in body if "\\itshape" in r]
    assert headings == ["six; 1", "six; 2", "four; 2"] and body.count("\\addlinespace") == 2
    assert [r.split(" & ")[0] for r in body if " & " in r] == ["a", "b", "c", "a", "b"]


def _grouped(n_groups=17, per_group=2):
    return pd.DataFrame({"scenario": np.repeat([f"scenario {k}" for k in range(n_groups)], per_group),
                         "method": [f"m{j}" for _ in range(n_groups) for j in range(per_group)],
                         "error": np.linspace(0.1, 2.0, n_groups * per_group)})


def test_long_table_repeats_its_head_with_the_words_of_the_report():
    frag = latex_table(_grouped(), [C("scenario", group=True), C("method"), C("error", unit="mm")],
                       caption="grouped", label="g", long=True)
    assert "\\begin{longtable}" in frag and "Table \\thetable{} (continued)" in frag
    assert "continued on the next page" in frag and frag.count("\\caption") == 1


@needs_pdflatex
def test_grouped_table_never_makes_a_float_too_large(tmp_path):
    frag = latex_table(_grouped(34, 1), [C("scenario", group=True), C("method"), C("error", unit="mm")],
                       caption="grouped", label="g")
    result = compile_pdf(standalone_document([frag]), tmp_path)
    assert result["ok"] and not [w for w in result["warnings"] if "Float too large" in w], result["warnings"]


def _bookmarks(out_file) -> list[str]:
    """The PDF bookmarks hyperref wrote to its .out file (UTF-16 strings: octal escapes and literal bytes)."""
    marks = []
    for m in re.finditer(r"\\BOOKMARK \[\d\]\[-\]\{[^}]*\}\{(.*)\}\{[^}]*\}%", out_file.read_text(encoding="latin-1")):
        raw = bytes(int(t[1:], 8) if t.startswith("\\") else ord(t) for t in re.findall(r"\\[0-7]{3}|.", m.group(1)))
        marks.append(raw[2:].decode("utf-16-be") if raw.startswith(b"\xfe\xff") else raw.decode("latin-1"))
    return marks


@needs_pdflatex
def test_headings_with_superscripts_make_clean_pdf_bookmarks(tmp_path):
    """A heading with 10⁶ (set as \\textsuperscript) and TeX specials compiles without hyperref's 'Token not
    allowed in a PDF string' and its bookmark reads as written, not '10 to 106'."""
    from experiments.render.document import render_report_tex
    title = "Scaling: runtime against N (10 to 10⁶) & 5 µm_b, σ = 0.05 R, 100 %"
    src = render_report_tex([{"title": "Speed: 10⁶ points", "label": "s",
                              "studies": [{"title": title, "findings": "x", "items": []}]}])
    result = compile_pdf(src, tmp_path, name="report", runs=1)
    assert result["ok"], result["errors"]
    assert "Token not allowed" not in result["log"]
    assert _bookmarks(tmp_path / "report.out") == ["Speed: 10⁶ points", title]


def test_the_no_value_note_blames_a_method_only_in_a_table_of_methods():
    """Table 9's unestimated error source (cyclic_error: all '–') read 'the method did not run there or failed'."""
    import numpy as np
    import pandas as pd
    from experiments.render.report_tables import latex_fragments
    sources = pd.DataFrame({"source": ["squareness", "cyclic_error"], "estimate": [66.46, np.nan], "unit": ["urad", "um"]})
    tex = "".join(latex_fragments(sources, caption="c", label="t"))
    assert "no value" in tex and "method" not in tex
    fits = pd.DataFrame({"method": ["circle.kasa", "circle.pratt"], "error": [0.1, np.nan]})
    shown = "".join(latex_fragments(fits, caption="c", label="t", unit="mm"))
    assert "does not apply there, or the method did not run or failed" in shown
