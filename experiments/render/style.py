"""One figure style for every figure of the report.

Figures are drawn at their printed size: ``COLUMN_WIDTH_IN`` is the text width of a one-column A4 page with
2.5 cm margins (21 cm - 5 cm = 16 cm), so a font of 9 pt in matplotlib is 9 pt on paper. Use::

    from experiments.render import style
    plt = style.plotting()             # matplotlib.pyplot, Agg backend
    with style.figure_style():
        fig, ax = plt.subplots(figsize=style.size(height_ratio=0.5))
        ax.plot(x, y, **style.method_style("circle.kasa"))
        style.plain_log_ticks(ax, "x")
        style.legend_outside(fig)
        style.save(fig, path)          # PNG, and the vector PDF next to it (pdf=False: PNG only)
"""
from __future__ import annotations

import contextlib
import hashlib
import importlib
from pathlib import Path

COLUMN_WIDTH_IN = 16.0 / 2.54          #: text width of A4 with 2.5 cm margins [in]
MIN_FONT_PT = 8.0                      #: smallest font a figure may use at its printed size

RC = {
    "figure.figsize": (COLUMN_WIDTH_IN, 0.55 * COLUMN_WIDTH_IN),
    "figure.dpi": 100,
    "savefig.dpi": 200,
    "savefig.bbox": "tight",
    "savefig.pad_inches": 0.03,
    "figure.constrained_layout.use": True,
    "font.size": 9.0,
    "axes.titlesize": 9.0,
    "axes.labelsize": 9.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "legend.fontsize": 8.0,
    "legend.title_fontsize": 8.0,
    "figure.titlesize": 9.5,
    "legend.frameon": False,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.5,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "lines.linewidth": 1.3,
    "lines.markersize": 4.5,
    "axes.formatter.use_mathtext": True,
    "axes.formatter.limits": (-4, 5),
    "mathtext.default": "regular",
    "font.family": "DejaVu Sans",      # has µ, °, σ, κ, –
    "pdf.fonttype": 42,
}

#: colour-blind safe palette (Okabe & Ito 2008, then Tol's muted set), in assignment order
PALETTE = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#882255",
           "#999933", "#44AA99", "#AA4499", "#661100")
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "<", ">", "p", "h", "*")
LINESTYLES = ("-", "--", "-.", ":")


def plotting(part: str = "pyplot"):
    """``matplotlib.<part>`` (pyplot by default; ``""``: matplotlib itself) on the Agg backend (files, no window): what
    the figures of a study's analysis draw with. This package draws outputs, never rows
    (``experiments.codehash.OUTPUT_PACKAGES``): a study module that imports it for its figures keeps matplotlib out of
    its rows' keys, and a new matplotlib redraws the figures (the outputs' fingerprint holds its version) without
    recomputing a row (docs/studies.md)."""
    import matplotlib
    matplotlib.use("Agg")
    return importlib.import_module(f"matplotlib.{part}") if part else matplotlib


@contextlib.contextmanager
def figure_style(**overrides):
    """Context manager: matplotlib (Agg backend) with the report's rcParams (plus ``overrides``)."""
    with plotting("").rc_context({**RC, **overrides}):
        yield


def size(width_fraction: float = 1.0, height_ratio: float = 0.55) -> tuple[float, float]:
    """(width, height) in inches for a figure ``width_fraction`` of the column wide."""
    w = COLUMN_WIDTH_IN * width_fraction
    return w, w * height_ratio


def _registry_order() -> dict[str, int]:
    try:
        import methods
        specs = methods.list_methods()
    except Exception:                                 # style must work without the registry (plugins absent)
        return {}
    by_family: dict[str, list[tuple[bool, str]]] = {}
    for s in specs:   # fitbench's own methods first: installing a plugin never re-colours a built-in method
        by_family.setdefault(s.family, []).append((not getattr(s, "builtin", True), s.id))
    return {mid: k for ids in by_family.values() for k, (_, mid) in enumerate(sorted(ids))}


_ORDER: dict[str, int] | None = None


def method_index(method_id: str) -> int:
    """A stable index for a method id: its rank within its family in the registry (sorted ids, the built-in
    methods before the plugins' so that a plugin never changes a built-in method's colour), so a method keeps its
    colour in every figure; ids outside the registry get an index from a hash of the id."""
    global _ORDER
    if _ORDER is None:
        _ORDER = _registry_order()
    base = method_id.split(" ", 1)[0]
    if base in _ORDER:
        k = _ORDER[base]
        if base != method_id:                          # a parameter variant: same colour, next line style
            k += len(PALETTE) * (1 + int(hashlib.sha1(method_id.encode()).hexdigest(), 16) % 3)
        return k
    return int(hashlib.sha1(method_id.encode()).hexdigest(), 16) % (len(PALETTE) * len(LINESTYLES))


def method_style(method_id: str, *, line: bool = True) -> dict:
    """Keyword arguments for ``ax.plot``: colour, marker and line style of ``method_id`` (the same in every
    figure) and a label (the id without its family prefix)."""
    k = method_index(method_id)
    kw = {"color": PALETTE[k % len(PALETTE)], "marker": MARKERS[k % len(MARKERS)],
          "label": short_label(method_id)}
    if line:
        kw["linestyle"] = LINESTYLES[(k // len(PALETTE)) % len(LINESTYLES)]
    return kw


def category_styles(labels) -> dict[str, dict]:
    """Distinct colour and marker for each of a few categories that are not registry methods (bands,
    scenarios, variants), in the order given: {label: {'color', 'marker', 'label'}}."""
    return {lab: {"color": PALETTE[k % len(PALETTE)], "marker": MARKERS[k % len(MARKERS)], "label": lab}
            for k, lab in enumerate(dict.fromkeys(labels))}


def short_label(method_id: str) -> str:
    """``circle.gauss_newton`` -> ``gauss_newton``; a variant keeps its parameters."""
    return method_id.split(".", 1)[1] if "." in method_id.split(" ", 1)[0] else method_id


def plain_number(value: float, _pos=None) -> str:
    """A tick label as a plain number: 0.001, 0.5, 1, 1.4, 20, 1000 (never 1.4×10⁰)."""
    if value == 0:
        return "0"
    text = f"{value:.6g}".replace("-", "\u2212")         # a typographic minus
    if "e" in text:                                   # very large/small: fall back to a power of ten
        mant, exp = f"{value:.6g}".split("e")
        exp = int(exp)
        return f"$10^{{{exp}}}$" if float(mant) == 1 else f"${mant}\\times10^{{{exp}}}$"
    return text


def plain_log_ticks(ax, axis: str = "both", *, minor: bool | None = None) -> None:
    """Label a log axis with plain numbers. Minor ticks are labelled (1, 2, 5 per decade) when the axis
    spans less than one decade (else a log axis of 1..1.4 would have no label at all), unlabelled otherwise."""
    import numpy as np
    ticker = plotting("ticker")
    FuncFormatter, LogLocator, NullFormatter = ticker.FuncFormatter, ticker.LogLocator, ticker.NullFormatter

    for name in ("x", "y") if axis == "both" else (axis,):
        a = ax.xaxis if name == "x" else ax.yaxis
        if a.get_scale() == "symlog":
            a.set_major_formatter(FuncFormatter(plain_number))
            a.set_minor_formatter(NullFormatter())
            continue
        if a.get_scale() != "log":
            continue
        lo, hi = sorted(ax.get_xlim() if name == "x" else ax.get_ylim())
        narrow = np.log10(hi / lo) < 1.0 if lo > 0 else False
        a.set_major_formatter(FuncFormatter(plain_number))
        label_minor = narrow if minor is None else minor
        if label_minor:
            a.set_minor_locator(LogLocator(subs=(1.0, 1.2, 1.5, 2.0, 3.0, 5.0, 7.0)))
            a.set_minor_formatter(FuncFormatter(plain_number))
        else:
            a.set_minor_formatter(NullFormatter())


def legend_outside(fig, *, axes=None, where: str = "below", ncol: int | None = None, title: str | None = None):
    """One legend for the figure, outside every axes (below or right of them), built from the labelled
    artists of ``axes`` (default all), each label once. Needs constrained layout (the style's default)."""
    handles, labels = [], []
    for ax in axes if axes is not None else fig.axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels and not lab.startswith("_"):
                handles.append(h)
                labels.append(lab)
    if not handles:
        return None
    if where == "right":
        return fig.legend(handles, labels, loc="outside right upper", ncol=ncol or 1, title=title)
    if ncol is None:
        longest = max(len(s) for s in labels)
        ncol = max(1, min(len(labels), int(fig.get_figwidth() * 72 / 8 / (0.62 * longest + 4))))
    return fig.legend(handles, labels, loc="outside lower center", ncol=ncol, title=title)


def smallest_font_pt(fig) -> float:
    """The smallest font size (pt at the printed size) of any visible text in ``fig`` (draws the figure)."""
    fig.canvas.draw()
    sizes = [t.get_fontsize() for t in fig.findobj(lambda o: hasattr(o, "get_fontsize") and hasattr(o, "get_text"))
             if t.get_visible() and t.get_text().strip()]
    return min(sizes) if sizes else float("inf")


def save(fig, path, *, dpi: float | None = None, pdf: bool = True) -> Path:
    """Write ``fig`` atomically to ``path`` (PNG, at ``dpi``; None: the style's ``savefig.dpi``) and, unless
    ``pdf=False``, the same figure as a vector PDF next to it (the report's LaTeX includes the PDF); close the figure.
    The one way a study's figure is saved."""
    from fitbench.plots import save_atomic
    plt = plotting()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        save_atomic(fig, path, dpi=dpi)
        if pdf:
            save_atomic(fig, path.with_suffix(".pdf"))
    finally:
        plt.close(fig)
    return path
