"""The method reports' figures (circular-test polar plot, positioning plot) go through one helper,
fitbench.plots.report_figure: the figure is closed on every path (drawing error, write error, success)
and the file is written atomically (a failed write leaves the previous file whole and no temporary file)."""
import dataclasses

import numpy as np
import pytest

import methods
from datasets.circular_test import circular_test, lola_hbg130
from datasets.positioning import axis_test
from fitbench.plots import pyplot, report_figure, save_atomic
from methods.circular_test import evaluate
from fitbench.plots.circular_test import polar_plot
from fitbench.plots.positioning import plot as positioning_plot

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def polar_inputs():
    cond, err = lola_hbg130()
    cw, ccw, _ = circular_test(cond, err, seed=2004)
    return cw, ccw, evaluate(cw, ccw, cond.nominal_radius, cond.nominal_center)


@pytest.fixture(scope="module")
def positioning_inputs():
    data, _ = axis_test(rng=np.random.default_rng(2), mpe=0.002)
    return methods.fit("positioning.gls_polynomial", data, mpe=0.002), data


def draw_polar(inputs, path, **kw):
    cw, ccw, ev = inputs
    return polar_plot(cw, ccw, ev, path, **kw)


def draw_positioning(inputs, path, **kw):
    res, data = inputs
    return positioning_plot(res, path, data=data, **kw)


DRAWERS = [pytest.param(draw_polar, "polar_inputs", id="circular_test"),
           pytest.param(draw_positioning, "positioning_inputs", id="positioning")]


def open_figures():
    return set(pyplot().get_fignums())


@pytest.mark.parametrize("draw, inputs", DRAWERS)
def test_writes_a_whole_png_and_closes_the_figure(draw, inputs, request, tmp_path):
    before = open_figures()
    path = tmp_path / "fig.png"
    draw(request.getfixturevalue(inputs), path)
    assert path.read_bytes().startswith(PNG_MAGIC) and path.stat().st_size > 10_000
    assert [p.name for p in tmp_path.iterdir()] == ["fig.png"]  # no temporary file left
    assert open_figures() == before


@pytest.mark.parametrize("draw, inputs", DRAWERS)
def test_a_failed_write_keeps_the_old_file_and_closes_the_figure(draw, inputs, request, tmp_path, monkeypatch):
    from matplotlib.figure import Figure
    path = tmp_path / "fig.png"
    path.write_bytes(b"the previous figure")

    def broken_savefig(self, fname, **kwargs):
        with open(fname, "wb") as f:  # a writer that dies half-way through
            f.write(PNG_MAGIC + b"half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", broken_savefig)
    before = open_figures()
    with pytest.raises(OSError, match="No space left"):
        draw(request.getfixturevalue(inputs), path)
    assert path.read_bytes() == b"the previous figure"
    assert [p.name for p in tmp_path.iterdir()] == ["fig.png"]
    assert open_figures() == before


def test_an_error_while_drawing_closes_the_figure_and_writes_nothing(polar_inputs, tmp_path):
    cw, ccw, ev = polar_inputs
    incomplete = dataclasses.replace(ev, figures={k: v for k, v in ev.figures.items() if k != "G_cw"})  # needed late
    before = open_figures()
    with pytest.raises(KeyError, match="G_cw"):
        polar_plot(cw, ccw, incomplete, tmp_path / "fig.png")
    assert open_figures() == before
    assert not list(tmp_path.iterdir())


def test_positioning_drawing_error_closes_the_figure(positioning_inputs, tmp_path):
    res, data = positioning_inputs

    class Broken:  # a data object whose runs cannot be drawn
        up = down = None

    before = open_figures()
    with pytest.raises(AttributeError):
        positioning_plot(res, tmp_path / "fig.png", data=Broken())
    assert open_figures() == before
    assert not list(tmp_path.iterdir())


def test_a_callers_save_gets_the_drawn_figure_and_it_is_closed_after(polar_inputs):
    seen = []
    before = open_figures()
    draw_polar(polar_inputs, "unused.png", save=lambda fig, path: seen.append((fig.number, path, open_figures())))
    (number, path, during), = seen
    assert path == "unused.png" and number in during  # open while the caller saves it
    assert open_figures() == before


def test_save_atomic_and_report_figure_alone(tmp_path):
    path = tmp_path / "plain.svg"
    with report_figure(path, dpi=50, figsize=(2, 2)) as fig:
        fig.add_subplot().plot([0, 1], [0, 1])
    assert path.read_text().lstrip().startswith("<?xml")  # the format follows the suffix
    fig = pyplot().figure()
    try:
        save_atomic(fig, tmp_path / "again.png", dpi=30)
    finally:
        pyplot().close(fig)
    assert (tmp_path / "again.png").read_bytes().startswith(PNG_MAGIC)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["again.png", "plain.svg"]


def test_every_text_of_the_polar_figure_is_legible_at_report_width_and_inside_the_figure(polar_inputs):
    """Shown 800 px wide (the report's figure width) every text is >= 9 px high, lies inside the figure,
    and no two texts outside the polar grid overlap (the table, legend, title, angle labels)."""
    from matplotlib.text import Text
    from methods.circular_test import diagnose
    cw, ccw, ev = polar_inputs
    cond, _ = lola_hbg130()
    dg = diagnose(cw, ccw, cond.nominal_radius, cond.nominal_center, feed_mm_min=1000.0)
    checked = []

    def check(fig, path):
        renderer = fig.canvas.get_renderer()
        fig.draw(renderer)
        width_in = fig.get_figwidth()
        box = fig.bbox
        texts = [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()]
        assert len(texts) >= 20                     # the panel, the legend, the ring and angle labels, the title
        for t in texts:
            px_at_800 = t.get_fontsize() * 800 / (72 * width_in)
            assert px_at_800 >= 9, (t.get_text(), round(px_at_800, 1))
            e = t.get_window_extent(renderer)
            assert box.x0 - 1 <= e.x0 and e.x1 <= box.x1 + 1 and box.y0 - 1 <= e.y0 and e.y1 <= box.y1 + 1, t.get_text()
        polar = fig.axes[0]
        rings = set(polar.get_yticklabels())        # inside the grid, on a white ground, over the traces
        outside = [t for t in texts if t not in rings]
        extents = [t.get_window_extent(renderer) for t in outside]
        for i in range(len(outside)):
            for j in range(i + 1, len(outside)):
                assert not extents[i].overlaps(extents[j]), (outside[i].get_text(), outside[j].get_text())
        checked.append(len(texts))

    polar_plot(cw, ccw, ev, "unused.png", diagnostics=dg, save=check,
               title="verdict FAIL (G 25.66 µm / 20 µm, H 5.22 µm / 10 µm, G(b) 25.66 µm / 30 µm)")
    assert checked


def test_the_polar_figure_drawn_into_part_of_a_page_stays_in_its_part(polar_inputs):
    """Drawn into a SubFigure (the one-page report's lower part) every text of the table lies in that part."""
    from matplotlib.text import Text
    cw, ccw, ev = polar_inputs
    fig = pyplot().figure(figsize=(8.27, 11.69))
    try:
        top, bottom = fig.subfigures(2, 1)
        polar_plot(cw, ccw, ev, None, into=bottom)
        renderer = fig.canvas.get_renderer()
        fig.draw(renderer)
        box = bottom.bbox
        texts = [t for t in bottom.findobj(Text) if t.get_visible() and t.get_text().strip()]
        assert any(t.get_text() == "G(b)" for t in texts)
        for t in texts:
            e = t.get_window_extent(renderer)
            assert box.y0 - 1 <= e.y0 and e.y1 <= box.y1 + 1, t.get_text()
    finally:
        pyplot().close(fig)


def roundness_inputs():
    t = np.linspace(0, 2 * np.pi, 3600, endpoint=False)
    r = 12.5 + 1.5e-3 * np.cos(3 * t) + 0.6e-3 * np.cos(2 * t + 1) + 0.3e-3 * np.cos(17 * t)
    return methods.fit("roundness.iso12181", np.c_[r * np.cos(t), r * np.sin(t)], cutoff_upr=50.0)


@pytest.mark.parametrize("which", ["positioning", "roundness"])
def test_positioning_and_roundness_texts_are_legible_at_report_width_and_inside_the_figure(which, positioning_inputs):
    """Shown 800 px wide every text of the positioning and the roundness figure is >= 9 px high and lies
    inside the figure (the legends were 6 px, the roundness ring labels 5.6 px, its legend cut off)."""
    from matplotlib.text import Text
    from fitbench.plots.roundness import plot as roundness_plot
    seen = []

    def check(fig, path):
        renderer = fig.canvas.get_renderer()
        fig.draw(renderer)
        undrawn = set()                               # tick labels outside the axes' view (matplotlib skips them)
        for a in fig.axes:
            for axis in (a.xaxis, a.yaxis):
                lo, hi = sorted(axis.get_view_interval())
                eps = 1e-9 * max(abs(lo), abs(hi), 1.0)
                undrawn |= {lab for tick in axis.get_major_ticks() if not lo - eps <= tick.get_loc() <= hi + eps
                            for lab in (tick.label1, tick.label2)}
        texts = [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip() and t not in undrawn]
        for t in texts:
            px_at_800 = t.get_fontsize() * 800 / (72 * fig.get_figwidth())
            assert px_at_800 >= 9, (t.get_text(), round(px_at_800, 1))
            e, box = t.get_window_extent(renderer), fig.bbox
            assert box.x0 - 1 <= e.x0 and e.x1 <= box.x1 + 1 and box.y0 - 1 <= e.y0 and e.y1 <= box.y1 + 1, t.get_text()
        seen.append(len(texts))

    if which == "positioning":
        draw_positioning(positioning_inputs, "unused.png", save=check, title="synthetic axis, 5 runs")
    else:
        roundness_plot(roundness_inputs(), "unused.png", title="a turned shaft", save=check)
    assert seen and seen[0] > 10


def test_a_signed_value_that_rounds_to_zero_prints_without_a_minus():
    from fitbench.plots.circular_test import _signed
    assert _signed(-0.001) == "+0.00" and _signed(-0.004999) == "+0.00"
    assert _signed(-0.006) == "-0.01" and _signed(0.0) == "+0.00"
    assert _signed(1.234) == "+1.23" and _signed(-1.234) == "-1.23"
