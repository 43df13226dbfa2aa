"""Study ``ellipse_angle``: scatter of the fitted angle of a near-circular ellipse against a - b.

For each a - b, ``repetitions`` noisy copies of the ellipse are fitted; the standard deviation of
the angle error is compared with the first-order (Gauss–Markov) prediction
sigma * sqrt([(J^T J)^-1]_theta,theta) from the orthogonal-distance Jacobian at the truth, which
grows like sigma / ((a - b) sqrt(N / 2)): the angle of a near-circle is ill-conditioned.
"""
from __future__ import annotations

import json

import numpy as np

import methods
from datasets.synthetic import ellipse_points
from experiments.studies.published_circle import safe_fit
from methods.ellipse._geometry import orthogonal_residuals
from methods.ellipse.orthogonal import distance_jacobian


def predicted_angle_sd(points, p, sigma):
    _, phi = orthogonal_residuals(points[:, 0], points[:, 1], p)
    J = distance_jacobian(points[:, 0], points[:, 1], p, phi)
    return float(sigma * np.sqrt(np.linalg.inv(J.T @ J)[4, 4]))


def run(cfg: dict, log=print):
    rows = []
    root = np.random.SeedSequence(int(cfg["seed"]))
    streams = root.spawn(len(cfg["a_minus_b_mm"]))
    a = float(cfg["semi_major"])
    theta = np.radians(float(cfg["angle_deg"]))
    sigma = float(cfg["noise_mm"])
    n = int(cfg["n_points"])
    summary = []
    log(f"  {'a - b [mm]':>10} {'predicted sd [deg]':>18} " + " ".join(f"{m:>24}" for m in cfg["_methods"]))
    for diff, stream in zip(cfg["a_minus_b_mm"], streams):
        b = a - float(diff)
        truth = dict(center=tuple(cfg["center"]), semi_axes=(a, b), angle=theta)
        exact = ellipse_points(n=n, **truth)
        pred = predicted_angle_sd(exact, np.array([*cfg["center"], a, b, theta]), sigma)
        rng = np.random.default_rng(stream)
        errors = {m: [] for m in cfg["_methods"]}
        for rep in range(int(cfg["repetitions"])):
            pts = ellipse_points(n=n, noise=sigma, rng=rng, **truth)
            for mid in cfg["_methods"]:
                res, problem = safe_fit(mid, pts, {})
                if res is None or not res.converged:
                    rows.append({"study": cfg["name"], "a_minus_b_mm": diff, "repetition": rep, "method": mid,
                                 "status": "error" if res is None else "not converged",
                                 "message": problem or res.message})
                    continue
                err = (res.angle - theta + np.pi / 2) % np.pi - np.pi / 2
                errors[mid].append(err)
                rows.append({"study": cfg["name"], "a_minus_b_mm": diff, "repetition": rep, "method": mid,
                             "status": "ok", "angle_error_rad": err, "predicted_sd_rad": pred,
                             "a_error_mm": res.semi_axes[0] - a, "b_error_mm": res.semi_axes[1] - b})
        sds = {m: float(np.sqrt(np.mean(np.square(e)))) if e else float("nan") for m, e in errors.items()}
        summary.append({"a_minus_b_mm": diff, "predicted_sd_deg": float(np.degrees(pred)),
                        **{f"rms_error_deg {m}": float(np.degrees(v)) for m, v in sds.items()}})
        log(f"  {diff:10.4f} {np.degrees(pred):18.4f} " + " ".join(f"{np.degrees(v):24.4f}" for v in sds.values()))
    return rows, {"summary": summary, "figure": "angle_conditioning.png"}


def figure(rows: list[dict], findings: dict, target) -> None:
    """Log-log plot of the angle scatter against a - b with the first-order prediction."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    summary = findings["summary"]
    diffs = np.array([s["a_minus_b_mm"] for s in summary]) * 1e3
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.loglog(diffs, [s["predicted_sd_deg"] for s in summary], "k-", label="first order: σ·sqrt([(JᵀJ)⁻¹]θθ)")
    for key, marker in zip([k for k in summary[0] if k.startswith("rms_error_deg")], "os"):
        ax.loglog(diffs, [s[key] for s in summary], marker, mfc="none", label=key.split(" ", 1)[1] + " (RMS)")
    ax.axvline(22.1, color="0.6", ls=":", label="paper's ellipse (22.1 µm)")
    ax.set_xlabel("a − b [µm]  (a = 299.0243 mm, N = 3358, σ = 1 µm per coordinate)")
    ax.set_ylabel("angle error [deg]")
    ax.set_title("Angle of a near-circle: error ∝ σ / ((a − b)·sqrt(N/2))")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(target / "angle_conditioning.png", dpi=120)
    plt.close(fig)
