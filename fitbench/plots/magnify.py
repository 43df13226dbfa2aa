"""The magnified contouring-error figure: reference polyline and magnified trajectory."""
from __future__ import annotations

from fitbench.plots import pyplot, save_atomic


def plot_magnified(data, res, path, eta, *, save=None):
    """The reference polyline and the magnified trajectory (the magnification paper's figures)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.plot(*data.reference.T, color="0.5", lw=1, label="reference")
    ax.plot(*res.points.T, lw=0.8, label=f"{res.method}, magnification {eta:g}")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.legend(fontsize=8)
    ax.set_title(f"continuity {res.extra['continuity']:.2f}, loops {res.extra['self_intersections']}; "
                 f"largest error {res.form_error * 1e3:.2f} µm", fontsize=9)
    fig.tight_layout()
    try:
        save(fig, path) if save is not None else save_atomic(fig, path, dpi=120)
    finally:
        plt.close(fig)
