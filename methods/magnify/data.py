"""Input of the magnification methods and the continuity metric."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from methods._errors import InvalidInputError
from methods._lazy import lazy_module

shapely = lazy_module("shapely")


@dataclass(frozen=True)
class MagnifyInput:
    """A reference trajectory (polyline; arcs given as fine polylines) and a measured trajectory
    (points in order)."""

    reference: np.ndarray  # (M, 2)
    measured: np.ndarray   # (N, 2)

    @property
    def line(self) -> shapely.LineString:
        return shapely.LineString(self.reference)


def validate(data, method_id="") -> MagnifyInput:
    """The registry's validator for the magnify family: a MagnifyInput or (reference, measured)."""
    if isinstance(data, tuple) and len(data) == 2:
        data = MagnifyInput(np.asarray(data[0], float), np.asarray(data[1], float))
    if not isinstance(data, MagnifyInput):
        raise InvalidInputError(f"{method_id}: magnify methods take MagnifyInput(reference, measured) or a pair of arrays")
    ref, meas = np.asarray(data.reference, float), np.asarray(data.measured, float)
    for arr, name in ((ref, "reference"), (meas, "measured trajectory")):
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise InvalidInputError(f"{method_id}: the {name} must be an (N, 2) array of x, y; got shape {arr.shape}")
        if not np.isfinite(arr).all():
            raise InvalidInputError(f"{method_id}: the {name} contains NaN or inf")
    if len(meas) < 2:
        raise InvalidInputError(f"{method_id}: the measured trajectory needs at least 2 points, got {len(meas)}")
    if len(ref) < 2:
        raise InvalidInputError(f"{method_id}: the reference trajectory needs at least 2 points, got {len(ref)}")
    keep = np.concatenate([[True], np.any(np.diff(ref, axis=0) != 0, axis=1)])  # drop repeated vertices
    ref = ref[keep]
    if len(ref) < 2 or shapely.LineString(ref).length == 0:
        raise InvalidInputError(f"{method_id}: the reference trajectory is degenerate (zero length)")
    return MagnifyInput(ref, meas)


def continuity(magnified: np.ndarray, measured: np.ndarray, eta: float) -> float:
    """Largest step of the magnified trajectory relative to eta times the largest measured step:
    about 1 (or less) for a continuous magnification, large where it jumps."""
    step_mag = np.hypot(*np.diff(magnified, axis=0).T)
    step_meas = np.hypot(*np.diff(measured, axis=0).T)
    return float(np.nanmax(step_mag) / (abs(eta) * step_meas.max()))


def self_intersections(points: np.ndarray) -> int:
    """Number of crossings between non-adjacent segments of a polyline (loops of a magnified plot)."""
    pts = points[np.isfinite(points).all(axis=1)]
    if len(pts) < 4:
        return 0
    segs = shapely.linestrings(np.stack([pts[:-1], pts[1:]], axis=1))
    tree = shapely.STRtree(segs)
    i, j = tree.query(segs, predicate="intersects")
    return int(np.sum(j > i + 1))
