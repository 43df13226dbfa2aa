"""The report's figures redrawn in one style (``experiments.render.style``) from the tables the studies write
(``results/<study>/*.csv``). Each function takes a DataFrame (plus options) and a PNG path, returns the path,
and knows no study by name beyond the columns it reads; a framework figure registry can register them as
they are. Fonts are >= 8 pt at the printed size (the figures are drawn at the column width of A4 with
2.5 cm margins), legends sit outside the data, lengths are in µm or mm and angles in °, no data is shifted.
"""
from __future__ import annotations

import json
import textwrap

import numpy as np
import pandas as pd

from experiments.render import style

#: least-squares circle estimators (the KCR bound applies to them); the others estimate other circles
_ALGEBRAIC_KINDS = ("closed form",)


def _kind(method_id: str) -> str | None:
    try:
        import methods
        return methods.get(method_id).kind
    except Exception:
        return None


def _params_label(p) -> str:
    if p is None or (isinstance(p, float) and np.isnan(p)) or p in ("{}", ""):
        return ""
    return " " + ",".join(f"{k}={v}" for k, v in json.loads(p).items())


def noise_kcr(kcr: pd.DataFrame, path, *, methods: list[str] | None = None, n: int | None = None):
    """Radius RMSE / KCR bound (top) and radius bias / σ (bottom) against σ / R, one column per arc.

    ``kcr``: results/noise/kcr.csv (arc_deg, noise, n, method, params, radius_rmse_over_kcr,
    radius_bias_over_sigma). ``methods``: which to draw (default: every method whose registry kind is not
    'convex program': the least-squares estimators the KCR bound is about; the zone fits estimate other
    circles and stay in the table)."""
    import matplotlib.pyplot as plt
    n = int(kcr["n"].max()) if n is None else n
    t = kcr[(kcr["n"] == n) & (kcr["params"].fillna("{}") == "{}")].copy()
    if methods is None:
        methods = sorted(m for m in t["method"].unique() if _kind(m) != "convex program")
    t = t[t["method"].isin(methods)]
    arcs = sorted(t["arc_deg"].unique(), reverse=True)
    with style.figure_style():
        fig, axes = plt.subplots(2, len(arcs), figsize=style.size(1.0, 0.62), sharex=True, sharey="row",
                                 squeeze=False)
        for j, arc in enumerate(arcs):
            for m, g in t[t["arc_deg"] == arc].groupby("method"):
                g = g.sort_values("noise")
                kw = style.method_style(m)
                if _kind(m) in _ALGEBRAIC_KINDS:
                    kw["linestyle"] = "--"
                axes[0, j].plot(g["noise"], g["radius_rmse_over_kcr"], **kw)
                axes[1, j].plot(g["noise"], g["radius_bias_over_sigma"], **kw)
            axes[0, j].axhline(1.0, color="0.2", lw=0.8)
            axes[1, j].axhline(0.0, color="0.2", lw=0.8)
            axes[0, j].set_title(f"{arc:.0f}° arc")
            axes[1, j].set_xlabel("σ / R")
            for i in (0, 1):
                axes[i, j].set_xscale("log")
            axes[0, j].set_yscale("log")
        axes[0, 0].set_ylabel("radius RMSE /\nKCR bound")
        axes[1, 0].set_ylabel("radius bias / σ")
        for ax in axes.ravel():
            style.plain_log_ticks(ax)
        style.legend_outside(fig, axes=[axes[0, 0]], title=f"N = {n} points; dashed: closed-form (algebraic) fits")
        return style.save(fig, path)


def positioning_coverage(coverage: pd.DataFrame, path, *, nominal: float = 0.95):
    """Coverage of the true deviation curve by each band, per scenario: horizontal grouped bars (scenario
    names readable on the y axis), the nominal coverage as a line, the legend below the axes.
    ``coverage``: results/positioning/coverage.csv (dataset, method, coverage)."""
    import matplotlib.pyplot as plt
    scen = list(dict.fromkeys(coverage["dataset"]))
    bands = list(dict.fromkeys(coverage["method"]))
    with style.figure_style():
        fig, ax = plt.subplots(figsize=style.size(1.0, 0.12 * len(scen) * len(bands) / 3 + 0.25))
        h = 0.8 / len(bands)
        y = np.arange(len(scen))[::-1]
        colours = style.category_styles(bands)
        for b, band in enumerate(bands):
            vals = [coverage[(coverage["dataset"] == s) & (coverage["method"] == band)]["coverage"].mean() for s in scen]
            kw = colours[band]
            bars = ax.barh(y + (len(bands) / 2 - b - 0.5) * h, vals, h, color=kw["color"], label=band.replace("+-", "±"))
            ax.bar_label(bars, labels=[f"{100 * v:.0f} %" for v in vals], padding=2, fontsize=8)
        ax.axvline(nominal, color="0.2", lw=0.9, ls="--", label=f"nominal {100 * nominal:.0f} %")
        ax.set_yticks(y, ["\n".join(textwrap.wrap(s.replace(" um", " µm"), 32)) for s in scen])
        ax.set_xlim(0, 1.12)
        ax.set_xticks(np.linspace(0, 1, 6), [f"{100 * v:.0f} %" for v in np.linspace(0, 1, 6)])
        ax.set_xlabel("share of positions where the band covers the true deviation curve")
        ax.grid(axis="y", visible=False)
        style.legend_outside(fig, ncol=2)
        return style.save(fig, path)


def convergence_success(success: pd.DataFrame, path):
    """Success rate against start distance [radii], one panel per arc. Coinciding curves are not shifted:
    each method has its own marker size and line style, so curves that overlap stay visible and every point
    is drawn at its true value (0..1). ``success``: results/convergence/success.csv."""
    import matplotlib.pyplot as plt
    arcs = list(success["arc_deg"].unique())
    with style.figure_style():
        fig, axes = plt.subplots(1, len(arcs), figsize=style.size(1.0, 0.42), sharey=True, squeeze=False)
        groups = list(success.groupby(["method", "params"], sort=True).groups)
        for j, arc in enumerate(arcs):
            ax = axes[0, j]
            for k, (m, p) in enumerate(groups):
                g = success[(success["arc_deg"] == arc) & (success["method"] == m) & (success["params"] == p)]
                g = g.sort_values("start_distance")
                kw = style.method_style(m + _params_label(p))
                ax.plot(g["start_distance"], g["success_rate"], color=kw["color"], marker=kw["marker"],
                        linestyle=style.LINESTYLES[k % len(style.LINESTYLES)], ms=3.5 + 1.4 * (len(groups) - 1 - k),
                        mfc="none", mew=1.1, label=style.short_label(m) + _params_label(p))
            ax.set_xscale("log")
            style.plain_log_ticks(ax, "x")
            ax.set_ylim(-0.03, 1.03)
            ax.set_yticks(np.linspace(0, 1, 6), [f"{100 * v:.0f} %" for v in np.linspace(0, 1, 6)])
            ax.set_title(f"{arc:.0f}° arc")
            ax.set_xlabel("start distance from the true centre [radii]")
        axes[0, 0].set_ylabel("runs reaching the optimum")
        style.legend_outside(fig, axes=[axes[0, 0]], ncol=3)
        return style.save(fig, path)


def magnification_continuity(results: pd.DataFrame, path, *, threshold: float = 1.0):
    """Continuity (largest magnified step / (η × largest measured step); about 1 or less: continuous, left
    panel) and loops of the magnified trajectory (right panel) per example and algorithm as dot charts;
    a run the algorithm does not apply to is marked 'skipped'.
    ``results``: results/magnification/results.csv (dataset, method, status, continuity, loops)."""
    import matplotlib.pyplot as plt
    examples = list(dict.fromkeys(results["dataset"]))
    algos = list(dict.fromkeys(results["method"]))
    colours = style.category_styles(algos)
    with style.figure_style():
        fig, (ax, axl) = plt.subplots(1, 2, figsize=style.size(1.0, 0.62), sharey=True,
                                      gridspec_kw={"width_ratios": (3, 2)})
        y = np.arange(len(examples))[::-1]
        dy = 0.8 / len(algos)
        for a, algo in enumerate(algos):
            kw = colours[algo]
            label = algo.replace("delta", "δ").replace(" eta ", " η ")
            rows = results[results["method"] == algo].set_index("dataset")
            yy = y + (len(algos) / 2 - a - 0.5) * dy
            ok = np.array([ex in rows.index and rows.at[ex, "status"] == "ok" for ex in examples])
            cont = np.array([rows.at[ex, "continuity"] if o else np.nan for ex, o in zip(examples, ok)], float)
            loops = np.array([rows.at[ex, "loops"] if o else np.nan for ex, o in zip(examples, ok)], float)
            ax.plot(cont, yy, kw["marker"], color=kw["color"], ms=5, ls="none", label=label)
            axl.plot(loops, yy, kw["marker"], color=kw["color"], ms=5, ls="none")
            if (~ok).any():
                for axis in (ax, axl):
                    axis.plot(np.full((~ok).sum(), np.nan), yy[~ok], "x")   # keeps the limits
                ax.plot(np.full((~ok).sum(), threshold), yy[~ok], "x", color=kw["color"], ms=5, mew=1.2,
                        label="_skipped")
        ax.plot([], [], "x", color="0.3", label="skipped (not applicable)")
        ax.axvline(threshold, color="0.2", lw=0.9, ls="--", label="continuous (≤ 1)")
        ax.set_xscale("log")
        style.plain_log_ticks(ax, "x")
        axl.set_xscale("symlog", linthresh=1.0)
        axl.set_xticks([0, 1, 3, 10, 30], ["0", "1", "3", "10", "30"])
        axl.set_xlim(-0.3, 1.6 * max(1.0, float(np.nanmax(pd.to_numeric(results["loops"], errors="coerce")))))
        ax.set_yticks(y, [e.replace("_", " ") for e in examples])
        for axis in (ax, axl):
            axis.grid(axis="y", visible=False)
        ax.set_xlabel("continuity = largest magnified step /\n(η × largest measured step)")
        axl.set_xlabel("loops (self-intersections)")
        style.legend_outside(fig, axes=[ax], ncol=2)
        return style.save(fig, path)


def magnification_trajectories(panels: list[dict], path):
    """Magnified trajectories side by side. Each panel: {'example': name in datasets.contouring.EXAMPLES,
    'eta': magnification, 'method': a magnify method id, 'params': its other parameters, 'title': str,
    'box': (x0, x1, y0, y1) in mm or None}. Axes in mm, reference and magnified path in the legend."""
    import matplotlib.pyplot as plt
    import methods
    from datasets.contouring import EXAMPLES
    from methods.magnify import MagnifyInput
    ncol = min(3, len(panels))
    nrow = int(np.ceil(len(panels) / ncol))
    with style.figure_style():
        fig, axes = plt.subplots(nrow, ncol, figsize=style.size(1.0, 0.36 * nrow), squeeze=False)
        for ax, pnl in zip(axes.ravel(), panels):
            ref, meas = EXAMPLES[pnl["example"]]()
            data = MagnifyInput(ref, meas)
            eta = float(pnl["eta"])
            res = methods.fit(pnl["method"], data, eta=eta, **pnl.get("params", {}))
            ax.plot(*data.reference.T, color="0.55", lw=1.0, label="reference path")
            ax.plot(*res.points.T, color=style.PALETTE[0], lw=0.9, label="magnified path (error × η)")
            if pnl.get("box"):
                x0, x1, y0, y1 = pnl["box"]
                ax.set_xlim(x0, x1)
                ax.set_ylim(y0, y1)
            # equal scales in x and y: a zoom box is shown exactly (the axes box takes the box's shape);
            # without one, matplotlib widens the free data limits to fill the panel
            ax.set_aspect("equal", adjustable="box" if pnl.get("box") else "datalim")
            ax.set_title(f"{pnl.get('title', pnl['method'])}\nη = {eta:g}: continuity {res.extra['continuity']:.2f}, "
                         f"loops {res.extra['self_intersections']}", fontsize=8)
            ax.set_xlabel("x [mm]")
            ax.set_ylabel("y [mm]")
        for ax in axes.ravel()[len(panels):]:
            ax.set_visible(False)
        style.legend_outside(fig, axes=[axes[0, 0]])
        return style.save(fig, path)


def multilateration_conditioning(accuracy: pd.DataFrame, path, *, scenario: str | None = None,
                                 stations: str = "located"):
    """Condition numbers of both steps per scheme (categorical x: dots, no joining line) and the volumetric
    error RMS after alignment in a panel of its own. ``accuracy``: results/multilateration/accuracy.csv."""
    import matplotlib.pyplot as plt
    sub = accuracy[accuracy["stations"] == stations]
    scenario = scenario or sub["dataset"].iloc[0]
    g = sub[sub["dataset"] == scenario].reset_index(drop=True)
    xs = np.arange(len(g))
    names = [m.replace("_", " ") for m in g["method"]]
    with style.figure_style():
        fig, axes = plt.subplots(1, 3, figsize=style.size(1.0, 0.45))
        for ax, step, title in ((axes[0], "stations", "step 1: stations"), (axes[1], "points", "step 2: points")):
            if f"kappa_{step}" not in g or g[f"kappa_{step}"].isna().all():
                ax.set_visible(False)
                continue
            ax.plot(xs, g[f"kappa_{step}"], "o", color=style.PALETTE[0], label="κ₂ (SVD), median")
            ax.plot(xs, g[f"kappa_{step}_theorem1"], "v", color=style.PALETTE[1], label="Theorem 1 lower estimate")
            ax.axhline(100, color="0.2", ls="--", lw=0.8, label="100: the paper's 'satisfactory'")
            ax.set_yscale("log")
            style.plain_log_ticks(ax, "y")
            ax.set_title(title)
            ax.set_ylabel("condition number")
        axes[2].plot(xs, g["aligned_error_rms_um"], "s", color=style.PALETTE[2], label="volumetric error RMS")
        axes[2].set_ylabel("volumetric error RMS\nafter alignment [µm]")
        axes[2].set_ylim(0, None)
        axes[2].set_title("accuracy")
        for ax in axes:
            ax.set_xticks(xs, names, rotation=35, ha="right")
            ax.set_xlim(-0.5, len(xs) - 0.5)
            ax.grid(axis="x", visible=False)
        style.legend_outside(fig, ncol=2, title="; ".join(textwrap.wrap(scenario, 90)) + f" (stations {stations})")
        return style.save(fig, path)


def published_circularity(rows: pd.DataFrame, path):
    """Published against reproduced circularity per data set and column of the roundness paper's table 1,
    with the 99 % range that the printed digits allow. ``rows``: the published study's comparison rows
    (dataset, variant, column, published, reproduced_value, rounding_p0_5, rounding_median, rounding_p99_5),
    values in mm; drawn in µm relative to the published value so that every panel shares one axis."""
    import matplotlib.pyplot as plt
    r = rows.reset_index(drop=True)
    labels = [f"{d.replace('roundness_', '')}{'*' if v != 'as published' else ''}\n{c.split(' ')[0]}"
              for d, v, c in zip(r["dataset"], r["variant"], r["column"])]
    x = np.arange(len(r))
    to_um = lambda col: (r[col] - r["published"]) * 1e3     # noqa: E731
    with style.figure_style():
        fig, ax = plt.subplots(figsize=style.size(1.0, 0.45))
        lo, med, hi = to_um("rounding_p0_5"), to_um("rounding_median"), to_um("rounding_p99_5")
        ax.errorbar(x, med, yerr=[med - lo, hi - med], fmt="none", ecolor="0.55", elinewidth=2.5, capsize=4,
                    label="99 % range allowed by the printed digits")
        ax.plot(x, to_um("reproduced_value"), "o", color=style.PALETTE[0], label="reproduced from the printed data")
        ax.axhline(0.0, color=style.PALETTE[1], lw=1.0, label="published value")
        ax.set_xticks(x, labels)
        ax.set_xlim(-0.6, len(x) - 0.4)
        ax.set_ylabel("circularity − published [µm]")
        ax.grid(axis="x", visible=False)
        ax.set_yscale("symlog", linthresh=1.0)
        top = float(np.nanmax(np.abs(np.concatenate([lo, hi]))))
        ticks = [t for t in (1, 3, 10, 30, 100, 300, 1000) if t <= top * 1.2]
        ax.set_yticks([-t for t in ticks[::-1]] + [0] + ticks)
        style.plain_log_ticks(ax, "y")
        style.legend_outside(fig, ncol=2, title="*: repeated closing point dropped")
        return style.save(fig, path)
