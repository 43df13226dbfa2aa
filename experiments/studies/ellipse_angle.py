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
    """Per a - b: the predicted s.d. and each method's RMS angle error [deg] and its number of converged fits."""
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
            row[f"n_ok {m}"] = len(ok)
        rows.append(row)
    return pd.DataFrame(rows)


def ratio_standard_error(n):
    """Monte-Carlo standard error of RMS / prediction over ``n`` copies if the prediction holds: n (RMS / s.d.)^2
    is chi-square with n degrees of freedom, so the ratio's s.d. is 1 / sqrt(2 n) to first order."""
    return 1.0 / np.sqrt(2.0 * np.asarray(n, dtype=float))


def consistency_text(m, ratio, se, a_minus_b_mm) -> str:
    """'m: RMS error / prediction 0.95 to 1.07, within 2 standard errors of 1 at 7 of 8 a − b; 2.4 s.e. above at
    a − b = 1 mm (1.07)': how many rows lie within 2 Monte-Carlo standard errors of the prediction, naming each
    that does not (by how many standard errors: 1 row in 20 by chance beyond 2, 1 in 370 beyond 3)."""
    z = (np.asarray(ratio) - 1.0) / np.asarray(se)
    ok = np.abs(z) <= 2
    text = (f"{m}: RMS error / prediction {np.nanmin(ratio):.2f} to {np.nanmax(ratio):.2f}, within 2 standard errors of 1 "
            f"at {int(ok.sum())} of {len(z)} a − b")
    off = [f"{abs(zi):.1f} s.e. {'above' if zi > 0 else 'below'} at a − b = {d:.4g} mm ({r:.2f})"
           for zi, r, d in zip(z, ratio, a_minus_b_mm) if not abs(zi) <= 2]
    return text + ("; " + ", ".join(off) if off else "")


def figure(table, target, sigma, n, reps=None):
    """RMS angle error and the prediction against a − b (top); RMS / prediction with ± 2 Monte-Carlo standard errors
    (bottom: the scatter the log scale above hides)."""
    from experiments.render import style
    plt = style.plotting()
    diffs = table["a_minus_b_mm"].to_numpy() * 1e3
    keys = [k for k in table.columns if k.startswith("rms_error_deg")]
    with style.figure_style():
        fig, (ax, rx) = plt.subplots(2, 1, figsize=style.size(0.8, 0.95), sharex=True, height_ratios=[2, 1])
        ax.loglog(diffs, table["predicted_sd_deg"], "k-", label="first order: σ·sqrt([(JᵀJ)⁻¹]θθ)")
        rx.axhline(1.0, color="k", lw=1)
        if reps:
            band = 2 * float(ratio_standard_error(reps))
            rx.axhspan(1 - band, 1 + band, color="0.88", lw=0, label=f"1 ± 2 standard errors ({reps} copies)")
        for j, key in enumerate(keys):
            m = key.split(" ", 1)[1]
            kw = style.method_style(m)
            ax.loglog(diffs, table[key], marker=kw["marker"], color=kw["color"], linestyle="none", mfc="none",
                      label=f"{kw['label']} (RMS)")
            ratio = table[key] / table["predicted_sd_deg"]
            err = 2 * ratio_standard_error(table[f"n_ok {m}"]) if f"n_ok {m}" in table else None
            shift = 1.0 + 0.06 * (j - (len(keys) - 1) / 2)     # side by side, not on top of each other
            rx.errorbar(diffs * shift, ratio, yerr=err, marker=kw["marker"], color=kw["color"], linestyle="none",
                        mfc="none", capsize=2)
        for a in (ax, rx):
            a.axvline(22.1, color="0.6", ls=":", label="paper's ellipse (22.1 µm)" if a is ax else None)
        rx.set_xscale("log")
        rx.set_xlabel(f"a − b [µm]  (N = {n}, σ = {sigma * 1e3:g} µm)")
        ax.set_ylabel("angle error [°]")
        rx.set_ylabel("RMS / prediction")
        style.plain_log_ticks(ax, "both")
        style.plain_log_ticks(rx, "x")
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
        reps = int(df.groupby(["data_semi_axes", "method"]).size().max())
        figure(table, target, params["noise"], params["n"], reps)
        names = [c.split(" ", 1)[1] for c in table.columns if c.startswith("rms")]
        ratio = {m: table[f"rms_error_deg {m}"] / table["predicted_sd_deg"] for m in names}
        se = {m: pd.Series(ratio_standard_error(table[f"n_ok {m}"]), index=table.index) for m in names}
        values = {"ratio_to_prediction": {m: [float(v) for v in r] for m, r in ratio.items()},
                  "ratio_standard_error": {m: [float(v) for v in s] for m, s in se.items()},
                  "a_minus_b_mm": [float(v) for v in table["a_minus_b_mm"]],
                  "largest_predicted_sd_deg": float(table["predicted_sd_deg"].max()),
                  "smallest_predicted_sd_deg": float(table["predicted_sd_deg"].min())}
        findings = (f"The first-order prediction of the angle's scatter grows from {values['smallest_predicted_sd_deg']:.3g}° "
                    f"at a − b = {table['a_minus_b_mm'].max():.4g} mm to {values['largest_predicted_sd_deg']:.3g}° at "
                    f"a − b = {table['a_minus_b_mm'].min():.4g} mm. ")
        # methods whose ratios read alike (halir_flusser and orthogonal agree to 1e-5 here) share one clause
        said: dict = {}
        for m in names:
            said.setdefault(consistency_text("", ratio[m], se[m], table["a_minus_b_mm"]), []).append(m)
        findings += "; ".join(" and ".join(ms) + text for text, ms in said.items())
        findings += (f" ({reps} noisy copies per a − b: one Monte-Carlo standard error of a ratio is "
                     f"±{100 / np.sqrt(2 * reps):.1f} % if the prediction holds, so about 1 row in 20 lies beyond 2 by chance).")
        shown = table[["a_minus_b_mm", "predicted_sd_deg"]].rename(columns={"a_minus_b_mm": "a - b [mm]",
                                                                            "predicted_sd_deg": "predicted s.d. [°]"})
        for m in names:
            shown[f"{m} RMS [°]"] = table[f"rms_error_deg {m}"]
        for m in names:
            shown[f"{m} ratio"] = ratio[m]
        one_se = all(se[m].equals(se[names[0]]) for m in names)
        for m in (names[:1] if one_se else names):
            shown["ratio s.e." if one_se else f"{m} ratio s.e."] = se[m]
        caption = (f"RMS error of the fitted axis angle [°] against the axis difference a - b, and the first-order "
                   f"prediction sigma sqrt([(J^T J)^-1]_theta,theta); synthetic near-circular ellipses, a = 299.0243 mm, N = {params['n']}, "
                   f"sigma = {params['noise'] * 1e3:g} µm per coordinate, {reps} repetitions; the ratio RMS / prediction "
                   "with its Monte-Carlo standard error 1/sqrt(2 n) over n converged fits (dimensionless)")
        fig = Figure(caption="RMS error of the fitted axis angle [°] against a − b [µm] on synthetic near-circular "
                             "ellipses, with the first-order prediction: the angle of a near-circle is ill-conditioned "
                             f"(top); RMS / prediction with ± 2 Monte-Carlo standard errors of an RMS of {reps} copies "
                             "(bottom: error bars, and the grey band around 1)",
                     file="angle_conditioning.png")
        # ratios to 0.01 (their standard error is a few %), standard errors to 0.001; angles to 1e-5° (three digits
        # of the smallest, 0.0014° at a - b = 1 mm)
        decimals = {c: (3 if c.endswith("s.e.") else 2) for c in shown.columns if "ratio" in c}
        decimals.update({c: 5 for c in shown.columns if c.endswith("[°]")})
        return Analysis(tables=[Table(caption=caption, data=shown, unit="°", digits=4, decimals=decimals)], figures=[fig],
                        values=values,
                        findings=findings)
