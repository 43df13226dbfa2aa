"""Ellipse-specific input checks (after the shared :func:`methods._validation.validate_points`)."""
from __future__ import annotations

import numpy as np

from methods._errors import InvalidInputError


def count_distinct(points: np.ndarray, enough: int) -> int:
    """The number of distinct points, counted up to ``enough`` (exact equality; the first 64 rows decide
    in the common case, the whole set is sorted only when they hold fewer than ``enough`` distinct points)."""
    head = np.ascontiguousarray(points[:64], dtype=np.float64) + 0.0  # + 0.0 makes -0.0 equal to 0.0
    n_head = len(np.unique(head.view(np.complex128)))
    if n_head >= enough or len(points) <= 64:
        return n_head
    pts = np.ascontiguousarray(points, dtype=np.float64) + 0.0  # the whole set only when the head is not enough
    return len(np.unique(pts.view(np.complex128)))


def check_distinct_points(points: np.ndarray, minimum: int, method: str) -> None:
    """Refuse fewer than ``minimum`` distinct points: duplicates add no information, and a conic through
    fewer than 5 distinct points is not determined (any fit would be an arbitrary member of a family)."""
    n = count_distinct(points, minimum)
    if n < minimum:
        raise InvalidInputError(f"{method}: needs at least {minimum} distinct points, got {n} distinct among "
                                f"{len(points)} (repeated points do not determine an ellipse)")
