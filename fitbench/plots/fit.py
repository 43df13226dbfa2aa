"""A quick look at one fit (``fitbench fit ... --plot``): the points with the fitted circle or ellipse, and the
residuals (µm) against the polar angle about the fitted centre."""
from __future__ import annotations

import numpy as np

from fitbench.plots import report_figure


def fitted_curve(result, family: str, n: int = 721) -> np.ndarray | None:
    """(n, 2) points of the fitted circle or ellipse (mm), None for another family."""
    t = np.linspace(0.0, 2 * np.pi, n)
    cx, cy = result.center
    if family == "circle":
        return np.c_[cx + result.radius * np.cos(t), cy + result.radius * np.sin(t)]
    if family == "ellipse":
        a, b = result.semi_axes
        c, s = np.cos(result.angle), np.sin(result.angle)
        x, y = a * np.cos(t), b * np.sin(t)
        return np.c_[cx + c * x - s * y, cy + s * x + c * y]
    return None


def plot_fit(points, result, family: str, path, title: str = "", *, save=None) -> None:
    """Left: the points and the fitted curve (mm, equal axes); right: the residuals (µm) against the angle
    about the fitted centre (°)."""
    points = np.asarray(points, dtype=float)
    with report_figure(path, dpi=120, save=save, figsize=(11, 4.8)) as fig:
        ax = fig.add_subplot(1, 2, 1)
        ax.plot(points[:, 0], points[:, 1], ".", ms=2, color="k", label=f"{len(points)} points")
        curve = fitted_curve(result, family)
        if curve is not None:
            ax.plot(curve[:, 0], curve[:, 1], color="tab:red", lw=1, label=result.method)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.legend(fontsize=8, loc="upper right")
        ax.set_title(title, fontsize=9)
        bx = fig.add_subplot(1, 2, 2)
        res = np.asarray(result.residuals, dtype=float) if result.residuals is not None else None
        if res is not None and res.shape[0] == points.shape[0]:
            ang = np.degrees(np.arctan2(points[:, 1] - result.center[1], points[:, 0] - result.center[0])) % 360
            order = np.argsort(ang)
            bx.plot(ang[order], res[order] * 1e3, lw=0.7, color="k")
            bx.axhline(0.0, color="0.6", lw=0.6)
            bx.set_xlim(0, 360)
            bx.set_xticks(np.arange(0, 361, 45))
        bx.set_xlabel("angle about the fitted centre [°]")
        bx.set_ylabel("residual [µm]")
        bx.set_title(f"form error {result.form_error * 1e3:.4g} µm", fontsize=9)
        fig.tight_layout()
