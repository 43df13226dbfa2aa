"""Roundness results (ISO 12181): :class:`RoundnessFit` (:mod:`methods.result_base`). The RONt/RONq figures per
reference circle are in ``references``; the roundness study turns them into its own row columns."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from methods.result_base import FitResult

__all__ = ["RoundnessFit"]


@dataclass(kw_only=True)
class RoundnessFit(FitResult):
    """An ISO 12181 roundness evaluation (lengths in the input's unit, angles in rad).

    ``cutoff_upr`` (None: unfiltered) and ``filter_path`` say how the profile was filtered; ``raw_lsci`` is the
    centre and radius about which the deviations were taken and filtered; ``references`` maps lsci / mzci /
    mici / mcci to {center, radius, RONt, RONp, RONv, RONq, inner_radius, outer_radius, method, converged,
    message}; ``spectrum`` = {upr, amplitude, phase} of the filtered deviations; ``dominant_lobes`` the largest
    harmonics k >= 2; ``points`` the filtered profile (input order); ``angles``/``deviations`` the filtered
    radial deviations about the raw LSCI centre in angle order. ``residuals`` = r_i - R about the first
    reference; ``form_error`` = RONt of MZCI (else of the one reference evaluated)."""

    cutoff_upr: float | None = None
    filter_path: str = ""
    n_points: int = 0
    raw_lsci: dict = field(default_factory=dict)
    references: dict = field(default_factory=dict)
    spectrum: dict = field(default_factory=dict)
    dominant_lobes: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    points: np.ndarray = field(default_factory=lambda: np.empty((0, 2)))
    angles: np.ndarray = field(default_factory=lambda: np.empty(0))
    deviations: np.ndarray = field(default_factory=lambda: np.empty(0))

    FAMILY = "roundness"

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        if not residuals:  # the per-point arrays go with the residuals
            for k in ("points", "angles", "deviations"):
                d.pop(k, None)
        head = {k: d.pop(k) for k in ("method", "cutoff_upr", "filter_path", "n_points", "form_error", "raw_lsci",
                                      "references", "dominant_lobes", "warnings")}
        return {**head, **d}
