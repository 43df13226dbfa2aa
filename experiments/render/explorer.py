"""``explorer.html``: the interactive companion of the report, one static page that works offline (Plotly's
JavaScript is embedded; no server, no network), built by ``experiments.report`` from the same declarations.

- every ranking the studies declare (``[[rankings]]``): Dolan–Moré performance profiles and the metric against
  the runtime, one Plotly trace per method (a checkbox per method, or a click on the legend, shows or hides it
  in every plot of the ranking), and the problems x methods map coloured by the ratio to the best method of the
  problem; a click on a cell draws that problem's points with the method's fitted circle or ellipse, and its
  residuals against the angle;
- every declared table of every study, sortable (click a header) and filterable (type in the box), coloured
  against the best method of the row where the study declares ``colour = "lower_is_better"``.

User text is text here too: the page is a jinja2 template with autoescaping; data travel as JSON inside
``<script type="application/json">`` (``tojson`` escapes ``<``, ``>``, ``&``), read by the page's own script.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import jinja2
import numpy as np
import pandas as pd
from markupsafe import Markup

MAX_PROBLEMS_WITH_FITS = 20   #: problems per ranking whose points and fits are embedded (the page stays small)
MAX_POINTS = 200              #: points per problem drawn (evenly subsampled)


def _r(v, sig: int = 7):
    """A finite float rounded to ``sig`` significant digits for JSON (None for NaN/inf)."""
    try:
        v = float(v)
    except (TypeError, ValueError):
        return None
    if not math.isfinite(v):
        return None
    return float(f"{v:.{sig}g}")


def _curve(row: pd.Series) -> tuple[list, list] | None:
    """The fitted circle or ellipse of a result row as a closed polyline (None when the row has no geometry)."""
    t = np.linspace(0, 2 * np.pi, 73)
    cx, cy = row.get("center_x"), row.get("center_y")
    a, b, th = row.get("semi_axis_a"), row.get("semi_axis_b"), row.get("angle")
    if _r(cx) is None or _r(cy) is None:
        return None
    if _r(a) is not None and _r(b) is not None:
        th = float(th) if _r(th) is not None else 0.0
        x = cx + a * np.cos(t) * np.cos(th) - b * np.sin(t) * np.sin(th)
        y = cy + a * np.cos(t) * np.sin(th) + b * np.sin(t) * np.cos(th)
    elif _r(row.get("radius")) is not None:
        x, y = cx + row["radius"] * np.cos(t), cy + row["radius"] * np.sin(t)
    else:
        return None
    return [_r(v) for v in x], [_r(v) for v in y]


def _residuals(row: pd.Series, pts: np.ndarray) -> list | None:
    """Signed distance of each point from the fitted curve (circle: exact; ellipse: along the ray from the
    centre, a first-order approximation of the orthogonal distance)."""
    cx, cy = row.get("center_x"), row.get("center_y")
    if _r(cx) is None or _r(cy) is None:
        return None
    d = pts - np.array([cx, cy], dtype=float)
    rho = np.hypot(d[:, 0], d[:, 1])
    a, b = row.get("semi_axis_a"), row.get("semi_axis_b")
    if _r(a) is not None and _r(b) is not None:
        th = float(row.get("angle")) if _r(row.get("angle")) is not None else 0.0
        phi = np.arctan2(d[:, 1], d[:, 0]) - th
        radius = a * b / np.hypot(b * np.cos(phi), a * np.sin(phi))
    elif _r(row.get("radius")) is not None:
        radius = float(row["radius"])
    else:
        return None
    return [_r(v, 5) for v in rho - radius]


def _points(meta: dict, study: str, dataset: str, stream: str):
    """The points of one problem, regenerated from the study's declaration (the data source and its seed
    stream); None when the source is not available here."""
    from experiments import engine
    cfg = meta.get("config") if isinstance(meta.get("config"), dict) else None
    if not cfg:
        return None
    try:
        entry, point, rep = (int(x) for x in str(stream).split("."))
        spec = next(s for s in engine.expand_datasets(cfg, study) if s["label"] == dataset
                    and s["entry"] == entry and s["point"] == point)
        pts, _ = engine.load_data(spec, int(cfg.get("seed", 0)), [entry, point, rep])
    except Exception:  # noqa: BLE001 - a source missing here (e.g. NIST files) means: no drawing, said on the page
        return None
    pts = np.asarray(pts, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2:
        return None
    return pts


def ranking_data(name: str, r, folders: dict[str, Path], metas: dict[str, dict]) -> dict:
    """Everything the page draws for one ranking (plain JSON)."""
    from experiments.render.profiles import method_label, performance_ratios, profile
    table = r.table
    methods = [str(c) for c in table.columns]
    ratios = performance_ratios(table)
    finite = ratios.to_numpy(float)
    finite = finite[np.isfinite(finite)]
    top = max(float(finite.max()) if finite.size else 1.0, 1.0 + 1e-9)
    taus = np.unique(np.concatenate([[1.0], np.geomspace(1.0, top * 1.01, 240)]))   # a grid, not every ratio
    prof = profile(table, taus=taus)
    data = {"name": name, "metric": r.metric, "unit": r.unit, "methods": methods, "problems": list(map(str, table.index)),
            "cost": [[_r(v) for v in row] for row in table.to_numpy(float)],
            "ratio": [[_r(v, 4) for v in row] for row in ratios.to_numpy(float)],
            "profile": {"tau": [_r(t, 5) for t in prof.index], "rho": {m: [_r(v, 5) for v in prof[m]] for m in methods
                                                                        if m in prof.columns}},
            "time": None, "fits": {}}
    # runtime per problem and method, from the rows (when the studies timed their fits)
    times = {}
    rows_by_study = {}
    for study in r.studies:
        try:
            rows = pd.read_csv(folders[study] / "results.csv", keep_default_na=False, na_values=[""], low_memory=False)
        except (OSError, ValueError):
            continue
        rows["_label"] = [method_label(m, p) for m, p in zip(rows["method"], rows.get("params", [None] * len(rows)))]
        rows_by_study[study] = rows
        if "time_median_s" in rows:
            keys = (study + " | " + rows["dataset"].astype(str) + " | " + rows["data_stream"].astype(str) + " | "
                    + rows["repetition"].astype(str))
            times.update({(k, lab): _r(t) for k, lab, t in zip(keys, rows["_label"], rows["time_median_s"])})
    if times:
        data["time"] = [[times.get((p, m)) for m in methods] for p in data["problems"]]
    for p in data["problems"][:MAX_PROBLEMS_WITH_FITS]:
        parts = p.split(" | ")
        if len(parts) < 4 or parts[0] not in rows_by_study:
            continue
        study, dataset, stream, rep = parts[0], parts[1], parts[2], parts[3]
        rows = rows_by_study[study]
        sel = rows[(rows["dataset"].astype(str) == dataset) & (rows["data_stream"].astype(str) == stream)
                   & (rows["repetition"].astype(str) == rep)]
        pts = _points(metas.get(study, {}), study, dataset, stream)
        if pts is None or sel.empty:
            continue
        keep = pts[np.linspace(0, len(pts) - 1, min(len(pts), MAX_POINTS)).astype(int)]
        fits = {}
        for _, row in sel.iterrows():
            if row["_label"] not in methods:
                continue
            curve, res = _curve(row), _residuals(row, keep)
            if curve is None or res is None:
                continue
            fits[row["_label"]] = {"x": curve[0], "y": curve[1], "residual": res, "status": str(row.get("status", ""))}
        if fits:
            angle = np.degrees(np.arctan2(keep[:, 1] - keep[:, 1].mean(), keep[:, 0] - keep[:, 0].mean())) % 360
            data["fits"][p] = {"x": [_r(v) for v in keep[:, 0]], "y": [_r(v) for v in keep[:, 1]],
                               "angle": [_r(v, 5) for v in angle], "methods": fits}
    return data


def table_blocks(tables: list[dict]) -> list[dict]:
    """The declared tables as HTML (coloured where declared), each with its caption; the table element's id is
    ``T_`` + the block's id (pandas Styler's)."""
    from experiments.render.report_tables import html_table
    out = []
    for k, t in enumerate(tables, start=1):
        out.append({"id": f"xtable-{k}", "html": Markup(html_table(t["data"], caption=t["caption"], unit=t["unit"],
                                                                    digits=t["digits"], colour=t["colour"],
                                                                    table_id=f"xtable-{k}"))})
    return out


def write_explorer(out: Path, rankings: dict, tables: list[dict], folders: dict[str, Path], metas: dict[str, dict],
                   *, title: str = "fitbench: interactive explorer") -> Path:
    """Write ``out/explorer.html`` (see the module docstring). ``tables``: [{caption, data, unit, digits,
    colour}] in report order."""
    from plotly.offline import get_plotlyjs
    data = [ranking_data(n, r, folders, metas) for n, r in rankings.items() if r.table is not None and len(r.table)]
    env = jinja2.Environment(autoescape=True, undefined=jinja2.StrictUndefined)
    page = env.from_string(PAGE).render(title=title, plotly=Markup(get_plotlyjs()), data=data,
                                        tables=table_blocks(tables), script=Markup(SCRIPT))
    from experiments.provenance import write_atomic
    path = out / "explorer.html"
    write_atomic(path, page)
    return path


PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>{{ title }}</title>
<style>
body{font-family:sans-serif;max-width:1200px;margin:1.5em auto;padding:0 1em;color:#222;line-height:1.4}
.table-box{overflow-x:auto;max-width:100%}caption{text-align:left;max-width:calc(min(100vw, 1200px) - 4em)}table{border-collapse:collapse;font-size:0.85em;margin:0.5em 0}
th,td{border:1px solid #bbb;padding:3px 6px}th{background:#eee;cursor:pointer}tbody th{text-align:left;min-width:9em}
td.num{text-align:right;white-space:nowrap}
th.sorted-asc::after{content:" ▲"}th.sorted-desc::after{content:" ▼"}
.methods label{margin-right:1em;white-space:nowrap;font-size:0.9em}.plots{display:flex;flex-wrap:wrap;gap:1em}
.plot{width:560px;height:420px}.fit{width:560px;height:420px}.filter{margin:0.3em 0}
</style>
<script>{{ plotly }}</script>
</head><body>
<h1>{{ title }}</h1>
<p>Built by <code>python -m experiments.report</code> beside <code>report.html</code>, from the same study
declarations; it needs no network. Toggle methods with the check boxes (or the legends), click a cell of a
problems map to draw that problem's fit and residuals, click a table header to sort, type in a filter box to
keep matching rows.</p>
{% for r in data %}
<section class="ranking" id="ranking-{{ loop.index }}" data-ranking="{{ loop.index0 }}">
<h2>Ranking: {{ r.name }}</h2>
<div class="methods">{% for m in r.methods %}<label><input type="checkbox" checked data-method="{{ loop.index0 }}"> {{ m }}</label>{% endfor %}</div>
<div class="plots">
<div class="plot profile" id="profile-{{ loop.index }}"></div>
<div class="plot runtime" id="runtime-{{ loop.index }}"></div>
<div class="plot map" id="map-{{ loop.index }}"></div>
<div class="fit" id="fit-{{ loop.index }}"><p>Click a cell of the problems map to draw that problem's fit.</p></div>
</div>
</section>
{% endfor %}
{% if not data %}<p>No study declares a ranking ([[rankings]]): no profiles to explore.</p>{% endif %}
<h2>Tables</h2>
{% for t in tables %}
<div class="explorer-table"><input class="filter" type="search" placeholder="filter rows" aria-label="filter rows of {{ t.id }}" data-table="T_{{ t.id }}">
{{ t.html }}</div>
{% endfor %}
<script type="application/json" id="explorer-data">{{ data|tojson }}</script>
<script>{{ script }}</script>
</body></html>
"""

#: the page's own script: reads the embedded JSON, draws with Plotly, wires check boxes, clicks, sorting, filters
SCRIPT = r"""
(function () {
  var DATA = JSON.parse(document.getElementById('explorer-data').textContent);
  var cfg = {displaylogo: false, responsive: true};
  // Plotly reads a few HTML tags in its text (legends, titles, ticks): user text goes in with <, >, & escaped
  function esc(s) { return String(s).replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;'); }
  window.explorer = {data: DATA, figures: []};
  DATA.forEach(function (r, k) {
    var n = k + 1, unit = r.unit ? ' [' + esc(r.unit) + ']' : '';
    var prof = r.methods.map(function (m) {
      return {x: r.profile.tau, y: r.profile.rho[m], name: esc(m), mode: 'lines', line: {shape: 'hv'}};
    });
    Plotly.newPlot('profile-' + n, prof, {title: {text: 'Performance profile: ' + esc(r.metric)},
      xaxis: {title: {text: 'τ (cost / best cost)'}, type: 'log'}, yaxis: {title: {text: 'ρ(τ): share of problems'},
      range: [0, 1.02]}, legend: {font: {size: 9}}, margin: {t: 40}}, cfg);
    var figs = ['profile-' + n];
    if (r.time) {
      var rt = r.methods.map(function (m, j) {
        return {x: r.time.map(function (row) { return row[j]; }), y: r.cost.map(function (row) { return row[j]; }),
                text: r.problems.map(esc), name: esc(m), mode: 'markers', type: 'scatter', marker: {size: 5}};
      });
      Plotly.newPlot('runtime-' + n, rt, {title: {text: esc(r.metric) + ' against runtime'},
        xaxis: {title: {text: 'median runtime [s]'}, type: 'log'}, yaxis: {title: {text: esc(r.metric) + unit}, type: 'log'},
        showlegend: false, margin: {t: 40}}, cfg);
      figs.push('runtime-' + n);
    } else {
      document.getElementById('runtime-' + n).textContent = 'The studies of this ranking did not time their fits.';
    }
    var z = r.ratio.map(function (row) { return row.map(function (v) { return v === null ? null : Math.log10(v); }); });
    Plotly.newPlot('map-' + n, [{type: 'heatmap', z: z, x: r.methods.map(esc), y: r.problems.map(esc), colorscale: [[0, '#1a9850'], [0.25, '#d9ef8b'], [0.5, '#fee08b'], [1, '#d73027']],
      zmin: 0, zmax: 1, colorbar: {title: {text: 'log₁₀ ratio<br>(blank: failed)'}},
      customdata: r.cost, hovertemplate: '%{y}<br>%{x}<br>' + esc(r.metric) + ' %{customdata}' + unit + '<extra></extra>'}],
      {title: {text: 'Ratio to the best method per problem'}, xaxis: {tickangle: 45, tickfont: {size: 8}},
       yaxis: {showticklabels: false, title: {text: 'problems'}}, margin: {t: 40, b: 110}}, cfg);
    document.getElementById('map-' + n).on('plotly_click', function (ev) {
      var ij = ev.points[0].pointNumber;          // [problem row, method column]
      explorer.showFit(k, r.problems[ij[0]], r.methods[ij[1]]);
    });
    explorer.figures.push(figs);
    document.querySelectorAll('#ranking-' + n + ' input[data-method]').forEach(function (box) {
      box.addEventListener('change', function () {
        var j = +box.getAttribute('data-method');
        figs.forEach(function (id) { Plotly.restyle(id, {visible: box.checked ? true : 'legendonly'}, [j]); });
      });
    });
  });
  explorer.showFit = function (k, problem, method) {
    var r = DATA[k], n = k + 1, f = r.fits[problem], el = document.getElementById('fit-' + n);
    if (!f || !f.methods[method]) {
      Plotly.purge(el);
      el.textContent = 'No drawing for ' + problem + ' / ' + method + ': its points or fit are not embedded ' +
        '(only the first problems of a ranking are, and only where the data source is available here).';
      return false;
    }
    var m = f.methods[method];
    Plotly.newPlot(el, [
      {x: f.x, y: f.y, mode: 'markers', name: 'points', marker: {size: 4, color: '#444'}, xaxis: 'x', yaxis: 'y'},
      {x: m.x, y: m.y, mode: 'lines', name: esc(method + ' (' + m.status + ')'), xaxis: 'x', yaxis: 'y'},
      {x: f.angle, y: m.residual, mode: 'markers', name: 'residual', marker: {size: 4}, xaxis: 'x2', yaxis: 'y2'}],
      {title: {text: esc(problem) + '<br>' + esc(method), font: {size: 11}}, showlegend: false,
       grid: {rows: 2, columns: 1, pattern: 'independent'},
       xaxis: {title: {text: 'x (units of the data)'}, scaleanchor: 'y'}, yaxis: {title: {text: 'y'}},
       xaxis2: {title: {text: 'angle about the centroid [°]'}},
       yaxis2: {title: {text: 'residual (units of the data)'}}, margin: {t: 50}}, cfg);
    el.setAttribute('data-problem', problem);
    el.setAttribute('data-method', method);
    return true;
  };
  function cellValue(td) {         // the number as shown (4.07×10⁻⁵), without a coloured cell's ratio line
    var t = (td.firstChild ? td.firstChild.textContent : '').trim().replace('×10', 'e').replace(/[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]/g, function (c) {
      return '-0123456789'['⁻⁰¹²³⁴⁵⁶⁷⁸⁹'.indexOf(c)];
    });
    var v = parseFloat(t);
    return isNaN(v) ? t.toLowerCase() : v;
  }
  document.querySelectorAll('.explorer-table table').forEach(function (table) {
    table.querySelectorAll('thead th').forEach(function (th, col) {
      th.addEventListener('click', function () {
        var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
        var asc = !th.classList.contains('sorted-asc');
        table.querySelectorAll('thead th').forEach(function (h) { h.classList.remove('sorted-asc', 'sorted-desc'); });
        th.classList.add(asc ? 'sorted-asc' : 'sorted-desc');
        rows.sort(function (a, b) {
          var x = cellValue(a.cells[col]), y = cellValue(b.cells[col]);
          if (typeof x !== typeof y) { return (typeof x === 'number' ? -1 : 1); }
          return (x < y ? -1 : x > y ? 1 : 0) * (asc ? 1 : -1);
        });
        rows.forEach(function (row) { body.appendChild(row); });
      });
    });
  });
  document.querySelectorAll('input.filter').forEach(function (box) {
    box.addEventListener('input', function () {
      var q = box.value.toLowerCase(), table = document.getElementById(box.getAttribute('data-table'));
      Array.prototype.forEach.call(table.tBodies[0].rows, function (row) {
        row.style.display = row.textContent.toLowerCase().indexOf(q) >= 0 ? '' : 'none';
      });
    });
  });
  document.body.setAttribute('data-explorer', 'ready');
})();
"""
