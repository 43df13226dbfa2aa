"""Plots like the positioning paper's figures 2 and 3: mean deviations with their +-k s bounds
(the standard's point-wise view) and the fitted polynomial with its expanded-uncertainty band."""
from __future__ import annotations

import numpy as np

from methods.positioning.model import evaluate_band


def plot(result, path, title: str = "") -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    per, fig_k = result.per_target, result.figures.get("k", 2.0)
    P = per["targets"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4), sharey=True)
    for ax, d, colour in ((axes[0], "up", "tab:blue"), (axes[0], "down", "tab:red")):
        x, s = per[f"mean_{d}"], per[f"s_{d}"]
        ax.plot(P, x * 1e3, "o-", color=colour, ms=4, label=f"mean deviation {'↑' if d == 'up' else '↓'}")
        ax.plot(P, (x + fig_k * s) * 1e3, "--", color=colour, lw=0.8)
        ax.plot(P, (x - fig_k * s) * 1e3, "--", color=colour, lw=0.8, label=f"±{fig_k:g}s {'↑' if d == 'up' else '↓'}")
    axes[0].set_title("ISO 230-2: point-wise (linear between targets)")
    grid = np.linspace(P.min(), P.max(), 400)
    for d, colour in (("up", "tab:blue"), ("down", "tab:red")):
        axes[1].plot(P, per[f"mean_{d}"] * 1e3, "o", color=colour, ms=4)
        if d in result.polynomial:
            v, U = evaluate_band(result.polynomial[d], grid, result.polynomial[d]["k"])
            axes[1].plot(grid, v * 1e3, color=colour, label=f"degree-{result.polynomial[d]['degree']} fit {'↑' if d == 'up' else '↓'}")
            axes[1].fill_between(grid, (v - U) * 1e3, (v + U) * 1e3, color=colour, alpha=0.2,
                                 label=f"U(P), k = {result.polynomial[d]['k']:g}")
    axes[1].set_title("model: fitted curve and expanded uncertainty anywhere on the travel")
    for ax in axes:
        ax.set_xlabel("target position P")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylabel("positional deviation [µm]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
