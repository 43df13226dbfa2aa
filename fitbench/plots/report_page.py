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


def one_page(path, *, title: str, lines: list[str], draw, aspect: float = 0.6, save=None,
             warnings: list[str] = ()) -> None:
    """Write the page: ``title``, the command's ``warnings`` in a framed box (each ``warning: ...``, what the
    command printed on stderr: the figures below may be wrong by them), and ``lines`` (monospaced text, all of it
    sized to fit the width and at most half the height) in the upper part; ``draw(subfigure)`` draws the test's
    plot below (a matplotlib SubFigure: the plot functions' ``into``), ``aspect`` = its height / width."""
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
    boxed = [part for w in warnings for part in
             textwrap.wrap(f"warning: {' '.join(str(w).split())}", chars, subsequent_indent=" " * 4,
                           break_on_hyphens=False, break_long_words=True)]
    # the box's lines and the gap below it (its frame and padding) count as text lines for the size
    box_lines = len(boxed) + 1.5 if boxed else 0
    longest = max(len(ln) for ln in text + boxed)
    size = min(_FONT_PT, width_pt / (_CHAR_WIDTH * max(longest, 1)),
               0.5 * A4_INCHES[1] * 72 / (1.2 * (len(text) + box_lines)))
    line_height = size * 1.2 / 72 / A4_INCHES[1]     # one text line, as a fraction of the page's height
    with report_figure(path, dpi=150, save=save, figsize=A4_INCHES, layout="constrained") as fig:
        stamp = _dt.datetime.now().strftime("%Y-%m-%d %H:%M")
        fig.text(_LEFT, 0.98, title, fontsize=12, fontweight="bold", va="top")
        fig.text(_RIGHT, 0.98, f"fitbench {__version__}, {stamp}", fontsize=7, va="top", ha="right", color="0.4")
        top = _TOP
        if boxed:
            fig.text(_LEFT, top, "\n".join(boxed), fontsize=size, family="monospace", va="top", linespacing=1.2,
                     color="#8b0000", bbox=dict(boxstyle="square,pad=0.4", facecolor="#fff1ee", edgecolor="#8b0000",
                                                linewidth=0.8))
            top -= box_lines * line_height
        fig.text(_LEFT, top, "\n".join(text), fontsize=size, family="monospace", va="top", linespacing=1.2)
        text_bottom = top - len(text) * line_height - 0.015
        height = min(text_bottom - 0.02, 1.25 * aspect * A4_INCHES[0] / A4_INCHES[1])
        rows = fig.subfigures(3, 1, height_ratios=[1 - text_bottom, height, text_bottom - height], facecolor="none")
        draw(rows[1])
