"""Study ``scaling``: runtime against N for every method, with log-log slopes (N >= 1000)."""
from __future__ import annotations

import numpy as np
import pandas as pd

from experiments.study import Analysis, Table, save_csv, save_figure


def analyse(df, cfg, target, log):
    """Runtime table and slopes; findings built from the measured slopes (the contract's example of an
    ``analyse`` study: tables, named values and a findings text, never hand-written numbers)."""
    ok = df[(df["status"] == "ok") & df["time_median_s"].notna()].copy()
    ok["label"] = ok["method"] + ok["params"].map(lambda p: "" if p == "{}" or "start" in p else " " + p)
    slopes = {}
    for label, g in ok.groupby("label", sort=False):
        big = g[g["data_n"] >= 1000]
        if len(big) >= 2:
            slopes[label] = float(np.polyfit(np.log10(big["data_n"]), np.log10(big["time_median_s"]), 1)[0])
    table = ok.pivot_table(index="label", columns="data_n", values="time_median_s", sort=False)
    table["slope_N>=1000"] = pd.Series(slopes)
    save_csv(table, target / "runtime_table.csv", float_format="%.4g")
    log("  median runtime [ms] by N, and the log-log slope for N >= 1000:")
    log("  " + f"{'method':<40}" + "".join(f"{int(c):>11}" for c in table.columns[:-1]) + f"{'slope':>8}")
    for label, vals in table.iterrows():
        log("  " + f"{label:<40}" + "".join(f"{v * 1e3:11.3f}" if v == v else f"{'-':>11}" for v in vals.iloc[:-1])
            + (f"{vals.iloc[-1]:8.2f}" if vals.iloc[-1] == vals.iloc[-1] else f"{'-':>8}"))
    figure(ok, slopes, target)
    shown = table.reset_index().rename(columns={"label": "method"})
    n_cols = [c for c in shown.columns[1:-1]]
    for c in n_cols:
        shown[c] = shown[c] * 1e3
    shown.columns = ["method"] + [f"N={int(c)} [ms]" for c in n_cols] + ["slope"]
    values = {"slopes": slopes, "largest_n": int(max(n_cols))}
    findings = (f"This run has fewer than two sizes N >= 1000 (largest N = {values['largest_n']}): "
                "no slopes are estimated.")
    if slopes:
        lo, hi = min(slopes, key=slopes.get), max(slopes, key=slopes.get)
        values.update(flattest=lo, flattest_slope=slopes[lo], steepest=hi, steepest_slope=slopes[hi])
        near_linear = sum(0.8 <= v <= 1.2 for v in slopes.values())
        findings = (f"For N >= 1000, {near_linear} of {len(slopes)} methods scale about linearly (log-log slope "
                    f"0.8 to 1.2); the smallest slope is {lo}'s ({slopes[lo]:.2f}), the largest {hi}'s "
                    f"({slopes[hi]:.2f}).")
    caption = (f"Median runtime per fit [ms] of every method on synthetic circles (R = 299 mm) and ellipses "
               f"against N, and the log-log slope for N >= 1000")
    return Analysis(tables=[Table(caption=caption, data=shown.round(3), unit="ms")], values=values, findings=findings)


def figure(ok, slopes, target):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), sharey=True)
    colours = plt.get_cmap("tab20").colors
    count = {0: 0, 1: 0}
    for label, g in ok.groupby("label", sort=True):
        side = 0 if label.startswith("circle.") else 1
        k = count[side]
        count[side] += 1
        g = g.sort_values("data_n")
        s = slopes.get(label)
        axes[side].loglog(g["data_n"], g["time_median_s"], marker="osd^v<>ph*"[k % 10], ms=4, color=colours[k % 20],
                          ls="-" if k < 10 else "--", label=label.split(".", 1)[1] + (f" ({s:.2f})" if s is not None else ""))
    for ax, title in zip(axes, ("circle methods", "ellipse methods")):
        ax.set_title(f"{title}: median runtime (slope for N ≥ 1000)")
        ax.set_xlabel("N (points)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylabel("seconds per fit")
    fig.tight_layout()
    save_figure(fig, target / "scaling.png", dpi=110)
    plt.close(fig)
