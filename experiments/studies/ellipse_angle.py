"""Study ``ellipse_angle``: scatter of the fitted angle of a near-circular ellipse against a - b.

For each a - b, noisy copies of the ellipse are fitted; the RMS angle error is compared with the
first-order (Gauss–Markov) prediction sigma * sqrt([(J^T J)^-1]_theta,theta) from the orthogonal-
distance Jacobian at the truth, which grows like sigma / ((a - b) sqrt(N / 2)): the angle of a
near-circle is ill-conditioned.
"""
from __future__ import annotations

import json

import numpy as np

from datasets.synthetic import ellipse_points
from methods.ellipse._geometry import orthogonal_residuals
from methods.ellipse.orthogonal import distance_jacobian
from experiments.study import save_figure


def predicted_angle_sd(points, p, sigma):
    _, phi = orthogonal_residuals(points[:, 0], points[:, 1], p)
    J = distance_jacobian(points[:, 0], points[:, 1], p, phi)
    return float(sigma * np.sqrt(np.linalg.inv(J.T @ J)[4, 4]))


def finalize(df, cfg, target, log):
    params = cfg["datasets"][0]["params"]
    sigma, theta = float(params["noise"]), np.radians(params["angle_deg"])
    summary = []
    log(f"  {'a - b [mm]':>10} {'predicted [deg]':>15} " + " ".join(f"{m:>24}" for m in df["method"].unique()))
    for axes_json, g in df.groupby("data_semi_axes", sort=False):
        a, b = json.loads(axes_json)
        exact = ellipse_points(params["center"], (a, b), theta, params["n"])
        pred = predicted_angle_sd(exact, np.array([*params["center"], a, b, theta]), sigma)
        row = {"a_minus_b_mm": a - b, "predicted_sd_deg": float(np.degrees(pred))}
        for m, gm in g.groupby("method", sort=False):
            ok = gm[gm["status"] == "ok"]["angle_error"].astype(float)
            row[f"rms_error_deg {m}"] = float(np.degrees(np.sqrt(np.mean(ok ** 2)))) if len(ok) else float("nan")
        summary.append(row)
        log(f"  {a - b:10.4f} {row['predicted_sd_deg']:15.4f} "
            + " ".join(f"{v:24.4f}" for k, v in row.items() if k.startswith("rms")))
    figure(summary, target, sigma, params["n"], params["semi_axes"] if "semi_axes" in params else None)
    return {"summary": summary, "figure": "angle_conditioning.png"}


def figure(summary, target, sigma, n, _):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    diffs = np.array([s["a_minus_b_mm"] for s in summary]) * 1e3
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.loglog(diffs, [s["predicted_sd_deg"] for s in summary], "k-", label="first order: σ·sqrt([(JᵀJ)⁻¹]θθ)")
    for key, marker in zip([k for k in summary[0] if k.startswith("rms_error_deg")], "os"):
        ax.loglog(diffs, [s[key] for s in summary], marker, mfc="none", label=key.split(" ", 1)[1] + " (RMS)")
    ax.axvline(22.1, color="0.6", ls=":", label="paper's ellipse (22.1 µm)")
    ax.set_xlabel(f"a − b [µm]  (a = 299.0243 mm, N = {n}, σ = {sigma * 1e3:g} µm per coordinate)")
    ax.set_ylabel("angle error [deg]")
    ax.set_title("Angle of a near-circle: error ∝ σ / ((a − b)·sqrt(N/2))")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    target.mkdir(parents=True, exist_ok=True)
    save_figure(fig, target / "angle_conditioning.png", dpi=120)
    plt.close(fig)


def report_tables(folder, f):
    """The tables a reader wants from this study (moved here from the report, which names no study)."""
    import pandas as pd

    from experiments.study import Table
    out = []
    out.append(("Angle of a near-circle: RMS angle error [deg] against a - b, and the first-order prediction",
                pd.DataFrame(f.get("summary", [])).round(4)))
    return [Table(caption=c, data=t) for c, t in out if t is not None and len(t)]
