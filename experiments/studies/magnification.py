"""Study ``magnification``: continuity (largest magnified step / (eta x largest measured step)) and loops
(self-intersections) of the magnified trajectory, per example and algorithm, with side-by-side figures."""
from __future__ import annotations

from typing import Annotated, Any

import numpy as np
import pandas as pd
from pydantic import Field

import methods
from datasets.contouring import EXAMPLES
from methods.magnify import MagnifyInput
from experiments.outputs import save_csv
from experiments.rows import base_row
from experiments.study import Analysis, ConfigError, ConfigTable, Figure, Study, Table


def variant_params(variant: dict, eta: float) -> dict:
    """The method parameters of a [[variants]] entry for an example magnified by ``eta``."""
    params = dict(variant.get("params", {}))
    for k in variant.get("times_eta", []):
        params[k] = params[k] * eta
    return {"eta": eta, **params}


def _panels(cfg):
    """The declared [[trajectories]] as panels of :func:`trajectories_figure`."""
    variants = {v["label"]: v for v in cfg["variants"]}
    return [{"example": t["example"], "eta": cfg["examples"][t["example"]], "method": variants[lab]["method"],
             "params": {k: v for k, v in variant_params(variants[lab], cfg["examples"][t["example"]]).items()
                        if k != "eta"},
             "title": f"{t['example']}:\n{lab}", "box": tuple(t["box"]) if t.get("box") else None}
            for t in cfg.get("trajectories", []) for lab in t["variants"]]


class Variant(ConfigTable):
    """An algorithm variant compared: a label (the rows' method column), a magnify method and its parameters;
    ``times_eta`` names parameters multiplied by the example's eta (e.g. delta_emax = 1.2 -> 1.2 eta e_max)."""
    label: Annotated[str, Field(min_length=1)]
    method: Annotated[str, Field(min_length=1)]
    params: dict[str, Any] = None
    times_eta: list[str] = None


class Trajectory(ConfigTable):
    """Trajectories drawn side by side: an example, the variants (labels) and a zoom box [x0, x1, y0, y1] in mm."""
    example: str
    variants: Annotated[list[str], Field(min_length=1)]
    box: Annotated[list[float], Field(min_length=4, max_length=4)] = None


class MagnificationConfig(ConfigTable):
    """The keys of the magnification study."""
    examples: Annotated[dict[str, Any], Field(min_length=1)]  # example name -> eta
    variants: Annotated[list[Variant], Field(min_length=1)]
    trajectories: list[Trajectory] = None


class MagnificationStudy(Study):
    """The ``magnification`` study (see the module's docstring)."""

    values = None  # its analysis names its values

    #: this study's own config keys (typed; the schema is generated from the model)
    config_schema = MagnificationConfig

    def validate(self, cfg, where):
        bad = set(cfg["examples"]) - set(EXAMPLES)  # types and presence: the schema (MagnificationConfig)
        if bad:
            raise ConfigError(f"{where}: examples must name some of {', '.join(EXAMPLES)} (got {sorted(bad)})")
        labels = [v["label"] for v in cfg["variants"]]
        if len(set(labels)) != len(labels):
            raise ConfigError(f"{where}: variant labels must be unique, got {labels}")
        for j, v in enumerate(cfg["variants"]):
            try:
                spec = methods.get(v["method"])
            except methods.UnknownMethodError as exc:
                raise ConfigError(f"{where} variants[{j}]: {exc}") from None
            unknown = (set(v.get("params", {})) | set(v.get("times_eta", []))) - set(spec.defaults) | (
                set(v.get("times_eta", [])) - set(v.get("params", {})))
            if unknown or "eta" in v.get("params", {}):
                raise ConfigError(f"{where} variants[{j}]: {spec.id} parameter(s) {', '.join(sorted(unknown)) or 'eta'} "
                                  f"cannot be set here (eta comes from [examples]; times_eta names given params); its "
                                  f"parameters are: {', '.join(k for k in spec.defaults if k != 'eta')}")
        for j, t in enumerate(cfg.get("trajectories", [])):
            if t["example"] not in cfg["examples"] or set(t["variants"]) - set(labels):
                raise ConfigError(f"{where} trajectories[{j}]: example must be one of [examples] and variants among the "
                                  f"[[variants]] labels; got {t['example']!r}, {t['variants']}")

    def tasks(self, cfg):
        out = []
        for i, (name, eta) in enumerate(cfg["examples"].items()):
            for v in cfg["variants"]:
                out.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": {"entry": i, "point": 0, "label": name},
                            "repetition": 0, "stream": [i, 0, 0], "seed": cfg["seed"], "method": v["label"],
                            "params": {}, "timing": None, "x_eta": float(eta), "x_variant": v})
        return out

    def execute(self, task):
        """One row per (example, variant), built on the engine's identity columns (base_row)."""
        name, eta, variant = task["dataset"]["label"], task["x_eta"], task["x_variant"]
        row = {**base_row(task), "param_eta": eta}
        try:
            ref, meas = EXAMPLES[name]()
            res = methods.fit(variant["method"], MagnifyInput(ref, meas), **variant_params(variant, eta))
        except methods.InvalidInputError as exc:
            return {**row, "status": "skipped", "message": str(exc)}
        return {**row, "delta_mm": res.extra.get("delta"), "status": "ok" if res.converged else "not converged",
                "message": res.message, "max_error_um": res.extra["max_contouring_error"] * 1e3,
                "continuity": res.extra["continuity"], "loops": res.extra["self_intersections"],
                "nearest_point_used": res.extra.get("nearest_point_used", 0)}

    def analyse(self, df, cfg, target, log):
        """Continuity / loops table from the rows, the redrawn continuity chart and trajectories; findings:
        which algorithm variants stay continuous and loop-free on every example they apply to."""
        table = df.pivot_table(index="dataset", columns="method", values=["continuity", "loops"], sort=False)
        save_csv(table, target / "metrics.csv", float_format="%.4g")
        cells = df.assign(cell=[("skipped" if st != "ok" else f"{c:.2f} / {int(lo)}")
                                for st, c, lo in zip(df["status"], df["continuity"], df["loops"])])
        piv = cells.pivot_table(index="dataset", columns="method", values="cell", aggfunc="first", sort=False)
        labels = [v["label"] for v in cfg["variants"]]
        piv = piv[[v for v in labels if v in piv.columns]].rename_axis("example").reset_index()
        log(piv.to_string(index=False))
        continuity_figure(df, target / "magnification_continuity.png")
        panels = _panels(cfg)
        if panels:
            trajectories_figure(panels, target / "magnification.png")
        ok = df[df["status"] == "ok"]
        clean = {}
        for label, g in ok.groupby("method", sort=False):
            clean[label] = int(((g["continuity"] <= 1.0 + 1e-9) & (g["loops"] == 0)).sum())
        applied = ok.groupby("method", sort=False).size()
        values = {"continuous_loop_free": clean, "applicable": applied.to_dict(),
                  "skipped": df[df["status"] != "ok"].groupby("method").size().to_dict()}
        findings = ("Examples where the magnified trajectory is continuous (continuity ≤ 1) and has no loops, out of "
                    "those the algorithm applies to: " + "; ".join(f"{lab}: {clean[lab]} of {applied[lab]}"
                                                                  for lab in labels if lab in clean) + ".")
        caption = (f"Continuity (largest magnified step / (eta x largest measured step); about 1 or less: continuous) and "
                   f"loops (self-intersections) of the magnified trajectory, as 'continuity / loops', for "
                   f"{len(cfg['examples'])} contouring examples (eta 50 to 1000, dimensionless); 'skipped': the algorithm "
                   "does not apply")
        figs = [Figure(caption="Continuity (left, log scale) and loops (right) of the magnified trajectory per contouring "
                               "example and algorithm variant; a variant that does not apply to an example (skipped) "
                               "has no value and no marker: its row says 'skipped'", file="magnification_continuity.png")]
        if panels:
            figs.append(Figure(caption="Magnified trajectories (positions in mm, errors magnified by η) by the conventional "
                                       "nearest-point rule and by offset-algorithm variants", file="magnification.png"))
        return Analysis(tables=[Table(caption=caption, data=piv)], figures=figs, values=values, findings=findings)


# ---------------------------------------------------------------- figures (drawn in experiments.render.style)
def continuity_figure(results: pd.DataFrame, path, *, threshold: float = 1.0):
    """Continuity (largest magnified step / (η × largest measured step); about 1 or less: continuous, left
    panel) and loops of the magnified trajectory (right panel) per example and algorithm as dot charts;
    a run the algorithm does not apply to has no marker: the word 'skipped' at the left edge of its row.
    ``results``: results/magnification/results.csv (dataset, method, status, continuity, loops)."""
    from experiments.render import style
    plt = style.plotting()
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
            # a variant that does not apply to an example has no value: no marker on either axis (at 1 it would read
            # as continuity 1), a word at the panel's left edge in the variant's colour
            for yk in yy[~ok]:
                ax.text(0.01, yk, "skipped", transform=ax.get_yaxis_transform(), ha="left", va="center",
                        color=kw["color"], fontsize=style.MIN_FONT_PT, fontstyle="italic")
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


def trajectories_figure(panels: list[dict], path):
    """Magnified trajectories side by side. Each panel: {'example': name in datasets.contouring.EXAMPLES,
    'eta': magnification, 'method': a magnify method id, 'params': its other parameters, 'title': str,
    'box': (x0, x1, y0, y1) in mm or None}. Axes in mm, reference and magnified path in the legend."""
    from experiments.render import style
    import methods
    from datasets.contouring import EXAMPLES
    from methods.magnify import MagnifyInput
    plt = style.plotting()
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
