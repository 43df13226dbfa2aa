"""Study ``noise``: bias and RMSE of centre and radius against the Kanatani–Cramér–Rao bound.

For isotropic Gaussian noise of s.d. sigma per coordinate, any unbiased estimator of (a, b, R) has
covariance >= sigma^2 (W^T W)^-1, W rows (cos t_i, sin t_i, 1) at the true points (the KCR bound,
Kanatani 1996; Chernov & Lesort, J. Math. Imaging Vis. 2005). Geometric and the modern algebraic fits
reach it to first order; they differ in their (second-order) bias, which dominates on short arcs.
"""
from __future__ import annotations

import json

import numpy as np
import pandas as pd

from datasets.synthetic import circle_points
from experiments.study import save_csv, save_figure


def kcr_bound(arc_deg: float, n: int, sigma: float, radius: float = 1.0) -> tuple[float, float]:
    """(centre RMSE bound, radius RMSE bound) for n points evenly on an arc of arc_deg degrees."""
    full = arc_deg >= 360.0
    pts = circle_points((0.0, 0.0), radius, n, arc=(0.0, np.radians(arc_deg)), endpoint=not full)
    W = np.column_stack([pts[:, 0] / radius, pts[:, 1] / radius, np.ones(n)])
    V = sigma ** 2 * np.linalg.inv(W.T @ W)
    return float(np.sqrt(V[0, 0] + V[1, 1])), float(np.sqrt(V[2, 2]))


def finalize(df, cfg, target, log):
    rows = []
    for (arc, noise, n, m, p), g in df.groupby(["data_arc_deg", "data_noise", "data_n", "method", "params"], sort=False):
        ok = g[g["status"] == "ok"]
        kc, kr = kcr_bound(arc, int(n), noise)
        r = {"arc_deg": arc, "noise": noise, "n": int(n), "method": m, "params": p, "runs": len(g), "ok": len(ok)}
        if len(ok):
            ce = ok["center_error"].astype(float)
            re = ok["radius_error"].astype(float)
            r.update(center_rmse=float(np.sqrt(np.mean(ce ** 2))), radius_bias=float(re.mean()),
                     radius_rmse=float(np.sqrt(np.mean(re ** 2))), kcr_center=kc, kcr_radius=kr)
            r["center_rmse_over_kcr"] = r["center_rmse"] / kc
            r["radius_rmse_over_kcr"] = r["radius_rmse"] / kr
            r["radius_bias_over_sigma"] = r["radius_bias"] / noise
        rows.append(r)
    table = pd.DataFrame(rows)
    save_csv(table, target / "kcr.csv", index=False, float_format="%.6g")
    zone = set(df.loc[df["inner_radius"].notna(), "method"]) if "inner_radius" in df else set()
    figure(table, target, zone_methods=zone)
    worst = table[table["noise"] == table["noise"].max()]
    log("  radius RMSE / KCR bound at the largest noise (1.00 = the statistical limit):")
    piv = worst.pivot_table(index="method", columns="arc_deg", values="radius_rmse_over_kcr", aggfunc="mean")
    piv = piv[sorted(piv.columns, reverse=True)]
    log("  " + f"{'method':<28}" + "".join(f"{c:>10.0f}°" for c in piv.columns))
    for m, vals in piv.iterrows():
        log("  " + f"{m:<28}" + "".join(f"{v:11.2f}" for v in vals))
    return {"kcr_table": "kcr.csv", "figure": "noise_kcr.png",
            "radius_rmse_over_kcr_at_max_noise": {m: {f"{c:g}": float(v) for c, v in vals.items()}
                                                  for m, vals in piv.iterrows()}}


def figure(table: pd.DataFrame, target, zone_methods=frozenset()) -> None:
    """The least-squares estimators (every method whose result is not a zone, plugins included; the zone
    methods estimate other circles, their rows are in kcr.csv); dashed: closed-form fits (method metadata)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = table["n"].max()
    import methods
    closed_form = {s.id for s in methods.list_methods() if s.kind == "closed form"}
    t = table[(table["n"] == n) & table["params"].eq("{}") & ~table["method"].isin(zone_methods)]
    arcs = sorted(t["arc_deg"].unique(), reverse=True)
    colours = plt.get_cmap("tab10").colors
    fig, axes = plt.subplots(2, len(arcs), figsize=(3.2 * len(arcs), 6.2), sharex=True, squeeze=False)
    for j, arc in enumerate(arcs):
        ta = t[t["arc_deg"] == arc]
        for k, (m, g) in enumerate(ta.groupby("method", sort=True)):
            g = g.sort_values("noise")
            kw = dict(ls="--" if m in closed_form else "-", marker="osd^v<>p"[k % 8], ms=4, color=colours[k % 10],
                      label=m.split(".", 1)[1])
            axes[0, j].loglog(g["noise"], g["radius_rmse_over_kcr"], **kw)
            axes[1, j].semilogx(g["noise"], g["radius_bias_over_sigma"], **kw)
        axes[0, j].axhline(1.0, color="k", lw=0.8)
        axes[0, j].set_title(f"{arc:.0f}° arc, N = {n}")
        axes[1, j].axhline(0.0, color="k", lw=0.8)
        axes[1, j].set_xlabel("σ / R")
    axes[0, 0].set_ylabel("radius RMSE / KCR bound")
    axes[1, 0].set_ylabel("radius bias / σ")
    axes[0, -1].legend(fontsize=6, loc="upper left")
    fig.suptitle("Least-squares estimators: radius RMSE against the KCR bound (top), radius bias (bottom); "
                 "dashed: closed-form fits")
    fig.tight_layout()
    save_figure(fig, target / "noise_kcr.png", dpi=110)
    plt.close(fig)


def report_tables(folder, f):
    """The tables a reader wants from this study (moved here from the report, which names no study)."""
    import pandas as pd

    from experiments.study import Table
    out = []
    t = pd.read_csv(folder / "kcr.csv")
    t = t[(t["noise"] == t["noise"].max()) & (t["n"] == t["n"].max())]
    piv = t.pivot_table(index="method", columns="arc_deg", values="radius_rmse_over_kcr", sort=False)
    piv = piv[sorted(piv.columns, reverse=True)].reset_index()
    piv.columns = ["method"] + [f"{c:.0f}° arc" for c in piv.columns[1:]]
    out.append((f"Radius RMSE / KCR bound at sigma = {t['noise'].max():g} R, N = {t['n'].max()} (1 = the statistical limit)",
                piv.round(2)))
    return [Table(caption=c, data=t) for c, t in out if t is not None and len(t)]
