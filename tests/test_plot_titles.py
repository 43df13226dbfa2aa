"""Plot titles an operator reads: the roundness figure's verdict title is wrapped inside the figure, clear of the
spectrum's title (it ran past the left edge and over 'harmonic spectrum ...')."""
import io

import numpy as np

import methods
from fitbench.cli.options import verdict, verdict_title
from fitbench.plots.roundness import plot


def test_a_long_roundness_verdict_title_is_wrapped_inside_the_figure_and_clear_of_the_spectrum():
    t = np.linspace(0, 2 * np.pi, 1800, endpoint=False)
    r = 3.0 + 1.5e-3 * np.cos(3 * t) + 0.3e-3 * np.cos(17 * t) + 0.2e-3 * np.cos(2 * t + 1)
    res = methods.fit("roundness.iso12181", np.c_[r * np.cos(t), r * np.sin(t)], cutoff_upr=50.0)
    values = {f"RONt {k.upper()}": v["RONt"] for k, v in res.references.items()}
    check = verdict(values, {k: 0.004 for k in values})
    title = "R1_polar_comma.csv" + verdict_title(check)
    assert len(title) > 120                                          # the reviewer's title: one line was 140 chars
    seen = []

    def save(fig, path):
        fig.savefig(io.BytesIO(), format="png", dpi=110)            # the CLI's dpi; the layout must hold at it
        renderer = fig.canvas.get_renderer()
        polar, spectrum = fig.axes[0], fig.axes[1]
        head, box = polar.title.get_window_extent(renderer), fig.bbox
        assert box.x0 <= head.x0 and head.x1 <= box.x1 and box.y0 <= head.y0 and head.y1 <= box.y1, (head, box)
        assert not head.overlaps(spectrum.title.get_window_extent(renderer))
        lines = polar.title.get_text().splitlines()
        assert len(lines) >= 3 and all(len(ln) <= 60 for ln in lines), lines
        for k, v in values.items():                                  # no figure split from its value and unit
            assert any(f"{k} {v * 1e3:.2f} µm / 4 µm".replace(" ", "\u00a0") in ln for ln in lines), k
        seen.append(lines)

    plot(res, "unused.png", title=title, save=save)
    assert seen


def test_the_report_page_wraps_a_long_line_instead_of_shrinking_its_text():
    """One 190-character heading set the whole text block of the circular-test report in about 4 pt; long lines are
    now wrapped (indented) and the text stays 8 pt, inside the page."""
    from matplotlib.text import Text
    from fitbench.plots.report_page import one_page
    long = "diagnostics " + "(a long heading that runs on) " * 7
    lines = ["files        cw.csv, ccw.csv", long, "  squareness    +66.548 +- 0.075 µrad"]
    seen = []

    def save(fig, path):
        renderer = fig.canvas.get_renderer()
        fig.draw(renderer)
        block = [t for t in fig.findobj(Text) if t.get_text().startswith("files")][0]
        e = block.get_window_extent(renderer)
        assert block.get_fontsize() == 8.0
        assert fig.bbox.x0 <= e.x0 and e.x1 <= fig.bbox.x1
        text = block.get_text().splitlines()
        assert len(text) > 3 and all(t.startswith("    ") for t in text[2:-1]) and text[-1] == lines[-1]
        assert " ".join(p.strip() for p in text[1:-1]) == long.strip() and max(map(len, text)) <= 110
        seen.append(text)

    one_page("unused.pdf", title="t", lines=lines, draw=lambda sub: None, save=save)
    assert seen


def test_the_report_page_never_wraps_a_table_row():
    """A table wider than the page at 8 pt (the roundness report's 137-character rows) keeps its rows whole: the text
    is set in the font that fits the widest row, and only prose lines are wrapped to that width."""
    from matplotlib.text import Text
    from fitbench.plots.report_page import one_page
    row = "least-squares circle (LSCI)  " + "  ".join(f"{v:10.4f}" for v in range(10))
    note = "note: " + "a long explanation of the data " * 8
    seen = []

    def save(fig, path):
        block = [t for t in fig.findobj(Text) if t.get_text().startswith("note")][0]
        text = block.get_text().splitlines()
        assert row in text and len(row) > 110
        assert max(map(len, text)) == len(row) and len(text) > 2         # the note wrapped to the row's width
        assert block.get_fontsize() < 8.0
        seen.append(text)

    one_page("unused.pdf", title="t", lines=[note, row], draw=lambda sub: None, save=save)
    assert seen
