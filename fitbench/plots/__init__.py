"""Figures of fitbench's tests (circular-test polar plot, positioning plot, roundness polar plot and
spectrum, magnified contouring error): one way to make, write and close them.

:func:`report_figure` yields a new pyplot figure, writes it when the drawing finished (atomically,
:func:`save_atomic`, unless the caller passes its own ``save``) and closes it on every path, so neither an
error while drawing nor a failed write leaves an open figure or a half-written file. matplotlib is
imported on first use. This package imports ``methods`` (results) only: the command line
(:mod:`fitbench.cli`) and the studies' example figures (``experiments``) both use it.
"""
from __future__ import annotations

import contextlib
from pathlib import Path

from methods.files import atomic_path


def ring_label(value_um: float) -> str:
    """A polar plot's ring: its radial deviation signed, and '0 µm' (no sign) for the nominal circle's ring."""
    v = round(float(value_um), 9) + 0.0
    return "0 µm" if v == 0 else f"{v:+g} µm"


def pyplot():
    """matplotlib.pyplot on the non-interactive Agg backend."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


#: metadata that would make a file differ from one save to the next (matplotlib's ``savefig(metadata=...)``:
#: None leaves the entry out), per format: the same figure gives the same bytes (SVG ids are salted too)
#: (PNG carries no date; matplotlib's PostScript always writes one and the file's name)
REPRODUCIBLE_METADATA = {"pdf": {"CreationDate": None}, "svg": {"Date": None}}


def write_figure(fig, path, *, dpi: float | None = None) -> None:
    """Write ``fig`` straight to ``path`` (format from the suffix; ``dpi`` None: matplotlib's ``savefig.dpi``), for a
    caller whose ``path`` is already a temporary (a command's staged output, :func:`fitbench.cli.options.save_figure`;
    :func:`save_atomic` otherwise). No creation date is written (``REPRODUCIBLE_METADATA``): saving the same figure
    again gives the same bytes."""
    path = Path(path)
    fmt = path.suffix.lower().lstrip(".") or "png"
    extra = {} if dpi is None else {"dpi": dpi}
    if fmt in REPRODUCIBLE_METADATA:
        extra["metadata"] = REPRODUCIBLE_METADATA[fmt]
    import matplotlib
    # SVG ids are random unless salted (matplotlib's svg.hashsalt)
    with matplotlib.rc_context({"svg.hashsalt": "fitbench"} if fmt == "svg" else {}):
        fig.savefig(path, format=fmt, **extra)


def save_atomic(fig, path, *, dpi: float | None = None) -> None:
    """Write ``fig`` to ``path`` (:func:`write_figure`) through :func:`methods.files.atomic_path`: the whole figure or
    the old file, through a symlink to its regular target, a FIFO or a device refused; a new file gets the umask's
    mode."""
    with atomic_path(path) as tmp:
        write_figure(fig, tmp, dpi=dpi)


def tight(fig) -> None:
    """``fig.tight_layout()`` for a whole figure; a part of a page (a SubFigure, see ``into``) keeps its layout."""
    if hasattr(fig, "tight_layout"):
        fig.tight_layout()


@contextlib.contextmanager
def report_figure(path, *, dpi: float, save=None, into=None, **figure_kwargs):
    """``with report_figure(path, dpi=120, figsize=(w, h)) as fig:`` draw on ``fig``; when the block ends
    without error the figure is written by ``save(fig, path)`` if given, else :func:`save_atomic`; the figure
    is closed on every path. With ``into`` (a matplotlib SubFigure, part of a page such as the one-page
    report) the drawing goes there and nothing is written or closed."""
    if into is not None:
        yield into
        return
    plt = pyplot()
    fig = plt.figure(**figure_kwargs)
    try:
        yield fig
        if save is not None:
            save(fig, path)
        else:
            save_atomic(fig, path, dpi=dpi)
    finally:
        plt.close(fig)
