"""The magnified contouring-error figure: reference polyline and magnified trajectory."""
from __future__ import annotations

from fitbench.plots import pyplot, save_atomic


#: the corners an inset or the legend may take, named by the legend's ``loc``: axes fractions (x0, y0) of a box
#: INSET_SIZE wide, leaving room inside the axes for the inset's tick labels (left, below) and title (above)
INSET_SIZE = 0.36
CORNERS = {"upper right": (0.62, 0.57), "upper left": (0.09, 0.57), "lower right": (0.62, 0.09),
           "lower left": (0.09, 0.09)}


def _corner_load(ax, pts, window) -> dict:
    """Per corner of :data:`CORNERS`: how many of ``pts`` (data coordinates) it would cover, plus a large count
    when it overlaps the zoom ``window`` (x0, x1, y0, y1) itself, in the axes' current limits."""
    import numpy as np
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    fx, fy = (pts[:, 0] - x0) / (x1 - x0), (pts[:, 1] - y0) / (y1 - y0)
    wx = (np.array(window[:2]) - x0) / (x1 - x0)
    wy = (np.array(window[2:]) - y0) / (y1 - y0)
    out = {}
    for name, (cx, cy) in CORNERS.items():
        inside = (fx >= cx) & (fx <= cx + INSET_SIZE) & (fy >= cy) & (fy <= cy + INSET_SIZE)
        overlap = wx[1] >= cx and wx[0] <= cx + INSET_SIZE and wy[1] >= cy and wy[0] <= cy + INSET_SIZE
        out[name] = int(inside.sum()) + (len(pts) + 1) * overlap
    return out


def zoom_layout(ax, data, res, eta):
    """(window (x0, x1, y0, y1), its half width, the corner of :data:`CORNERS` the inset takes) for the stretch
    around the largest contouring error, wide enough to show the magnified deviation there (3 eta e_max or 5 % of
    the trajectory's extent), or None without errors. Widens the axes' limits to hold the window (its rectangle
    used to reach past the axes and be cut by the figure's edge); the inset's corner covers the fewest points and
    not the window. Calling it again on the same axes gives the same answer."""
    import numpy as np
    err = np.asarray(res.residuals, dtype=float) if res.residuals is not None else None
    if err is None or err.size != len(res.points) or not np.isfinite(err).any():
        return None
    k = int(np.nanargmax(np.abs(err)))
    centre = np.asarray(data.measured, dtype=float)[k]
    pts = np.vstack([data.reference, res.points])
    extent = float(np.max(np.ptp(pts, axis=0)))
    half = max(3 * eta * float(np.nanmax(np.abs(err))), 0.05 * extent)
    window = (centre[0] - half, centre[0] + half, centre[1] - half, centre[1] + half)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    pad = 0.02 * extent
    ax.set_xlim(min(x0, window[0] - pad), max(x1, window[1] + pad))
    ax.set_ylim(min(y0, window[2] - pad), max(y1, window[3] + pad))
    load = _corner_load(ax, pts, window)
    return window, half, min(load, key=lambda c: (load[c], list(CORNERS).index(c)))


def zoom_on_largest_error(ax, data, res, eta):
    """An inset zoomed on the corner the plot is about (:func:`zoom_layout`): the rectangle of the window inside
    the axes and the inset's frame share a colour, without connector lines across the plot. The inset, or None."""
    layout = zoom_layout(ax, data, res, eta)
    if layout is None:
        return None
    window, half, corner = layout
    inset = ax.inset_axes([*CORNERS[corner], INSET_SIZE, INSET_SIZE])
    inset.plot(*data.reference.T, color="0.5", lw=1)
    inset.plot(*res.points.T, lw=0.8)
    inset.set_xlim(window[0], window[1])
    inset.set_ylim(window[2], window[3])
    inset.set_aspect("equal")
    inset.tick_params(labelsize=6)
    inset.set_title(f"largest error, {2 * half:.3g} mm wide", fontsize=7)
    colour = "tab:red"
    for spine in inset.spines.values():
        spine.set_edgecolor(colour)
    zoom = ax.indicate_inset_zoom(inset, edgecolor=colour)
    for line in (zoom.connectors if hasattr(zoom, "connectors") else zoom[1]) or []:   # matplotlib >= 3.10 / older
        line.set_visible(False)
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
    ax.set_title(f"continuity {res.extra['continuity']:.2f}, loops {res.extra['self_intersections']}; "
                 f"largest contouring error {res.form_error * 1e3:.2f} µm", fontsize=9)
    loc = "best"
    if zoom_on_largest_error(ax, data, res, eta) is not None:   # the legend where the inset and window leave room
        import numpy as np
        window, _, corner = zoom_layout(ax, data, res, eta)
        load = _corner_load(ax, np.vstack([data.reference, res.points]), window)
        load.pop(corner)
        loc = min(load, key=lambda c: (load[c], list(CORNERS).index(c)))
    ax.legend(fontsize=8, loc=loc)
    fig.tight_layout()
    try:
        save(fig, path) if save is not None else save_atomic(fig, path, dpi=120)
    finally:
        plt.close(fig)
