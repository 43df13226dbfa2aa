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
