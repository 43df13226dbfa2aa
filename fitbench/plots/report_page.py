"""A one-page test report (``--report FILE.pdf``): what instrument software hands to a customer. An A4 page
with the test conditions, the figures of the standard with their verdict, the diagnostics (the text the
command prints, set in a monospaced font) and the test's plot below them, drawn on the same page by the
command's own plot function (vector graphics in the PDF)."""
from __future__ import annotations

import datetime as _dt
import re
import textwrap

from fitbench import __version__
from fitbench.plots import report_figure

A4_INCHES = (8.27, 11.69)
_LEFT, _RIGHT, _TOP = 0.05, 0.95, 0.955
_CHAR_WIDTH = 0.62      # DejaVu Sans Mono: advance width / font size (0.60), with a margin
_FONT_PT = 8.0          # the text's font size, unless the lines would not fit half the page's height


def one_page(path, *, title: str, lines: list[str], draw, aspect: float = 0.6, save=None) -> None:
    """Write the page: ``title`` and ``lines`` (monospaced text, sized to fit the width and at most half the
    height) in the upper part; ``draw(subfigure)`` draws the test's plot below (a matplotlib SubFigure: the
    plot functions' ``into``), ``aspect`` = its height / width."""
    width_pt = (_RIGHT - _LEFT) * A4_INCHES[0] * 72
    raw = [ln for block in lines for ln in str(block).splitlines()] or [""]
    # a table's row (fields apart by two spaces or more) is never wrapped: the text is set in the font that fits the
    # widest row, at most 8 pt; a line of prose longer than that is wrapped (its continuation indented), not set in
    # a smaller font (one long heading made the whole block about 4 pt)
    rows = [ln for ln in raw if re.search(r"\S {2,}\S", ln.strip())]
    chars = max([int(width_pt / (_CHAR_WIDTH * _FONT_PT)), *map(len, rows)])
    text = [part for ln in raw for part in
            ([ln] if ln in rows else textwrap.wrap(ln, chars, subsequent_indent=" " * (len(ln) - len(ln.lstrip()) + 4),
                                                   break_on_hyphens=False, break_long_words=True) or [""])]
    longest = max(len(ln) for ln in text)
    size = min(_FONT_PT, width_pt / (_CHAR_WIDTH * max(longest, 1)), 0.5 * A4_INCHES[1] * 72 / (1.2 * len(text)))
    with report_figure(path, dpi=150, save=save, figsize=A4_INCHES, layout="constrained") as fig:
        stamp = _dt.datetime.now().strftime("%Y-%m-%d %H:%M")
        fig.text(_LEFT, 0.98, title, fontsize=12, fontweight="bold", va="top")
        fig.text(_RIGHT, 0.98, f"fitbench {__version__}, {stamp}", fontsize=7, va="top", ha="right", color="0.4")
        fig.text(_LEFT, _TOP, "\n".join(text), fontsize=size, family="monospace", va="top", linespacing=1.2)
        text_bottom = _TOP - len(text) * size * 1.2 / 72 / A4_INCHES[1] - 0.015
        height = min(text_bottom - 0.02, 1.25 * aspect * A4_INCHES[0] / A4_INCHES[1])
        rows = fig.subfigures(3, 1, height_ratios=[1 - text_bottom, height, text_bottom - height], facecolor="none")
        draw(rows[1])
