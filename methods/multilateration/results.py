"""Multilateration results: :class:`MultilaterationFit` (:mod:`methods.result_base`)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from methods.result_base import FitResult

__all__ = ["MultilaterationFit"]


@dataclass(kw_only=True)
class MultilaterationFit(FitResult):
    """Multilateration: ``stations`` (K, 4) = [x, y, z, L] per station in input order (given or located),
    ``points`` (N, 3) actual positions and ``volumetric_errors`` = points - nominal, one row per nominal point in
    order of first appearance; ``condition_numbers`` of every linear system solved (SVD and the paper's
    Theorem 1 lower estimate); ``residuals`` (N, K) = ||X_a,i - LT(k)|| - (L_k + P_i(k)) (NaN: not measured);
    ``form_error`` = the largest volumetric error magnitude. ``frame`` says which frame stations and points are
    in: ``"measurement"`` (that of the given stations or of the nominal points the stations were located
    from) or ``"nominal"`` (a solution defined up to a rigid motion, moved by the least-squares rigid motion
    that aligns its points with the nominal ones)."""

    station_ids: list
    stations: np.ndarray
    points: np.ndarray
    volumetric_errors: np.ndarray
    condition_numbers: dict = field(default_factory=dict)
    frame: str = "measurement"

    FAMILY = "multilateration"
    MISSING_RESIDUALS = True  # NaN: a length not measured (see above)

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        head = {k: d.pop(k) for k in ("method", "station_ids", "stations", "points", "volumetric_errors",
                                      "condition_numbers")}
        return {**head, **d}
