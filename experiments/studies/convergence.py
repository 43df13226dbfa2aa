"""Study ``convergence``: iterative circle methods started far from the optimum.

Each start is the true centre moved by d radii in one of k directions, with the true radius. The
known optimum of each method's objective comes from a good start: the geometric least-squares circle
(Levenberg–Marquardt from Kåsa's circle) for S_CG, Kåsa's closed form for S_CA (Powell hybrid).
A run succeeds when it reports convergence and lands within 1e-6 R of that optimum.
"""
from __future__ import annotations

import json
from typing import Annotated

import numpy as np
import pandas as pd
from pydantic import Field

import methods
from experiments.render.text import counts_by_group, joined
from experiments.outputs import save_csv
from experiments.rows import base_row, fit_row, load_data
from experiments.study import Analysis, ConfigError, ConfigTable, Figure, Study, Table


def reference_method(cfg_or_task: dict, method_id: str) -> str:
    """The method that gives the known optimum of ``method_id``'s objective (TOML ``reference_optimum``:
    a table method id -> reference id, with a ``default``)."""
    refs = cfg_or_task["x_reference_optimum"] if "x_reference_optimum" in cfg_or_task else cfg_or_task["reference_optimum"]
    return refs.get(method_id, refs["default"])


def _objective_at(task, points, circle) -> float | None:
    """The method's own objective at ``circle``: the first entry of its history when started there."""
    res = methods.fit(task["method"], points, **{**task["params"], "start": [float(v) for v in circle]})
    return float(res.history[0]) if res.history else None


def success_table(df):
    """Success rate and median iterations/evaluations of the successful runs per arc, method and start distance."""
    rows = []
    for (arc, m, p, dist), g in df.groupby(["data_arc_deg", "method", "params", "start_distance"], sort=False):
        ok = g[g["success"] == True]  # noqa: E712
        rows.append({"arc_deg": arc, "method": m, "params": p, "start_distance": dist, "runs": len(g),
                     "success_rate": len(ok) / len(g),
                     "iterations_median": float(ok["iterations"].median()) if len(ok) and ok["iterations"].notna().any() else np.nan,
                     "nfev_median": float(ok["nfev"].median()) if len(ok) else np.nan})
    return pd.DataFrame(rows)


def _label(m, p):
    return m + ("" if p == "{}" else " " + p.replace('"', "").replace("{", "").replace("}", ""))


class ConvergenceConfig(ConfigTable):
    """The keys of the convergence study (values checked by ``validate``)."""
    start_distances: Annotated[list[Annotated[float, Field(ge=0)]], Field(min_length=1)]  # radii
    # method id -> the method giving the known optimum of its objective, with a 'default' entry
    reference_optimum: Annotated[dict[str, str], Field(json_schema_extra={"required": ["default"]})]
    start_directions: Annotated[int, Field(ge=1)]


class ConvergenceStudy(Study):
    """The ``convergence`` study (see the module's docstring)."""

    values = None  # its analysis names its values

    #: this study's own config keys (typed; the schema is generated from the model)
    config_schema = ConvergenceConfig

    def validate(self, cfg, where):
        for r in cfg["reference_optimum"].values():  # types and presence: the schema (ConvergenceConfig)
            try:
                methods.get(r)
            except methods.UnknownMethodError as exc:
                raise ConfigError(f"{where}: reference_optimum: {exc}") from None
        for m, _ in cfg.expand_methods():
            if "start" not in methods.get(m).defaults:
                raise ConfigError(f"{where}: {m} has no 'start' parameter, so it cannot be started far away")

    def count_rows(self, cfg):
        """The rows of the study from its grid sizes (nothing expanded): each run of the grid x distances x
        directions."""
        return super().count_rows(cfg.replace(repetitions=1)) * len(cfg["start_distances"]) * cfg["start_directions"]

    def tasks(self, cfg):
        """The tasks, lazily (a generator: the engine counts and expands them a block at a time)."""
        for t in cfg.replace(repetitions=1).grid_tasks():
            for d in cfg["start_distances"]:
                for k in range(cfg["start_directions"]):
                    yield {**t, "x_start_distance": float(d), "x_start_direction": k,
                           "x_directions": cfg["start_directions"], "x_reference_optimum": cfg["reference_optimum"]}

    def execute(self, task):
        """Fit from the distant start; compare with the known optimum (the reference method of the TOML). The
        objective values are the method's own: the first ``history`` entry of a restart at each circle."""
        points, truth = load_data(task["dataset"], task["seed"], task["stream"])
        R = truth["radius"]
        phi = 2 * np.pi * task["x_start_direction"] / task["x_directions"]
        start = (truth["center"][0] + task["x_start_distance"] * R * np.cos(phi),
                 truth["center"][1] + task["x_start_distance"] * R * np.sin(phi), R)
        fit_task = {**task, "params": {**task["params"], "start": list(start)}}
        row = fit_row(fit_task, points, truth)
        row["params"] = base_row(task)["params"]  # the method's own parameters; the start has its columns
        row.pop("param_start", None)
        row["start_x"], row["start_y"], row["start_radius"] = start
        row["start_distance"] = task["x_start_distance"]
        row["start_direction_deg"] = float(np.degrees(phi))
        ref = methods.fit(reference_method(task, task["method"]), points)
        if row.get("status") in ("ok", "not converged") and "center_x" in row:
            dist = max(np.hypot(row["center_x"] - ref.center[0], row["center_y"] - ref.center[1]),
                       abs(row["radius"] - ref.radius))
            row["distance_to_optimum"] = float(dist)
            row["success"] = bool(row["status"] == "ok" and dist <= 1e-6 * R)
            f = _objective_at(task, points, (row["center_x"], row["center_y"], row["radius"]))
            f_opt = _objective_at(task, points, (*ref.center, ref.radius))
            if f is not None and f_opt is not None:
                row["objective_excess"] = f - f_opt
        else:
            row["success"] = False
        return row

    def analyse(self, df, cfg, target, log):
        """Success tables per arc (success.csv), the redrawn success figure, and which methods always converge."""
        table = success_table(df)
        save_csv(table, target / "success.csv", index=False, float_format="%.4g")
        success_figure(table, target / "convergence.png")
        tables = []
        n_dirs = cfg["start_directions"]
        data = cfg["datasets"][0].get("params", {})
        for arc, ta in table.groupby("arc_deg", sort=False):
            piv = ta.pivot_table(index=["method", "params"], columns="start_distance", values="success_rate", sort=False)
            log(f"  {arc:.0f}° arc " + " " * 28 + "".join(f"{c:>7g}" for c in piv.columns))
            for (m, p), vals in piv.iterrows():
                log(f"    {_label(m, p):<40}" + "".join(f"{v:7.2f}" for v in vals))
            shown = piv * 100
            shown.columns = [f"{c:g} R" for c in piv.columns]
            shown.index = [_label(m, p) for m, p in piv.index]
            shown = shown.rename_axis("method").reset_index()
            tables.append(Table(caption=f"Share of runs reaching the optimum of the method's own objective (within 1e-6 R) "
                                        f"from starts d radii from the true centre, {n_dirs} directions each; synthetic "
                                        f"circle, {arc:.0f}° arc, N = {data.get('n')}, sigma = {data.get('noise')} R",
                                data=shown, unit="%"))
        lab = table.assign(label=[_label(m, p) for m, p in zip(table["method"], table["params"])])
        worst = lab.groupby("label", sort=False)["success_rate"].min()
        always = [m for m, v in worst.items() if v == 1.0]
        far = table["start_distance"].max()
        values = {"always_converged": always, "largest_start_distance": float(far),
                  "lowest_success_rate": {m: float(v) for m, v in worst.items()}}
        by_arc = {f"{a:g}°": [m for m, v in g.groupby("label", sort=False)["success_rate"].min().items() if v == 1.0]
                  for a, g in lab.groupby("arc_deg", sort=False)}
        values["always_converged_by_arc"] = by_arc
        findings = (f"Method variants reaching their optimum from every start up to {far:g} radii: "
                    f"{counts_by_group(by_arc, len(worst), 'arc')}.")
        others = worst[[m for m in worst.index if m not in always]]
        if len(others):
            low = others.min()
            lowest = [m for m, v in others.items() if v == low]
            where = lab[lab["label"].isin(lowest) & (lab["success_rate"] == low)]
            findings += (f" Lowest success rate: {100 * low:.0f} % ({joined(lowest)}, on the "
                         f"{joined(f'{a:g}°' for a in dict.fromkeys(where['arc_deg']))} "
                         f"arc{'s' if where['arc_deg'].nunique() > 1 else ''}).")
        fig = Figure(caption="Share of runs from distant starts that reach the optimum of the method's own objective, "
                             "against the start distance [radii], synthetic circles (full circle and arc); iterative "
                             "methods only", file="convergence.png")
        return Analysis(tables=tables, figures=[fig], values=values, findings=findings)


# ---------------------------------------------------------------- figures (drawn in experiments.render.style)
def _params_label(p) -> str:
    if p is None or (isinstance(p, float) and np.isnan(p)) or p in ("{}", ""):
        return ""
    return " " + ",".join(f"{k}={v}" for k, v in json.loads(p).items())


def success_figure(success: pd.DataFrame, path):
    """Success rate against start distance [radii], one panel per arc. Coinciding curves are not shifted:
    each method has its own marker size and line style, so curves that overlap stay visible and every point
    is drawn at its true value (0..1). ``success``: results/convergence/success.csv."""
    from experiments.render import style
    plt = style.plotting()
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
