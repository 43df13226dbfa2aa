"""Study ``ellipse_angle``: scatter of the fitted angle of a near-circular ellipse against a - b.

For each a - b, noisy copies of the ellipse are fitted; the RMS angle error is compared with the
first-order (Gauss–Markov) prediction sigma * sqrt([(J^T J)^-1]_theta,theta) from the orthogonal-
distance Jacobian at the truth (``methods.ellipse.parameter_covariance``), which grows like
sigma / ((a - b) sqrt(N / 2)): the angle of a near-circle is ill-conditioned.
"""
from __future__ import annotations

import json

import numpy as np
import pandas as pd

from datasets.synthetic import ellipse_points
from methods.ellipse import parameter_covariance
from experiments.study import Analysis, Figure, Study, Table


def predicted_angle_sd(points, p, sigma):
    """First-order s.d. of the fitted angle [rad]."""
    return float(np.sqrt(parameter_covariance(points, p, sigma)[4, 4]))


def angle_table(df, params) -> pd.DataFrame:
    """Per a - b: the predicted s.d. and each method's RMS angle error [deg] (converged fits)."""
    sigma, theta = float(params["noise"]), np.radians(params["angle_deg"])
    rows = []
    for axes_json, g in df.groupby("data_semi_axes", sort=False):
        a, b = json.loads(axes_json)
        exact = ellipse_points(params["center"], (a, b), theta, params["n"])
        pred = predicted_angle_sd(exact, np.array([*params["center"], a, b, theta]), sigma)
        row = {"a_minus_b_mm": a - b, "predicted_sd_deg": float(np.degrees(pred))}
        for m, gm in g.groupby("method", sort=False):
            ok = gm[gm["status"] == "ok"]["angle_error"].astype(float)
            row[f"rms_error_deg {m}"] = float(np.degrees(np.sqrt(np.mean(ok ** 2)))) if len(ok) else float("nan")
        rows.append(row)
    return pd.DataFrame(rows)


def figure(table, target, sigma, n):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from experiments.render import style
    diffs = table["a_minus_b_mm"].to_numpy() * 1e3
    with style.figure_style():
        fig, ax = plt.subplots(figsize=style.size(0.8, 0.6))
        ax.loglog(diffs, table["predicted_sd_deg"], "k-", label="first order: σ·sqrt([(JᵀJ)⁻¹]θθ)")
        for key in [k for k in table.columns if k.startswith("rms_error_deg")]:
            m = key.split(" ", 1)[1]
            kw = style.method_style(m)
            ax.loglog(diffs, table[key], marker=kw["marker"], color=kw["color"], linestyle="none", mfc="none",
                      label=f"{kw['label']} (RMS)")
        ax.axvline(22.1, color="0.6", ls=":", label="paper's ellipse (22.1 µm)")
        ax.set_xlabel(f"a − b [µm]  (N = {n}, σ = {sigma * 1e3:g} µm)")
        ax.set_ylabel("angle error [°]")
        style.plain_log_ticks(ax, "both")
        style.legend_outside(fig, ncol=2)
        style.save(fig, target / "angle_conditioning.png")
        plt.close(fig)


class EllipseAngleStudy(Study):
    """The ``ellipse_angle`` study (see the module's docstring)."""

    values = None  # its analysis names its values

    def analyse(self, df, cfg, target, log):
        """RMS angle error against a - b with the first-order prediction; findings: how close each method is to it."""
        params = cfg["datasets"][0]["params"]
        table = angle_table(df, params)
        log(table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
        figure(table, target, params["noise"], params["n"])
        ratio = {c.split(" ", 1)[1]: table[c] / table["predicted_sd_deg"] for c in table.columns if c.startswith("rms")}
        values = {"ratio_to_prediction": {m: [float(v) for v in r] for m, r in ratio.items()},
                  "a_minus_b_mm": [float(v) for v in table["a_minus_b_mm"]],
                  "largest_predicted_sd_deg": float(table["predicted_sd_deg"].max()),
                  "smallest_predicted_sd_deg": float(table["predicted_sd_deg"].min())}
        reps = int(df.groupby(["data_semi_axes", "method"]).size().max())
        findings = (f"The first-order prediction of the angle's scatter grows from {values['smallest_predicted_sd_deg']:.3g}° "
                    f"at a − b = {table['a_minus_b_mm'].max():.4g} mm to {values['largest_predicted_sd_deg']:.3g}° at "
                    f"a − b = {table['a_minus_b_mm'].min():.4g} mm. ")
        findings += "; ".join(f"{m}: RMS error / prediction between {r.min():.2f} and {r.max():.2f}"
                              for m, r in ratio.items())
        findings += f" ({reps} noisy copies per a − b, so a ratio is known to about ±{100 / np.sqrt(2 * reps):.0f} %)."
        shown = table.rename(columns={"a_minus_b_mm": "a - b [mm]", "predicted_sd_deg": "predicted s.d. [°]",
                                      **{c: f"{c.split(' ', 1)[1]} RMS [°]" for c in table.columns if c.startswith("rms")}})
        caption = (f"RMS error of the fitted axis angle [°] against the axis difference a - b, and the first-order "
                   f"prediction sigma sqrt([(J^T J)^-1]_theta,theta); synthetic near-circular ellipses, a = 299.0243 mm, N = {params['n']}, "
                   f"sigma = {params['noise'] * 1e3:g} µm per coordinate, {reps} repetitions")
        fig = Figure(caption="RMS error of the fitted axis angle [°] against a − b [µm] on synthetic near-circular "
                             "ellipses, with the first-order prediction: the angle of a near-circle is ill-conditioned",
                     file="angle_conditioning.png")
        return Analysis(tables=[Table(caption=caption, data=shown, unit="°", digits=4)], figures=[fig], values=values,
                        findings=findings)
