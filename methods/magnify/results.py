"""Magnified contouring-error results: :class:`MagnifyFit` (:mod:`methods.result_base`)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from methods.result_base import FitResult

__all__ = ["MagnifyFit"]


@dataclass(kw_only=True)
class MagnifyFit(FitResult):
    """A magnified contouring-error trajectory (Ibaraki & Matsubara 2009): ``points`` p~(k) = r~(k) + eta (p(k) -
    r~(k)) (one per measured point, in order) and ``reference_points`` r~(k); ``residuals`` = the contouring
    errors, each measured point's distance from the reference path, for every method; ``form_error`` = the
    largest. |p - r~| equals the contouring error only where r~ is the nearest point of the path (``nearest``);
    its largest is ``extra['max_magnified_distance']``."""

    points: np.ndarray
    reference_points: np.ndarray

    FAMILY = "magnify"

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        return {"method": d.pop("method"), "points": d.pop("points"), **d}
