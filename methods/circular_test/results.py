"""ISO 230-4 circular-test results: :class:`CircularTestFit` and the row columns it declares (the centre G(b) is
evaluated about and its errors against the truth; :mod:`methods.result_base`)."""
from __future__ import annotations

from dataclasses import dataclass, field

from methods.result_base import CENTER_COLUMNS, CENTER_ERROR_COLUMNS, FitResult, center_errors, number_text

__all__ = ["CircularTestFit"]


@dataclass(kw_only=True)
class CircularTestFit(FitResult):
    """ISO 230-4 evaluation of a bidirectional circular test (:func:`methods.circular_test.evaluate`), lengths in
    data units: ``figures`` = {G_cw, G_ccw, G_b, H, F_max, F_min, mean_radial_deviation}; ``center`` is the
    centre G(b) is evaluated about (``center_kind`` 'lsq': least squares, 'mz': minimum zone), ``center_cw`` /
    ``center_ccw`` those of each run; ``residuals`` = the radial deviations of both runs (CW then CCW) from the
    nominal radius about ``F_center``; ``form_error`` = G(b), the bidirectional circular deviation."""

    #: the standard's figures, in the order they are reported
    FIGURES = ("G_cw", "G_ccw", "G_b", "H", "F_max", "F_min", "mean_radial_deviation")

    figures: dict
    center: tuple
    center_cw: tuple
    center_ccw: tuple
    center_kind: str
    F_center: tuple
    F_about: str
    H_about: str
    nominal_radius: float
    n_points: dict
    partial_arc: bool
    arc_deg: dict
    conditions: dict = field(default_factory=dict)

    FAMILY = "circular_test"
    COLUMNS = (*FitResult.COLUMNS, *CENTER_COLUMNS, *CENTER_ERROR_COLUMNS)
    SHAPES = {"center": (2,)}

    def geometry(self) -> dict:
        return {"center_x": self.center[0], "center_y": self.center[1]}

    def truth_errors(self, truth: dict) -> dict:
        return center_errors(self.center, truth)

    def report_lines(self, unit: str = "mm") -> list[tuple[str, str]]:
        f = self.figures
        common = " (over the common arc)" if self.partial_arc else ""
        return [("nominal radius", f"{number_text(self.nominal_radius)} {unit}"),
                (f"centre ({self.center_kind})",
                 f"({number_text(self.center[0])}, {number_text(self.center[1])}) {unit}"),
                ("G CW / CCW", f"{number_text(f['G_cw'])} / {number_text(f['G_ccw'])} {unit}"),
                ("G(b)", f"{number_text(f['G_b'])} {unit}"),
                ("H (1996)", f"{number_text(f['H'])} {unit}{common}"),
                ("F max / F min", f"{number_text(f['F_max'])} / {number_text(f['F_min'])} {unit} ({self.F_about})"),
                ("mean radial deviation", f"{number_text(f['mean_radial_deviation'])} {unit}")]

    def to_dict(self, residuals: bool = True) -> dict:
        d = super().to_dict(residuals)
        figures = d.pop("figures")
        return {"method": d.pop("method"), **figures, "center": d.pop("center"), **d}
