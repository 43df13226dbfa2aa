"""The interactive explorer (explorer.html) and the report's layout at 1280 px, in headless Chromium with the
network disabled: a method is toggled off in every plot of its ranking, a table is sorted and filtered, a click
on a problems-map cell draws that problem's fit and residuals; no table, caption or figure of report.html
reaches past the right edge of a 1280 px window (measured with the DOM's widths; a wide table scrolls inside
its box). The report is that of the quick run of the ranked studies (published, noise, scaling; about half a
minute) that tests/test_report_paper.py checks too (tests.report_checks.ranked_quick_run: one run for both)."""
from __future__ import annotations

import json
import os
import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

from experiments import report
from tests.report_checks import chromium, ranked_quick_run

needs_chromium = pytest.mark.skipif(chromium() is None, reason="no chromium on PATH (.ci/run installs Debian's chromium)")
pytestmark = pytest.mark.system   # a quick run of three studies and three Chromium loads: about a minute
OFFLINE = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--no-first-run",
           "--disable-component-update", "--disable-sync", "--host-resolver-rules=MAP * ~NOTFOUND",
           "--proxy-server=127.0.0.1:9", "--virtual-time-budget=15000"]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    return ranked_quick_run(tmp_path_factory) / "paper"


def run_in_chromium(page: Path, script: str, width: int = 1280) -> dict:
    """Load a copy of ``page`` with ``script`` appended (it must put JSON into <pre id="__check__">)."""
    probed = page.with_name(f".check-{os.getpid()}-{page.name}")  # the page may be shared by xdist workers
    text = page.read_text(encoding="utf-8")
    probed.write_text(text.replace("</body>", f"<script>{script}</script></body>"), encoding="utf-8")
    try:
        with tempfile.TemporaryDirectory(prefix="chromium-") as profile:
            proc = subprocess.run([chromium(), *OFFLINE, f"--user-data-dir={profile}", f"--window-size={width},900",
                                   "--dump-dom", probed.as_uri()], capture_output=True, text=True, timeout=180)
    finally:
        probed.unlink(missing_ok=True)
    m = re.search(r'<pre id="__check__">(.*?)</pre>', proc.stdout, flags=re.S)
    assert m, f"no result from the page (exit {proc.returncode}): {proc.stderr[-800:]}"
    import html
    return json.loads(html.unescape(m.group(1)))


EXPLORE = r"""
window.addEventListener('load', function () { setTimeout(function () {
  var out = {ready: document.body.getAttribute('data-explorer'), plotly: typeof Plotly};
  var r = explorer.data[0];
  var box = document.querySelector('#ranking-1 input[data-method="0"]');
  box.checked = false; box.dispatchEvent(new Event('change'));
  out.methods = r.methods;
  out.axes = explorer.data.map(function (d, k) {   // every axis of a cost names its unit (one per panel)
    var rt = document.getElementById('runtime-' + (k + 1));
    return {profile: document.getElementById('profile-' + (k + 1)).layout.title.text, metric: d.metric,
            runtime: rt.layout ? Object.keys(rt.layout).filter(function (a) { return /^[xy]axis\d*$/.test(a); })
                                       .map(function (a) { return rt.layout[a].title.text; }) : null};
  });
  out.visible = explorer.figures[0].map(function (id) {   // [method index, visible] of every trace
    return document.getElementById(id).data.map(function (t) {
      return [t.meta, t.visible === undefined ? true : t.visible]; });
  });
  out.covered = [];                                 // a plot's title under its mode bar
  document.querySelectorAll('.js-plotly-plot').forEach(function (plot) {
    var bar = plot.querySelector('.modebar'), title = plot.querySelector('.gtitle');
    if (!bar || !title) { return; }
    var a = bar.getBoundingClientRect(), b = title.getBoundingClientRect();
    if (a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom) {
      out.covered.push(plot.id + ': ' + title.textContent); }
  });
  var p = Object.keys(r.fits)[0], m = Object.keys(r.fits[p].methods)[0];
  document.getElementById('map-1').emit('plotly_click', {points: [{pointNumber: [r.problems.indexOf(p),
                                                                                r.methods.indexOf(m)]}]});
  var fit = document.getElementById('fit-1');
  out.fit = {problem: fit.getAttribute('data-problem'), method: fit.getAttribute('data-method'), asked: [p, m],
             traces: fit.data ? fit.data.map(function (t) { return t.x.length; }) : []};
  var table = document.querySelector('.explorer-table table'), ths = table.querySelectorAll('thead th');
  var col = Array.prototype.findIndex.call(table.tBodies[0].rows[0].cells, function (c) {
    return c.classList.contains('num'); });
  ths[col].click();
  out.sortedText = Array.prototype.map.call(table.tBodies[0].rows, function (row) {   // the number, not the ratio
    return row.cells[col].firstChild ? row.cells[col].firstChild.textContent.trim() : ''; });
  var filter = document.querySelector('input.filter');
  var first = table.tBodies[0].rows[0].cells[0].textContent.trim();
  filter.value = first; filter.dispatchEvent(new Event('input'));
  out.filtered = Array.prototype.filter.call(table.tBodies[0].rows, function (row) {
    return row.style.display !== 'none'; }).map(function (row) { return row.cells[0].textContent.trim(); });
  out.filter = first;
  out.external = Array.prototype.filter.call(document.querySelectorAll('[src],[href]'), function (e) {
    return /^(https?:)?\/\//.test(e.getAttribute('src') || e.getAttribute('href') || ''); }).length;
  var pre = document.createElement('pre'); pre.id = '__check__'; pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
}, 300); });
"""


def _number(text: str) -> float:
    t = text.split("\n")[0].replace("×10", "e").translate(str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789"))
    return float(t.split()[0])


@needs_chromium
def test_explorer_toggles_sorts_filters_and_draws_a_fit_offline(built):
    out = run_in_chromium(built / "explorer.html", EXPLORE)
    assert out["ready"] == "ready" and out["plotly"] == "object" and out["external"] == 0
    for axes in out["axes"]:   # readable names with units, never a bare column name such as form_error
        assert "_" not in axes["profile"], axes
        if axes["runtime"]:    # one unit per axis (never "mm (published) or R (noise)")
            assert all(re.search(r"\[[^]]+\]$", t) and "_" not in t and " or " not in t for t in axes["runtime"]), axes
        assert axes["runtime"] is None or axes["metric"] != "time_median_s", axes   # no runtime against itself
    assert out["covered"] == []
    for figure in out["visible"]:          # method 0 hidden in every plot (and panel) of the ranking, the others shown
        assert all((v == "legendonly") if j == 0 else (v is True) for j, v in figure), figure
    assert out["fit"]["problem"] == out["fit"]["asked"][0] and out["fit"]["method"] == out["fit"]["asked"][1]
    points, curve, residuals = out["fit"]["traces"]
    assert points >= 10 and curve > 50 and residuals == points
    shown = [_number(v) for v in out["sortedText"] if v not in ("–", "failed", "")]
    assert len(shown) >= 2 and shown == sorted(shown), out["sortedText"]
    assert out["filtered"] and all(out["filter"] in v for v in out["filtered"])


OVERFLOW = r"""
window.addEventListener('load', function () {
  var W = document.documentElement.clientWidth, bad = [], n = 0;
  document.querySelectorAll('table, caption, figcaption, figure, img, h1, h2, h3, p, nav').forEach(function (el) {
    n++;
    var box = el.tagName === 'TABLE' ? el.closest('.table-box') : null;   // a wide table scrolls in its box
    var r = (box || el).getBoundingClientRect();
    if (r.right > W + 0.5) { bad.push(el.tagName + ' ' + (el.textContent || '').slice(0, 60) + ' right=' + r.right); }
  });
  var pre = document.createElement('pre'); pre.id = '__check__';
  pre.textContent = JSON.stringify({width: W, checked: n, bad: bad, scroll: document.documentElement.scrollWidth});
  document.body.appendChild(pre);
});
"""


@needs_chromium
def test_no_table_or_caption_of_the_report_overflows_at_1280_px(built):
    out = run_in_chromium(built / "report.html", OVERFLOW, width=1280)
    assert out["checked"] > 40 and out["bad"] == [], out["bad"][:5]   # three studies and their rankings
    assert out["scroll"] <= out["width"]


def test_explorer_embeds_fits_whose_residuals_match_the_rows(built):
    """The drawn residuals are the distances of the points from the row's fitted circle: a least-squares
    circle's residuals have (almost) zero mean, and the embedded page holds no network reference."""
    text = (built / "explorer.html").read_text(encoding="utf-8")
    assert not re.search(r"""<script[^>]+src=|<link[^>]+href=["']https?:""", text)
    data = json.loads(re.search(r'<script type="application/json" id="explorer-data">(.*?)</script>', text,
                                flags=re.S).group(1))
    fits = [f for r in data for f in r["fits"].values()]
    assert fits
    gn = [f["methods"][m]["residual"] for f in fits for m in f["methods"] if m == "circle.gauss_newton"]
    assert gn and all(abs(np.mean(r)) < 0.05 * (np.max(np.abs(r)) + 1e-12) for r in gn if len(r) > 50)
