"""Study ``scaling``: runtime against N for every method, with log-log slopes (N >= 1000)."""
from __future__ import annotations

import numpy as np
import pandas as pd

from experiments.outputs import save_csv
from experiments.study import Analysis, Figure, Study, Table


def figure(ok, slopes, target):
    """Median runtime against N, one panel per method family (registry metadata), log-log slope in the legend."""
    import methods
    from experiments.render import style
    plt = style.plotting()
    ok = ok.assign(family=ok["method"].map(lambda m: methods.get(m).family))
    families = list(dict.fromkeys(ok["family"]))
    with style.figure_style():
        fig, axes = plt.subplots(1, len(families), figsize=style.size(1.0, 0.85), sharey=True, squeeze=False)
        for ax, fam in zip(axes[0], families):
            for label, g in ok[ok["family"] == fam].groupby("label", sort=True):
                g = g.sort_values("data_n")
                kw = style.method_style(label)
                s = slopes.get(label)
                ax.plot(g["data_n"], g["time_median_s"] * 1e3, marker=kw["marker"], color=kw["color"], ms=3,
                        label=style.short_label(label) + (f" ({s:.2f})" if s is not None else ""))
            ax.set_xscale("log")
            ax.set_yscale("log")
            style.plain_log_ticks(ax, "both")
            ax.set_title(f"{fam} methods")
            ax.set_xlabel("N (points)")
            ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.22), ncol=2, frameon=False)
        axes[0, 0].set_ylabel("median runtime per fit [ms]")
        style.save(fig, target / "scaling.png")
        plt.close(fig)


class ScalingStudy(Study):
    """The ``scaling`` study (see the module's docstring)."""

    values = None  # its analysis names its values

    def analyse(self, df, cfg, target, log):
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
        caption = ("Median runtime per fit [ms] of every method on synthetic circles (R = 299 mm) and ellipses "
                   "against N, and the log-log slope for N >= 1000")
        fig = Figure(caption="Median runtime per fit [ms] against the number of points N, per method family (log-log), "
                             "synthetic circles and ellipses; the log-log slope for N >= 1000 in the legend", file="scaling.png")
        return Analysis(tables=[Table(caption=caption, data=shown, unit="ms")], figures=[fig], values=values,
                        findings=findings)
