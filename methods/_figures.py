"""Figures of the method reports (circular-test polar plot, positioning plot): one way to make, write
and close them. :func:`report_figure` yields a new pyplot figure, writes it when the drawing finished
(atomically, :func:`save_atomic`, unless the caller passes its own ``save``) and closes it on every path,
so neither an error while drawing nor a failed write leaves an open figure or a half-written file.
matplotlib is imported on first use (``import methods`` stays light)."""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path


def pyplot():
    """matplotlib.pyplot on the non-interactive Agg backend."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_atomic(fig, path, *, dpi: float | None = None) -> None:
    """Write ``fig`` to ``path`` (format from the suffix; ``dpi`` None: matplotlib's ``savefig.dpi``) through a
    temporary file in the same folder and ``os.replace``: readers see the old file or the whole new one, never
    a partial one, and a failed write leaves no temporary file. The one atomic figure writer of fitbench."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        fig.savefig(tmp, format=path.suffix.lower().lstrip(".") or "png", **({} if dpi is None else {"dpi": dpi}))
        os.chmod(tmp, 0o644)  # mkstemp makes it private; a figure is for reading
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


@contextlib.contextmanager
def report_figure(path, *, dpi: float, save=None, **figure_kwargs):
    """``with report_figure(path, dpi=120, figsize=(w, h)) as fig:`` draw on ``fig``; when the block ends
    without error the figure is written by ``save(fig, path)`` if given, else :func:`save_atomic`; the figure
    is closed on every path."""
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
