"""The figures a study declares (``[[figures]]`` in its TOML, and the default figure of a study that declares none):
the built-in plots ``lines`` and ``bars``, registered as a plugin's are (:func:`experiments.study.register_plot`),
drawn from the ok rows with axes labelled with their columns' units, and saved beside the study's outputs."""
from __future__ import annotations

import inspect
from pathlib import Path

import pandas as pd

from experiments.render import style
from experiments.study import PLOT_COLUMNS, PLOTS, Figure, register_plot
from experiments.tables import AGGREGATES, NO_VALUE, lacking_note, rows_where
from experiments.units import DATA_UNITS, aggregate_words, metric_unit, readable, value_unit


def _aggregate(df, by, y, how):
    agg = AGGREGATES[how]
    return df.groupby(by, sort=False, dropna=False)[y].agg(agg)


@register_plot("lines")
def lines(df, ax, *, x, y, by=None, aggregate="mean", logx=False, logy=False, xlabel=None, ylabel=None):
    """One line per value of ``by``: ``aggregate`` of ``y`` against ``x``."""
    groups = df.groupby(by, sort=False, dropna=False) if by else [(y, df)]  # a data set without a by key: 'none'
    for label, g in groups:
        s = _aggregate(g, x, y, aggregate).sort_index()
        ax.plot(s.index, s.values, marker="o", ms=3, label=_legend(by, label))
    ax.set_xscale("log" if logx else "linear")
    ax.set_yscale("log" if logy else "linear")
    ax.set_xlabel(xlabel or x)
    ax.set_ylabel(ylabel or f"{aggregate} of {y}")
    if by:
        ax.legend(fontsize=8, loc="best")


def _legend(by, label) -> str:
    """A line's label: its value of ``by``; of several columns 'circle.kasa, n = 20' (the first column's value, then
    each other as name = value)."""
    def text(v):
        return NO_VALUE if v is None or v != v else str(v)  # the data sets without that parameter
    if isinstance(by, str) or not isinstance(label, tuple):
        return text(label)
    return ", ".join(text(v) if i == 0 else f"{readable(c)} = {text(v)}" for i, (c, v) in enumerate(zip(by, label)))


@register_plot("bars")
def bars(df, ax, *, x, y, aggregate="mean", logy=False, xlabel=None, ylabel=None):
    """One bar per value of ``x``: ``aggregate`` of ``y``."""
    s = _aggregate(df, x, y, aggregate)
    ax.bar(range(len(s)), s.values)
    ax.set_xticks(range(len(s)), [_legend(x, v) for v in s.index], rotation=30, ha="right", fontsize=8)
    ax.set_yscale("log" if logy else "linear")
    ax.set_xlabel(xlabel or x)
    ax.set_ylabel(ylabel or f"{aggregate} of {y}")


def plot_arguments(f: dict) -> dict:
    """The arguments a ``[[figures]]`` entry gives its plot function: its plot keys and its ``args`` table."""
    args = {k: f[k] for k in ("x", "y", "by", "aggregate", "logx", "logy", "xlabel", "ylabel") if k in f}
    args.update(f.get("args", {}))
    return args


def load_plotting_in_background() -> None:
    """Import matplotlib (Agg), pyplot and the PNG and PDF backends in a daemon thread: a run whose rows run in worker processes waits for them
    meanwhile, and its figures need the import after the rows (0.5-0.7 s here). An import that fails here fails
    again, with its message, where the figures are drawn."""
    import threading

    def load():
        try:
            style.plotting()
            style.plotting("backends.backend_agg")  # the PNG of each figure
            style.plotting("backends.backend_pdf")  # its PDF, for the report's LaTeX: 0.15 s more
        except Exception:  # reported where the figures import it
            pass
    threading.Thread(target=load, daemon=True, name="fitbench-load-plotting").start()


def declared_figure(df: pd.DataFrame, f: dict, target: Path, number: int, cfg: dict | None = None) -> Figure:
    """The figure a ``[[figures]]`` entry declares: its registered plot drawn from the ok rows and saved under
    ``target`` as figure ``number`` (PNG and PDF), or the file the study's analysis wrote. An axis the entry does not
    label names its column and the unit of its values in the study ``cfg`` as the default figure's
    (:func:`experiments.units.value_unit`: a length in mm for mm data, in the ``length_unit``, else in data units,
    which the caption says how to name); a count has none."""
    if "file" in f:
        return Figure(caption=f["caption"], file=f["file"])
    plt = style.plotting()
    args = plot_arguments(f)
    accepted = inspect.signature(PLOTS[f["plot"]]).parameters
    note = ""
    for axis, label in (("x", "xlabel"), ("y", "ylabel")):  # axes name their column and its unit
        if isinstance(args.get(axis), str) and label in accepted and label not in args:
            how = args.get("aggregate", "mean")
            unit = "" if axis == "y" and how == "count" else value_unit(cfg, args[axis])
            what = readable(args[axis]) if axis == "x" else aggregate_words(how, args[axis])
            args[label] = f"{what} [{unit}]" if unit else what
            if unit == DATA_UNITS:   # how to name the data's unit, as the default figure's caption says
                note = metric_unit(cfg or {}, args[axis])[1]
    fig, ax = plt.subplots(figsize=(f.get("width", 6.4), f.get("height", 4.2)))
    plot = PLOTS[f["plot"]]
    if plot in (lines, bars):  # these read only the columns their arguments name: select the rows of those alone
        named = [c for a in PLOT_COLUMNS[f["plot"]][0] for c in
                 ([args[a]] if isinstance(args.get(a), str) else list(args.get(a) or ()))]
        df = df[[c for c in dict.fromkeys([*named, "status", "dataset", *(f.get("where") or {})]) if c in df.columns]]
    shown = rows_where(df[df["status"] == "ok"], f.get("where"))
    if plot is lines and isinstance(args.get("x"), str) and args["x"] in shown and shown[args["x"]].isna().any():
        # rows of data sets without the x parameter have no place on the axis: left out, and the caption says so
        note = lacking_note(shown, [args["x"]], drawn=False) + note
        shown = shown[shown[args["x"]].notna()]
    plot(shown, ax, **args)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    name = f"figure_{number}_{f['plot']}.png"
    style.save(fig, target / name, dpi=110)
    caption = f["caption"]
    if note and not caption.rstrip().endswith((".", "!", "?")):
        caption = caption.rstrip() + "."
    return Figure(caption=caption + note, file=name)
