"""``roundness.iso12181``: the registered ISO 12181 evaluation (filter, four reference circles, spectrum)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from methods._registry import register
from methods._result import FitResult
from methods.roundness.evaluation import MIN_POINTS, evaluate, summary_form_error


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

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        if not residuals:  # the per-point arrays go with the residuals
            for k in ("points", "angles", "deviations"):
                d.pop(k, None)
        head = {k: d.pop(k) for k in ("method", "cutoff_upr", "filter_path", "n_points", "form_error", "raw_lsci",
                                      "references", "dominant_lobes", "warnings")}
        return {**head, **d}


@register("roundness.iso12181", kind="convex program", min_points=MIN_POINTS,
          summary="ISO 12181 roundness: ISO 16610-21 Gaussian filter (UPR), RONt/p/v/q about LSCI, MZCI, MICI, MCCI, harmonics",
          reference="ISO 12181-1:2011 clause 3 (parameters, reference circles); ISO 12181-2:2011; "
                    "ISO 16610-21:2011 clause 5 (closed-profile Gaussian filter)")
def iso12181(points, *, cutoff_upr=50.0, reference="all"):
    """Filter the profile at ``cutoff_upr`` UPR (None: unfiltered; 15, 50, 150, 500, 1500 or any positive
    value) and evaluate RONt/RONp/RONv/RONq about ``reference`` (lsci, mzci, mici, mcci or all)."""
    ev = evaluate(points, cutoff_upr=cutoff_upr, reference=reference)
    first = next(iter(ev["references"].values()))
    res_r = np.hypot(ev["points"][:, 0] - first["center"][0], ev["points"][:, 1] - first["center"][1])
    return RoundnessFit(form_error=summary_form_error(ev["references"]), residuals=res_r - first["radius"],
                        converged=ev["converged"], message=ev["message"] + (f"; warning: {ev['warnings'][0]}" if ev["warnings"] else ""),
                        cutoff_upr=ev["cutoff_upr"], filter_path=ev["filter_path"], n_points=ev["n_points"],
                        raw_lsci=ev["raw_lsci"], references=ev["references"], spectrum=ev["spectrum"],
                        dominant_lobes=ev["dominant_lobes"], warnings=ev["warnings"], points=ev["points"],
                        angles=ev["angles"], deviations=ev["deviations"],
                        extra={"order": ev["order"]})
