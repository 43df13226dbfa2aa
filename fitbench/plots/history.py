"""The trend plot of ``fitbench history``: one panel per test (circular test, positioning, roundness), the
test figures against the test date. The panels share one date axis (the same dates line up) and each shows its
date labels; a single test date is shown over a few days around it, not matplotlib's default of years."""
from __future__ import annotations

import datetime as _dt

from fitbench.plots import report_figure

#: half the date span shown around a single test date (or added on each side of several)
SINGLE_DATE_HALF_SPAN = _dt.timedelta(days=3)


def date_limits(dates) -> tuple[_dt.datetime, _dt.datetime]:
    """The date axis' limits: the dates' span padded by 5 % each side, at least 3 days around a single date."""
    lo, hi = min(dates), max(dates)
    pad = max((hi - lo) * 0.05, SINGLE_DATE_HALF_SPAN if hi == lo else _dt.timedelta(hours=12))
    return lo - pad, hi + pad


def plot(history: dict, columns: dict, path, save=None, into=None, titles: dict | None = None) -> None:
    """``history`` = {(test, machine, plane or axis): [(date, file, {column: value})]}, one panel per trend
    (:func:`fitbench.cli.history.collect`; a plain test name as the key: one trend of that test), drawn with
    ``columns`` = {test: [(JSON path, name, factor, unit)]}, each panel named by ``titles`` (key -> name; default
    the test); written by ``save(fig, path)``."""
    import matplotlib.dates as mdates
    with report_figure(path, dpi=120, save=save, into=into, figsize=(10, 3.4 * len(history))) as fig:
        axes = fig.subplots(len(history), 1, squeeze=False, sharex=True)[:, 0]
        every = [r[0] for rows in history.values() for r in rows]
        locator = mdates.AutoDateLocator(minticks=3, maxticks=8)
        for ax, (key, rows) in zip(axes, history.items()):
            kind = key[0] if isinstance(key, tuple) else key
            dates = [r[0] for r in rows]
            for _, name, _, unit in columns[kind]:
                vals = [r[2][name] for r in rows]
                if any(v is not None for v in vals):
                    ax.plot(dates, [float("nan") if v is None else v for v in vals], "o-", ms=3, lw=1,
                            label=f"{name} [{unit}]")
            ax.set_title(f"{(titles or {}).get(key, kind)}: trend over {len(rows)} test(s)", fontsize=9)
            ax.legend(fontsize=7, ncol=2)
            ax.grid(alpha=0.3)
            ax.xaxis.set_major_locator(locator)
            ax.xaxis.set_major_formatter(mdates.ConciseDateFormatter(locator))
            ax.tick_params(axis="x", labelbottom=True, labelsize=8)   # every panel labels its dates
        axes[0].set_xlim(*date_limits(every))
        axes[-1].set_xlabel("test date (--date, else the JSON file's modification time)", fontsize=8)
        if hasattr(fig, "tight_layout"):
            fig.tight_layout()
