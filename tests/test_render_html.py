"""The HTML pieces of the report in headless Chromium: numbered captions, table of contents with working
anchors, every image loads; coloured ratio tables; the Dolan–Moré profile arithmetic."""
from __future__ import annotations

import base64
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from experiments.render.html_tables import coloured_table, ratio_colour
from experiments.render.profiles import performance_ratios, problem_table, profile, plot_profiles
from tests.report_checks import check_html_report, chromium, screenshot

needs_chromium = pytest.mark.skipif(chromium() is None, reason="no chromium/chromium-browser on PATH")


def _table():
    t = pd.DataFrame({"circle.kasa": [1.0, 4.0, np.inf], "circle.gauss_newton": [2.0, 2.0, 3.0],
                      "circle.minimum_zone": [1.0, 8.0, 1.5]}, index=pd.Index(["p1", "p2", "p3"], name="problem"))
    return t


def test_profile_by_hand():
    r = performance_ratios(_table())
    assert r.loc["p2", "circle.minimum_zone"] == 4.0 and r.loc["p3", "circle.kasa"] == np.inf
    rho = profile(_table(), [1.0, 2.0, 4.0, 100.0])
    # kasa: best on p1 (tie), 2x on p2, failed on p3
    assert rho["circle.kasa"].tolist() == pytest.approx([1 / 3, 2 / 3, 2 / 3, 2 / 3])
    assert rho["circle.gauss_newton"].tolist() == pytest.approx([1 / 3, 1.0, 1.0, 1.0])
    assert rho["circle.minimum_zone"].tolist() == pytest.approx([2 / 3, 2 / 3, 1.0, 1.0])


def test_ties_are_not_decided_by_rounding():
    t = pd.DataFrame({"a": [1.0, 1.0], "b": [1.0 + 1e-12, 3.0]})
    assert profile(t, [1.0])["b"].iloc[0] == 0.5
    assert profile(t, [1.0], rtol=0.0)["b"].iloc[0] == 0.0


def test_problem_table_from_rows():
    rows = pd.DataFrame({"study": "s", "dataset": ["a", "a", "b", "b", "c"], "data_stream": "0",
                         "method": ["m.x", "m.y", "m.x", "m.y", "m.x"], "params": "{}",
                         "status": ["ok", "ok", "ok", "not converged", "ok"], "err": [1e-20, 2.0, 3.0, 1.0, 1.0]})
    t = problem_table(rows, metric="err", floor=1e-9)
    assert t.shape == (2, 2) and t.attrs["dropped_problems"] == 1       # c: m.y never ran there
    assert t.loc["s | b | 0", "m.y"] == np.inf                           # not converged = failure
    assert t.loc["s | a | 0", "m.x"] == 1e-9                             # floored
    with pytest.raises(ValueError, match="repeat"):
        problem_table(pd.concat([rows, rows]), metric="err")
    with pytest.raises(ValueError, match="no column"):
        problem_table(rows, metric="nope")


def cell_colours(html: str) -> dict[tuple[int, int], str]:
    """{(row, column): background colour} of a Styler table, read from its <style> block."""
    import re
    out = {}
    for selectors, colour in re.findall(r"([^{}]+)\{\s*background-color:\s*(#[0-9a-f]{6})", html):
        for r, c in re.findall(r"_row(\d+)_col(\d+)", selectors):
            out[int(r), int(c)] = colour
    return out


def test_coloured_table():
    from experiments.render.html_tables import BANDS, FAIL_COLOUR
    html = coloured_table(_table(), unit="µm", caption="Table 1: errors")
    assert html.count("<tr>") == 4 and "failed" in html and "Cell colour" in html
    assert ratio_colour(1.0) != ratio_colour(3.0) != ratio_colour(np.inf)
    colours = cell_colours(html)
    assert len(colours) == 9
    assert colours[1, 2] == dict(BANDS)[5.0] and ">8.0<br><small>4×</small>" in html        # p2: 8 = 4 x the best
    assert colours[0, 0] == colours[0, 2] == dict(BANDS)[1.0]                            # p1: a tie for the best
    assert colours[2, 0] == FAIL_COLOUR                                                   # p3: kasa failed
    big = coloured_table(pd.DataFrame({"a": [4.07e8, 2.5], "b": [1.5e-5, 1e-4]}), digits=3)
    assert "4.07×10⁸" in big and "1.5×10⁻⁵" in big        # one format per column (experiments.render.numbers),
    assert "1.0×10⁻⁴" in big                               # with no more digits than its values carry
    with pytest.raises(ValueError):
        coloured_table(pd.DataFrame({"a": [-1.0]}))


def build_sample_report(folder: Path, *, broken_image=False, unnumbered=False) -> Path:
    """A small report like the real one: TOC, two sections, a numbered figure (a profile PNG, once as a file
    and once embedded) and a numbered coloured table."""
    folder.mkdir(parents=True, exist_ok=True)
    png = folder / "figures" / "profile.png"
    plot_profiles({"error": _table()}, png)
    data = base64.b64encode(png.read_bytes()).decode()
    src = "figures/missing.png" if broken_image else "figures/profile.png"
    cap = "A profile" if unnumbered else "Figure 1: performance profile of three methods on three problems."
    html = f"""<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>sample</title></head><body>
<h1>Sample report</h1>
<nav id="toc"><ol><li><a href="#sec-1">1 Accuracy</a></li><li><a href="#sec-2">2 Runtime</a></li></ol></nav>
<h2 id="sec-1">1 Accuracy</h2>
<figure><img src="{src}" alt="profile"><figcaption>{cap}</figcaption></figure>
{coloured_table(_table(), unit="µm", caption="Table 1: error by problem (colour: ratio to the best).")}
<h2 id="sec-2">2 Runtime</h2>
<figure><img src="data:image/png;base64,{data}" alt="profile"><figcaption>Figure 2: the same, embedded.</figcaption></figure>
</body></html>"""
    path = folder / "report.html"
    path.write_text(html, encoding="utf-8")
    return path


@needs_chromium
def test_sample_report_passes(tmp_path):
    report = build_sample_report(tmp_path / "ok")
    assert check_html_report(report) == []
    shot = screenshot(report, tmp_path / "top.png", width=1000, height=900)
    assert shot.stat().st_size > 10_000


@pytest.mark.slow  # a report built and three Chromium checks: 3.3 s
@needs_chromium
def test_checks_can_fail(tmp_path):
    problems = check_html_report(build_sample_report(tmp_path / "bad", broken_image=True, unnumbered=True))
    assert any("do not load" in p for p in problems)
    assert any("unnumbered figure" in p for p in problems)
    no_toc = tmp_path / "bad" / "notoc.html"
    no_toc.write_text((tmp_path / "bad" / "report.html").read_text().replace('id="toc"', 'id="x"')
                      .replace('id="sec-2"', 'id="elsewhere"'))
    assert any("no table of contents" in p for p in check_html_report(no_toc))
    dead = tmp_path / "bad" / "dead.html"
    dead.write_text((tmp_path / "bad" / "report.html").read_text().replace('id="sec-2"', 'id="elsewhere"'))
    assert any("without a target" in p for p in check_html_report(dead))


def test_declared_unit_is_not_doubled_nor_put_on_counts():
    """A column that names its own unit keeps it once; a count column (whole numbers, even as floats after a
    CSV round trip) gets no length unit and is printed as an integer."""
    import pandas as pd
    from experiments.render.report_tables import html_table, latex_fragments
    df = pd.DataFrame({"method": ["a", "b"], "largest error [mm]": [0.46, 1.1e-13], "sets > 1e-9 mm": [27.0, 0.0],
                       "not_converged": [0, 2], "radius": [1.5, 2.25]})
    out = html_table(df, caption="c", unit="mm")
    assert "largest error [mm]</th>" in out and "[mm] [mm]" not in out
    assert "sets &gt; 1e-9 mm</th>" in out and ">27<" in out and "27.0" not in out
    assert ">not converged</th>" in out            # a count of fits: no unit (the field name as words)
    assert "radius [mm]</th>" in out
    tex = "".join(latex_fragments(df, caption="c", label="t", unit="mm"))
    assert tex.count(r"\si{\milli\metre}") == 1 and r"radius \\ {}[\si{\milli\metre}]" in tex
    assert "& 27 &" in tex


def test_markdown_table_keeps_every_value_in_its_cell():
    """report.md and summary.md tables (pandas' to_markdown): a user's '|' or '<b>' stays text in its cell,
    floats in the given format, NaN empty, numbers right-aligned."""
    from markdown_it import MarkdownIt
    from experiments.render.page import markdown_table
    df = pd.DataFrame({"set | name": ["p|q", "<b>x</b>"], "error": [1.23456789, np.nan], "runs": [3, 4]})
    md = markdown_table(df, ".4g")
    html = MarkdownIt("commonmark").enable("table").render(md)
    assert html.count("<td ") == 6 and html.count("<th ") == 3 and "<b>" not in html
    assert ">p|q</td>" in html and ">1.235</td>" in html and 'style="text-align:right">4</td>' in html
    assert html.count('style="text-align:right"></td>') == 1            # NaN: an empty cell


def test_profile_curves_carry_their_methods_markers_along_them_staggered():
    """13 methods share a 12-colour palette (kasa and pratt are both pinks): each curve carries its method's marker
    at several places, staggered between methods, and the legend shows line and marker together."""
    import matplotlib.pyplot as plt
    from experiments.render import style
    from experiments.render.profiles import MARKS
    fig = plot_profiles({"error": _table()})
    try:
        ax = fig.axes[0]
        methods = list(_table().columns)
        marked = [ln for ln in ax.get_lines() if ln.get_linestyle() in ("None", "") and len(ln.get_xdata()) == MARKS]
        assert len(marked) == len(methods) >= 2
        assert {ln.get_marker() for ln in marked} == {style.method_style(m)["marker"] for m in methods}
        starts = [float(ln.get_xdata()[0]) for ln in marked]
        assert len(set(starts)) == len(starts)                       # staggered: no two methods' marks coincide
        handles = fig.legends[0].legend_handles if hasattr(fig.legends[0], "legend_handles") else fig.legends[0].legendHandles
        assert all(h.get_marker() not in (None, "None", "") for h in handles)
    finally:
        plt.close(fig)
