"""The magnified contouring-error figure: reference polyline and magnified trajectory."""
from __future__ import annotations

from fitbench.plots import pyplot, save_atomic


def zoom_on_largest_error(ax, data, res, eta):
    """An inset zoomed on the corner the plot is about: the stretch around the largest contouring error,
    wide enough to show the magnified deviation there (3 eta e_max or 5 % of the trajectory's extent)."""
    import numpy as np
    err = np.asarray(res.residuals, dtype=float) if res.residuals is not None else None
    if err is None or err.size != len(res.points) or not np.isfinite(err).any():
        return None
    k = int(np.nanargmax(np.abs(err)))
    centre = np.asarray(data.measured, dtype=float)[k]
    extent = float(np.max(np.ptp(np.vstack([data.reference, res.points]), axis=0)))
    half = max(3 * eta * float(np.nanmax(np.abs(err))), 0.05 * extent)
    inset = ax.inset_axes([0.62, 0.62, 0.36, 0.36])
    inset.plot(*data.reference.T, color="0.5", lw=1)
    inset.plot(*res.points.T, lw=0.8)
    inset.set_xlim(centre[0] - half, centre[0] + half)
    inset.set_ylim(centre[1] - half, centre[1] + half)
    inset.set_aspect("equal")
    inset.tick_params(labelsize=6)
    inset.set_title(f"largest error, {2 * half:.3g} mm wide", fontsize=7)
    ax.indicate_inset_zoom(inset, edgecolor="0.3")
    return inset


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
    zoom_on_largest_error(ax, data, res, eta)
    fig.tight_layout()
    try:
        save(fig, path) if save is not None else save_atomic(fig, path, dpi=120)
    finally:
        plt.close(fig)
