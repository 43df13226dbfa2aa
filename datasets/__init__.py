"""fitbench data sets: the published sets with their metadata, synthetic generators with known
truth, and the reader for users' files.

This package is fitbench's ``datasets`` (not Hugging Face's): ``datasets.FITBENCH`` is True.
"""
from __future__ import annotations

import builtins
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from datasets.io import DataFileError, read_points

FITBENCH = True
PUBLISHED_DIR = Path(__file__).resolve().parent / "published"


@dataclass(frozen=True)
class Dataset:
    """Points (N, 2) with their metadata (citation, units, published results, notes)."""

    name: str
    points: np.ndarray = field(repr=False)
    meta: dict = field(default_factory=dict, repr=False)

    @property
    def published(self) -> dict:
        return self.meta.get("published", {}).get("values", {})


def list() -> builtins.list[str]:  # noqa: A001  (the documented API name)
    """Names of the published data sets shipped with fitbench."""
    return sorted(p.stem for p in PUBLISHED_DIR.glob("*.csv"))


def load(name: str, *, drop_repeated_closing_point: bool = False) -> Dataset:
    """Load a published data set by name, exactly as published.

    A closed profile whose last point repeats the first (``meta['repeated_closing_point']``) keeps
    the repeat unless ``drop_repeated_closing_point`` is true: the repeat counts twice in a least-squares fit.
    """
    names = list()
    if name not in names:
        import difflib
        close = difflib.get_close_matches(name, names, n=3)
        hint = f"; did you mean {' or '.join(close)}?" if close else f"; known: {', '.join(names)}"
        raise DataFileError(f"unknown data set {name!r}{hint}")
    points = read_points(PUBLISHED_DIR / f"{name}.csv")
    meta = json.loads((PUBLISHED_DIR / f"{name}.json").read_text(encoding="utf-8"))
    if drop_repeated_closing_point and meta.get("repeated_closing_point"):
        if not np.array_equal(points[0], points[-1]):
            raise DataFileError(f"{name}: metadata says the last point repeats the first, but it does not")
        points = points[:-1]
        meta = {**meta, "n_points": len(points), "variant": "repeated closing point dropped"}
    return Dataset(name=name, points=points, meta=meta)


def points_from(source) -> tuple[str, np.ndarray]:
    """Points from a path or a published data set name (a name wins when no such file exists)."""
    path = Path(source)
    if not path.exists() and str(source) in list():
        return str(source), load(str(source)).points
    return str(source), read_points(path)


__all__ = ["Dataset", "DataFileError", "list", "load", "read_points", "points_from", "FITBENCH"]
