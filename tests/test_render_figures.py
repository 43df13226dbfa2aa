"""The studies' figures (each beside its study in experiments/studies/): drawn from the committed results tables, fonts >= 8 pt at the printed size, legends
outside every axes, plain-number log ticks, a method keeps its colour across figures."""
from __future__ import annotations

import json
from pathlib import Path

import matplotlib
import pandas as pd
import pytest

from experiments.render import style
from experiments.studies import convergence, magnification, multilateration, noise, positioning, published

matplotlib.use("Agg")
RESULTS = Path(__file__).resolve().parents[1] / "results"


def _csv(study, name):
    path = RESULTS / study / name
    if not path.exists():
        pytest.skip(f"{path} is missing: run python -m experiments.run {study}")
    return pd.read_csv(path)


def _published_rows():
    meta = RESULTS / "published" / "meta.json"
    if not meta.exists():
        pytest.skip(f"{meta} is missing")
    return pd.DataFrame(json.loads(meta.read_text())["findings"]["published_vs_reproduced"])


CASES = {
    "noise": lambda p: noise.kcr_figure(_csv("noise", "kcr.csv"), p),
    "positioning": lambda p: positioning.coverage_figure(_csv("positioning", "coverage.csv"), p),
    "convergence": lambda p: convergence.success_figure(_csv("convergence", "success.csv"), p),
    "magnification": lambda p: magnification.continuity_figure(_csv("magnification", "results.csv"), p),
    "multilateration": lambda p: multilateration.conditioning_figure(_csv("multilateration", "accuracy.csv"), p),
    "published": lambda p: published.circularity_figure(_published_rows(), p),
    "trajectories": lambda p: magnification.trajectories_figure(
        [{"example": "corner_inside_convex", "eta": 200, "method": "magnify.nearest", "title": "nearest"}], p),
}


@pytest.fixture
def captured(monkeypatch):
    """Record every figure the functions save (style.save), with its checks made before it is closed."""
    seen = []
    original = style.save

    def save(fig, path, **kw):
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        legends = fig.legends + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
        overlaps = [ax for lg in legends for ax in fig.axes if ax.get_visible()
                    and lg.get_window_extent(renderer).overlaps(ax.get_window_extent(renderer))]
        ticks = [t.get_text() for ax in fig.axes for t in ax.get_xticklabels() + ax.get_yticklabels()]
        seen.append({"font": style.smallest_font_pt(fig), "overlaps": overlaps, "ticks": ticks,
                     "width_in": fig.get_figwidth()})
        return original(fig, path, **kw)

    monkeypatch.setattr(style, "save", save)
    return seen


@pytest.mark.parametrize("name", sorted(CASES))
def test_figure_is_readable(name, tmp_path, captured):
    path = CASES[name](tmp_path / f"{name}.png")
    assert path.exists() and path.stat().st_size > 5_000
    (info,) = captured
    assert info["font"] >= style.MIN_FONT_PT, f"{name}: a {info['font']} pt text"
    assert not info["overlaps"], f"{name}: a legend overlaps an axes"
    assert info["width_in"] <= style.COLUMN_WIDTH_IN + 1e-9
    assert not any("\\times10^{0}" in t or "10^{0}" in t for t in info["ticks"]), info["ticks"]


def test_plain_numbers():
    assert [style.plain_number(v) for v in (0.001, 0.5, 1.0, 1.4, 20.0, 1000.0, -3.0)] == [
        "0.001", "0.5", "1", "1.4", "20", "1000", "\u22123"]


def test_method_colour_is_stable():
    a = style.method_style("circle.gauss_newton")
    assert style.method_style("circle.gauss_newton") == a
    ids = ["circle.kasa", "circle.pratt", "circle.taubin", "circle.hyper", "circle.gauss_newton",
           "circle.levenberg_marquardt", "circle.nelder_mead", "circle.powell_hybrid", "circle.minimum_zone",
           "circle.chebyshev_lp", "circle.max_inscribed", "circle.min_circumscribed"]
    assert len({(style.method_style(m)["color"], style.method_style(m)["marker"]) for m in ids}) == len(ids)


def test_legend_outside_right_and_pdf(tmp_path):
    import matplotlib.pyplot as plt
    with style.figure_style():
        fig, ax = plt.subplots(figsize=style.size(0.8, 0.5))
        for m in ("circle.kasa", "circle.taubin"):
            ax.plot([1, 10, 100], [1, 2, 3], **style.method_style(m))
        ax.set_xscale("log")
        style.plain_log_ticks(ax, "x")
        legend = style.legend_outside(fig, where="right")
        fig.canvas.draw()
        r = fig.canvas.get_renderer()
        assert not legend.get_window_extent(r).overlaps(ax.get_window_extent(r))
        labels = [t.get_text() for t in ax.get_xticklabels() if t.get_text()]
        assert {"1", "10", "100"} <= set(labels) and not any("$" in t for t in labels)
        path = style.save(fig, tmp_path / "f.png", pdf=True)
    assert path.exists() and path.with_suffix(".pdf").read_bytes()[:4] == b"%PDF"


def test_a_plugin_never_recolours_a_built_in_method(monkeypatch):
    """Colours come from the rank within the family: a plugin method whose id sorts first ('circle.aaa_fit') moved
    every built-in circle method to the next colour (Figure 15 re-coloured by installing any plugin)."""
    from types import SimpleNamespace

    import methods
    ids = ["circle.kasa", "circle.gauss_newton", "circle.minimum_zone", "ellipse.halir_flusser"]
    monkeypatch.setattr(style, "_ORDER", None)
    before = {m: style.method_style(m) for m in ids}
    builtins = methods.list_methods()
    plugin = SimpleNamespace(id="circle.aaa_fit", family="circle", builtin=False)
    monkeypatch.setattr(methods, "list_methods", lambda *a, **k: [plugin, *builtins])
    monkeypatch.setattr(style, "_ORDER", None)
    assert {m: style.method_style(m) for m in ids} == before
    assert style.method_style("circle.aaa_fit")["color"] in style.PALETTE


def test_saved_figures_carry_no_creation_date(tmp_path):
    """A figure saved twice gives the same bytes: matplotlib's PDF carries a CreationDate unless told not to, so
    every report rebuild changed every figure PDF."""
    import matplotlib.pyplot as plt

    from fitbench.plots import save_atomic
    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    for suffix in (".pdf", ".svg", ".png"):
        save_atomic(fig, tmp_path / f"a{suffix}")
        first = (tmp_path / f"a{suffix}").read_bytes()
        assert b"CreationDate" not in first and b"<dc:date>" not in first, suffix
        save_atomic(fig, tmp_path / f"b{suffix}")
        assert (tmp_path / f"b{suffix}").read_bytes() == first, suffix
    plt.close(fig)
    style.save(*plt.subplots()[:1], tmp_path / "c.png")
    assert b"CreationDate" not in (tmp_path / "c.pdf").read_bytes()
