"""Magnified contouring-error results: :class:`MagnifyFit` (:mod:`methods.result_base`)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from methods.result_base import FitResult

__all__ = ["MagnifyFit"]


@dataclass(kw_only=True)
class MagnifyFit(FitResult):
    """A magnified contouring-error trajectory: ``points`` (one per measured point, in order),
    ``reference_points`` r~(k); ``residuals`` = contouring errors |p - r~|; ``form_error`` = the largest."""

    points: np.ndarray
    reference_points: np.ndarray

    FAMILY = "magnify"

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        return {"method": d.pop("method"), "points": d.pop("points"), **d}
