"""``explorer.html``: the interactive companion of the report, one static page that works offline (Plotly's
JavaScript is embedded; no server, no network), built by ``experiments.report`` from the same declarations.

- every ranking the studies declare (``[[rankings]]``): Dolan–Moré performance profiles and the metric against
  the runtime (one panel per unit when the pooled studies measure it in different units, mm and R; none when the
  metric is the runtime itself), one Plotly trace per method and panel (a checkbox per method, or a click on the
  legend, shows or hides it in every plot of the ranking), and the problems x methods map coloured by the ratio to the best method of the
  problem; a click on a cell draws that problem's points with the method's fitted circle or ellipse, and its
  residuals against the angle;
- every declared table of every study, sortable (click a header) and filterable (type in the box), coloured
  against the best method of the row where the study declares ``colour = "lower_is_better"``.

User text is text here too: the page is the jinja2 template ``templates/explorer.html.j2`` with autoescaping
(its script ``templates/explorer.js``); data travel as JSON inside
``<script type="application/json">`` (``tojson`` escapes ``<``, ``>``, ``&``), read by the page's own script.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
from markupsafe import Markup

MAX_PROBLEMS_WITH_FITS = 20   #: problems per ranking whose points and fits are embedded (the page stays small)
MAX_POINTS = 200              #: points per problem drawn (evenly subsampled)
TIME_COLUMN = "time_median_s"  #: the runtime a ranking's metric is plotted against


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
    from experiments.rows import load_data
    cfg = meta.get("config") if isinstance(meta.get("config"), dict) else None
    if not cfg:
        return None
    try:
        entry, point, rep = (int(x) for x in str(stream).split("."))
        spec = next(s for s in engine.expand_datasets(cfg, study) if s["label"] == dataset
                    and s["entry"] == entry and s["point"] == point)
        pts, _ = load_data(spec, int(cfg.get("seed", 0)), [entry, point, rep])
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
    from experiments.render.text import human_unit
    from experiments.units import readable
    problems = list(map(str, table.index))
    # every number carries its unit: each problem's (its study's: "mm" for published, "R" for noise), which the
    # hovers name and the runtime panels group by
    data = {"name": name, "metric": r.metric, "label": readable(r.metric), "unit": r.unit,
            "units": [human_unit(r.units.get(p.split(" | ")[0], r.unit)) for p in problems],
            "methods": methods, "problems": problems,
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
        if TIME_COLUMN in rows:
            keys = (study + " | " + rows["dataset"].astype(str) + " | " + rows["data_stream"].astype(str) + " | "
                    + rows["repetition"].astype(str))
            times.update({(k, lab): _r(t) for k, lab, t in zip(keys, rows["_label"], rows[TIME_COLUMN])})
    if r.metric == TIME_COLUMN:    # the cost is the runtime: against itself it would be a diagonal
        data["no_time"] = (f"This ranking's cost is the runtime ({readable(r.metric)}): the problems map and the "
                           "profile compare it; against itself it would be a diagonal.")
    elif times:
        data["time"] = [[times.get((p, m)) for m in methods] for p in data["problems"]]
        # the metric against the runtime: one panel per unit (costs in mm and in R never share an axis), of the
        # problems timed; the studies whose fits were not timed are named
        panels: dict = {}
        for i, (u, ts, cs) in enumerate(zip(data["units"], data["time"], data["cost"])):
            if any(t is not None and c is not None for t, c in zip(ts, cs)):
                panels.setdefault(u, []).append(i)
        data["panels"] = [{"unit": u, "problems": rows} for u, rows in panels.items()]
        timed = {i for rows in panels.values() for i in rows}
        data["untimed"] = sorted({p.split(" | ")[0] for i, p in enumerate(problems) if i not in timed})
        if not panels:
            data["time"] = None
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
                                                                    table_id=f"xtable-{k}",
                                                                    decimals=t.get("decimals"),
                                                                    exact=t.get("exact", ())))})
    return out


def write_explorer(out: Path, rankings: dict, tables: list[dict], folders: dict[str, Path], metas: dict[str, dict],
                   *, title: str = "fitbench: interactive explorer") -> Path:
    """Write ``out/explorer.html`` (see the module docstring). ``tables``: [{caption, data, unit, digits,
    colour, and the declared decimals and exact when given}] in report order."""
    from plotly.offline import get_plotlyjs
    data = [ranking_data(n, r, folders, metas) for n, r in rankings.items() if r.table is not None and len(r.table)]
    from experiments.render.page import TEMPLATES, html_template
    page = html_template("explorer.html.j2").render(
        title=title, plotly=Markup(get_plotlyjs()), data=data, tables=table_blocks(tables),
        script=Markup((TEMPLATES / "explorer.js").read_text(encoding="utf-8")))
    from methods.files import write_atomic
    path = out / "explorer.html"
    write_atomic(path, page)
    return path
