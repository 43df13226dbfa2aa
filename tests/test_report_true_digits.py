"""A printed digit is a digit of the data. The studies hand their tables over unrounded and the renderer alone
chooses the digits shown (experiments/render/numbers.py), never more than the values carry: a study that rounded
coverage to 95.5 % printed as 95.50 % beside the 95.48 % of its rows, stations rounded to 0.001 µm as -0.6570 for
-0.6568 µm, runtimes as 34.7000 ms. Also: the magnification figure draws no value for a skipped variant, the
abstract keeps a findings list whole, and the exact-length multilateration table says what its error is."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from experiments.render.report_tables import html_table, latex_fragments, text_frame

REPO = Path(__file__).resolve().parents[1]
RESULTS, PAPER = REPO / "results", REPO / "paper"


def _true_digits(text: str, value: float) -> bool:
    """The printed number is ``value`` rounded to the printed decimals (within half a unit of its last digit)."""
    decimals = len(text.split(".")[1]) if "." in text else 0
    return abs(float(text) - value) <= 0.5 * 10 ** -decimals * (1 + 1e-9)


def test_a_column_rounded_before_the_renderer_is_not_padded_in_any_rendering():
    rounded = pd.DataFrame({"band": ["a", "b", "c", "d"], "coverage [%]": [88.7, 95.5, 34.7, 22.9],
                            "time [ms]": [34.7, 0.348, 0.007, 88.723]})
    shown = text_frame(rounded, unit="", digits=7)
    assert list(shown["coverage [%]"]) == ["88.7", "95.5", "34.7", "22.9"]
    assert list(shown["time [ms]"]) == ["34.700", "0.348", "0.007", "88.723"]
    html = html_table(rounded, caption="c", unit="", digits=7)
    tex = "".join(latex_fragments(rounded, caption="c", label="t", unit="", digits=7))
    for page in (html, tex):
        assert "95.50" not in page and "34.7000" not in page and "0.0070" not in page
    assert ">95.5<" in html and ">34.700<" in html and " 95.5 " in tex and " 34.700 " in tex


def test_unrounded_values_keep_the_digits_the_renderer_chooses():
    values = pd.DataFrame({"band": ["a", "b", "c"], "coverage [%]": [88.72, 95.482, 84.136]})
    assert list(text_frame(values, unit="", digits=7)["coverage [%]"]) == ["88.72", "95.48", "84.14"]


def _md_table(md: str, caption_words: str) -> pd.DataFrame:
    """The Markdown table after the caption that contains ``caption_words``, cells as text."""
    after = md.split(caption_words, 1)[1].split("\n\n", 1)[1]
    lines = [ln for ln in after.split("\n\n", 1)[0].splitlines() if ln.startswith("|")]
    cells = [[c.strip().replace("\\[", "[").replace("\\]", "]") for c in ln.strip("|").split("|")] for ln in lines]
    return pd.DataFrame(cells[2:], columns=cells[0])


def _committed(*paths: Path):
    for p in paths:
        if not p.exists():
            pytest.fail(f"{p.relative_to(REPO)} is missing (committed with the project): run python -m experiments.run "
                        f"and experiments.report")


def test_the_committed_coverage_table_prints_true_digits_of_the_rows():
    """Table 'Coverage of the true deviation curve' of paper/report.md against the means of
    results/positioning/results.csv (1000 tests per cell): 95.48 %, not 95.50 %."""
    _committed(PAPER / "report.md", RESULTS / "positioning" / "results.csv")
    rows = pd.read_csv(RESULTS / "positioning" / "results.csv")
    means = rows[rows["status"] == "ok"].groupby(["dataset", "method"])[["coverage", "band_halfwidth_mean",
                                                                          "error_rms"]].mean()
    shown = _md_table((PAPER / "report.md").read_text(encoding="utf-8"), "Coverage of the true deviation curve")
    assert len(shown) == len(means)
    for r in shown.itertuples(index=False):
        truth = means.loc[(r[0], r[1])]
        for text, value in zip(r[2:], (100 * truth["coverage"], 1e3 * truth["band_halfwidth_mean"],
                                        1e3 * truth["error_rms"])):
            assert _true_digits(text, value), (r[0], r[1], text, value)


def test_the_committed_stations_table_prints_true_digits_of_the_rows():
    """Table 'Stations located by each scheme' against station_deltas_um of results/multilateration/results.csv:
    -0.6568 µm, not -0.6570."""
    _committed(PAPER / "report.md", RESULTS / "multilateration" / "results.csv")
    from experiments import config as configs
    from experiments.studies.multilateration import stations_table
    rows = pd.read_csv(RESULTS / "multilateration" / "results.csv", keep_default_na=False, na_values=[""],
                       low_memory=False)
    _, st = stations_table(rows, configs.load("multilateration"))
    shown = _md_table((PAPER / "report.md").read_text(encoding="utf-8"), "Stations located by each scheme")
    assert len(shown) == len(st) > 0
    for (_, r), (_, s) in zip(st.iterrows(), shown.iterrows()):
        assert (r["method"], r["station"]) == (s["method"], s["station"])
        for c in ("dx", "dy", "dz", "dL"):
            assert _true_digits(s[f"{c} [µm]"], r[f"{c}_um"]), (r["method"], r["station"], c)


def test_a_skipped_variant_is_not_drawn_as_a_value(tmp_path, monkeypatch):
    """Figure 'Continuity ...': a variant that does not apply to an example drew a × at continuity 1 (on the dashed
    'continuous' line, where it read as a value); now it has no marker on either panel and its row says 'skipped'."""
    from experiments.render import style
    from experiments.studies import magnification
    rows = pd.DataFrame({"dataset": ["e1", "e1", "e2", "e2"], "method": ["a", "b", "a", "b"],
                         "status": ["ok", "skipped", "ok", "ok"], "continuity": [0.5, np.nan, 2.0, 0.8],
                         "loops": [0.0, np.nan, 3.0, 0.0]})
    seen = {}

    def keep(fig, path, **kw):
        seen["fig"] = fig
        fig.canvas.draw()
        seen["points"] = [(ax, x) for ax in fig.axes for line in ax.get_lines()
                          for x in np.asarray(line.get_xdata(), float) if np.isfinite(x) and line.get_linestyle() in
                          ("None", "none", "")]
        seen["words"] = [t.get_text() for ax in fig.axes for t in ax.texts]
        return Path(path)

    monkeypatch.setattr(style, "save", keep)
    magnification.continuity_figure(rows, tmp_path / "c.png")
    cont, loops = seen["fig"].axes[:2]
    assert sorted(x for ax, x in seen["points"] if ax is cont) == [0.5, 0.8, 2.0]     # the ok rows, nothing at 1
    assert sorted(x for ax, x in seen["points"] if ax is loops) == [0.0, 0.0, 3.0]
    assert seen["words"] == ["skipped"]


MAGNIFICATION = ("Examples where the magnified trajectory is continuous (continuity ≤ 1) and has no loops, out of those "
                 "the algorithm applies to: nearest (conventional): 3 of 8; offset same side, delta = 1.2 eta e_max: "
                 "4 of 4.")
SCALING = ("For N >= 1000, 7 of 17 methods scale about linearly (log-log slope 0.8 to 1.2); the smallest slope is "
           "ellipse.algebraic_nm's (0.25), the largest circle.powell_hybrid's (0.87).")


def test_the_abstract_keeps_a_findings_list_whole():
    """The abstract cut the magnification finding at its first '; ' ("nearest (conventional): 3 of 8."), dropping
    the offset variants; a '; ' that ends a statement of its own (no ':' before it) still ends the clause."""
    from experiments.report import _abstract
    entries = [("s", 1, "magnification", "Magnified contouring errors: x", {"n_rows": 40}, {"findings": MAGNIFICATION},
                None),
               ("s", 2, "scaling", "Scaling: y", {"n_rows": 97}, {"findings": SCALING}, None)]
    text = _abstract(entries, {})
    assert "nearest (conventional): 3 of 8; offset same side, delta = 1.2 eta e_max: 4 of 4." in text
    assert "(log-log slope 0.8 to 1.2)." in text and "smallest slope" not in text


def test_the_exact_length_table_names_its_statistic_and_schemes():
    """The exact-length multilateration table called its columns 'case b vs truth', 'case a vs truth': the
    schemes (the config's conditioning_check) and the statistic (largest coordinate error, not aligned) are named."""
    _committed(RESULTS / "multilateration" / "report.json")
    from experiments import config as configs
    spec = configs.load("multilateration")["conditioning_check"]
    tables = json.loads((RESULTS / "multilateration" / "report.json").read_text(encoding="utf-8"))["tables"]
    (t,) = [t for t in tables if t["caption"].startswith("Exact lengths")]
    header = pd.read_csv(RESULTS / "multilateration" / t["file"], nrows=0).columns
    for scheme in (spec["published"], spec["reference"]):
        short = scheme.split(".", 1)[1]
        assert f"{short} vs truth, largest [µm]" in header and short in t["caption"]
    assert "largest coordinate error" in t["caption"] and "without alignment" in t["caption"]
