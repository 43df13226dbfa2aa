"""Study ``convergence``: iterative circle methods started far from the optimum.

Each start is the true centre moved by d radii in one of k directions, with the true radius. The
known optimum of each method's objective comes from a good start: the geometric least-squares circle
(Levenberg–Marquardt from Kåsa's circle) for S_CG, Kåsa's closed form for S_CA (Powell hybrid).
A run succeeds when it reports convergence and lands within 1e-6 R of that optimum.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

import methods
from experiments import engine
from experiments.engine import ConfigError
from experiments.study import save_csv, save_figure


def validate(cfg, where):
    d = cfg.get("start_distances")
    if not isinstance(d, list) or not d or not all(isinstance(v, (int, float)) and v >= 0 for v in d):
        raise ConfigError(f"{where}: start_distances must be a list of non-negative numbers, got {d!r}")
    k = cfg.get("start_directions")
    if not isinstance(k, int) or k < 1:
        raise ConfigError(f"{where}: start_directions must be a positive integer, got {k!r}")
    for m, _ in engine.expand_methods(cfg, where):
        if "start" not in methods.get(m).defaults:
            raise ConfigError(f"{where}: {m} has no 'start' parameter, so it cannot be started far away")


def tasks(cfg):
    base = engine.grid_tasks({**cfg, "repetitions": 1}, cfg["_where"])
    out = []
    for t in base:
        for d in cfg["start_distances"]:
            for k in range(cfg["start_directions"]):
                out.append({**t, "x_start_distance": float(d), "x_start_direction": k,
                            "x_directions": cfg["start_directions"]})
    return out


def _objective(method_id, points, c, r):
    d = np.hypot(points[:, 0] - c[0], points[:, 1] - c[1])
    if method_id == "circle.powell_hybrid":
        e = d * d - r * r
        return float(e @ e)
    e = d - r
    return float(e @ e)


def execute(task):
    points, truth = engine.load_data(task["dataset"], task["seed"], task["stream"])
    R = truth["radius"]
    phi = 2 * np.pi * task["x_start_direction"] / task["x_directions"]
    start = (truth["center"][0] + task["x_start_distance"] * R * np.cos(phi),
             truth["center"][1] + task["x_start_distance"] * R * np.sin(phi), R)
    fit_task = {**task, "params": {**task["params"], "start": list(start)}}
    row = engine.fit_row(fit_task, points, truth)
    row["params"] = engine.base_row(task)["params"]  # the method's own parameters; the start has its columns
    row.pop("param_start", None)
    row["start_x"], row["start_y"], row["start_radius"] = start
    row["start_distance"] = task["x_start_distance"]
    row["start_direction_deg"] = float(np.degrees(phi))
    ref_id = "circle.kasa" if task["method"] == "circle.powell_hybrid" else "circle.levenberg_marquardt"
    ref = methods.fit(ref_id, points)
    if row.get("status") in ("ok", "not converged") and "center_x" in row:
        dist = max(np.hypot(row["center_x"] - ref.center[0], row["center_y"] - ref.center[1]),
                   abs(row["radius"] - ref.radius))
        row["distance_to_optimum"] = float(dist)
        row["success"] = bool(row["status"] == "ok" and dist <= 1e-6 * R)
        f = _objective(task["method"], points, (row["center_x"], row["center_y"]), row["radius"])
        f_opt = _objective(task["method"], points, ref.center, ref.radius)
        row["objective_excess"] = f - f_opt
    else:
        row["success"] = False
    return row


def finalize(df, cfg, target, log):
    rows = []
    for (arc, m, p, dist), g in df.groupby(["data_arc_deg", "method", "params", "start_distance"], sort=False):
        ok = g[g["success"] == True]  # noqa: E712
        rows.append({"arc_deg": arc, "method": m, "params": p, "start_distance": dist, "runs": len(g),
                     "success_rate": len(ok) / len(g),
                     "iterations_median": float(ok["iterations"].median()) if len(ok) and ok["iterations"].notna().any() else np.nan,
                     "nfev_median": float(ok["nfev"].median()) if len(ok) else np.nan})
    table = pd.DataFrame(rows)
    save_csv(table, target / "success.csv", index=False, float_format="%.4g")
    log("  success rate by start distance (radii):")
    for arc, ta in table.groupby("arc_deg", sort=False):
        piv = ta.pivot_table(index=["method", "params"], columns="start_distance", values="success_rate", sort=False)
        log(f"  {arc:.0f}° arc " + " " * 28 + "".join(f"{c:>7g}" for c in piv.columns))
        for (m, p), vals in piv.iterrows():
            label = m + ("" if p == "{}" else " " + p.replace('"', "").replace("{", "").replace("}", ""))
            log(f"    {label:<40}" + "".join(f"{v:7.2f}" for v in vals))
    figure(table, target)
    return {"success_table": "success.csv", "figure": "convergence.png"}


def figure(table, target):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    arcs = list(table["arc_deg"].unique())
    fig, axes = plt.subplots(1, len(arcs), figsize=(5 * len(arcs), 3.6), squeeze=False, sharey=True)
    for j, arc in enumerate(arcs):
        groups = list(table[table["arc_deg"] == arc].groupby(["method", "params"], sort=False))
        for k, ((m, p), g) in enumerate(groups):
            label = m.split(".", 1)[1] + ("" if p == "{}" else " " + p.replace('"', "").replace("{", "").replace("}", ""))
            # small vertical offsets keep coinciding curves visible
            axes[0, j].semilogx(g["start_distance"], g["success_rate"] + 0.012 * (k - len(groups) / 2),
                                marker="osd^v"[k % 5], ms=5, label=label)
        axes[0, j].set_title(f"{arc:.0f}° arc")
        axes[0, j].set_xlabel("start distance from the centre [radii]")
    axes[0, 0].set_ylabel("success rate (curves offset by ±0.03 for visibility)")
    axes[0, -1].legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, target / "convergence.png", dpi=110)
    plt.close(fig)


def report_tables(folder, f):
    """The tables a reader wants from this study (moved here from the report, which names no study)."""
    import pandas as pd

    from experiments.study import Table
    out = []
    t = pd.read_csv(folder / "success.csv")
    for arc, g in t.groupby("arc_deg", sort=False):
        piv = g.pivot_table(index=["method", "params"], columns="start_distance", values="success_rate", sort=False)
        piv.columns = [f"{c:g} R" for c in piv.columns]
        piv = piv.reset_index()
        piv["method"] = piv["method"] + piv["params"].map(lambda p: "" if p == "{}" else " " + p.replace('"', ""))
        out.append((f"Convergence from distant starts ({arc:.0f}° arc): success rate by start distance",
                    piv.drop(columns=["params"]).round(2)))
    return [Table(caption=c, data=t) for c, t in out if t is not None and len(t)]
