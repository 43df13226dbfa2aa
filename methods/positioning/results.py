"""Positioning results (ISO 230-2): :class:`PositioningFit` and the row columns it declares
(:mod:`methods.result_base`)."""
from __future__ import annotations

from dataclasses import dataclass, field

from methods.result_base import Column, FitResult, GEOMETRY

__all__ = ["PositioningFit"]


@dataclass(kw_only=True)
class PositioningFit(FitResult):
    """Positioning of an NC axis: ISO 230-2 ``figures`` (A, E, M, R, B, ...), ``per_target`` arrays,
    and, for the polynomial models, ``polynomial`` = {"up"/"down": {"coefficients" (increasing powers of
    the position, input unit), "covariance", "degree"}}. ``residuals`` = mean deviations minus the model;
    ``form_error`` is not defined (NaN): the standard's figures are in ``figures``."""

    figures: dict = field(default_factory=dict)
    per_target: dict = field(default_factory=dict)
    polynomial: dict = field(default_factory=dict)

    FAMILY = "positioning"
    #: ISO 230-2 defines no form error (NaN)
    COLUMNS = (Column("form_error", "length", GEOMETRY, ""), Column("residual_rms", "length", GEOMETRY, "nonnegative"))

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        figures = d.pop("figures")
        return {"method": d.pop("method"), **figures, **d}
