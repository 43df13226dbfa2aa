"""The magnify plot's zoom: the rectangle marking the zoomed window was drawn beyond the main axes (x to 111 mm
where the axes ended at 104) and cut by the figure's edge, and its connector lines crossed the plot. Checked on
the rendered figure: the rectangle inside the axes and the figure, no visible connector, the inset clear of the
rectangle. Data: a 100 mm corner with an 8 µm corner cut (the review's KGM-like recipe)."""
from __future__ import annotations

import numpy as np

import methods as m
from fitbench.plots import pyplot
from fitbench.plots.magnify import zoom_on_largest_error
from methods.magnify import MagnifyInput


def corner():
    s = np.linspace(0, 100, 501)
    ref = np.r_[np.c_[s, 0 * s], np.c_[100 + 0 * s[1:], s[1:]]]
    t = np.linspace(0, 200, 2001)
    x, y = np.where(t <= 100, t, 100.0), np.where(t <= 100, 0.0, t - 100)
    e = 0.008 * np.exp(-np.abs(t - 100))
    return MagnifyInput(ref, np.c_[x - np.where(t > 100, e, 0), y + np.where(t <= 100, e, 0)])


def test_the_zoom_rectangle_lies_inside_the_axes_and_the_inset_clear_of_it():
    data = corner()
    res = m.fit("magnify.offset", data, eta=500.0)
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 6))
    try:
        ax.plot(*data.reference.T)
        ax.plot(*res.points.T)
        ax.set_aspect("equal")
        got = {}
        original = ax.indicate_inset_zoom

        def spy(*a, **k):
            got["zoom"] = original(*a, **k)
            return got["zoom"]
        ax.indicate_inset_zoom = spy
        inset = zoom_on_largest_error(ax, data, res, 500.0)
        fig.tight_layout()
        fig.canvas.draw()
        z = got["zoom"]
        rect, connectors = (z.rectangle, z.connectors) if hasattr(z, "connectors") else z
        r, a, f = rect.get_window_extent(), ax.bbox, fig.bbox
        assert a.x0 - 1 <= r.x0 and r.x1 <= a.x1 + 1 and a.y0 - 1 <= r.y0 and r.y1 <= a.y1 + 1, (r, a)
        assert f.x0 <= r.x0 and r.x1 <= f.x1 and f.y0 <= r.y0 and r.y1 <= f.y1
        assert not any(c.get_visible() for c in connectors or [])
        b = inset.get_window_extent()
        assert b.x1 < r.x0 or r.x1 < b.x0 or b.y1 < r.y0 or r.y1 < b.y0     # the inset does not cover the window
        (x0, x1), (y0, y1) = inset.get_xlim(), inset.get_ylim()
        assert x0 < 100 < x1 and y0 < 0 < y1                            # still the corner of the largest error
    finally:
        plt.close(fig)
