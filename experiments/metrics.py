"""Benchmark metrics: computed from a result and the truth, never inside a method."""
from __future__ import annotations

import numpy as np


def _angle_error(a, b):
    return float((a - b + np.pi / 2) % np.pi - np.pi / 2)


def metrics(result, truth: dict | None) -> dict:
    """Columns for one fit: form error, residual RMS, the fitted geometry, and errors against the
    truth where known (centre distance and signed components, radius, axes, angle)."""
    row = {"form_error": result.form_error,
           "residual_rms": float(np.sqrt(np.mean(np.square(result.residuals)))) if len(result.residuals) else np.nan}
    if hasattr(result, "center"):
        row["center_x"], row["center_y"] = result.center
    if hasattr(result, "radius"):
        row["radius"] = result.radius
    if hasattr(result, "semi_axes"):
        row["semi_axis_a"], row["semi_axis_b"] = result.semi_axes
        row["angle"] = result.angle
    if hasattr(result, "inner_radius"):
        row["inner_radius"], row["outer_radius"] = result.inner_radius, result.outer_radius
    if not truth:
        return row
    if "center" in truth and hasattr(result, "center"):
        dx = result.center[0] - truth["center"][0]
        dy = result.center[1] - truth["center"][1]
        row.update(center_error_x=dx, center_error_y=dy, center_error=float(np.hypot(dx, dy)))
    if "radius" in truth and hasattr(result, "radius"):
        row["radius_error"] = result.radius - truth["radius"]
    if "semi_axes" in truth and hasattr(result, "semi_axes"):
        row["semi_axis_a_error"] = result.semi_axes[0] - truth["semi_axes"][0]
        row["semi_axis_b_error"] = result.semi_axes[1] - truth["semi_axes"][1]
        row["angle_error"] = _angle_error(result.angle, truth["angle"])
    return row
