"""Study ``noise``: bias and RMSE of centre and radius against the Kanatani–Cramér–Rao bound.

For isotropic Gaussian noise of s.d. sigma per coordinate, any unbiased estimator of (a, b, R) has
covariance >= sigma^2 (W^T W)^-1, W rows (cos t_i, sin t_i, 1) at the true points (the KCR bound,
Kanatani 1996; Chernov & Lesort, J. Math. Imaging Vis. 2005). Geometric and the modern algebraic fits
reach it to first order; they differ in their (second-order) bias, which dominates on short arcs.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from datasets.synthetic import circle_points
from experiments.render.text import counts_by_group
from experiments.outputs import save_csv
from experiments.study import Analysis, Figure, Study, Table


def kcr_bound(arc_deg: float, n: int, sigma: float, radius: float = 1.0) -> tuple[float, float]:
    """(centre RMSE bound, radius RMSE bound) for n points evenly on an arc of arc_deg degrees."""
    full = arc_deg >= 360.0
    pts = circle_points((0.0, 0.0), radius, n, arc=(0.0, np.radians(arc_deg)), endpoint=not full)
    W = np.column_stack([pts[:, 0] / radius, pts[:, 1] / radius, np.ones(n)])
    V = sigma ** 2 * np.linalg.inv(W.T @ W)
    return float(np.sqrt(V[0, 0] + V[1, 1])), float(np.sqrt(V[2, 2]))


def rmse_standard_error(e) -> float:
    """Monte-Carlo standard error of sqrt(mean(e^2)) over the n values ``e`` (delta method: s.e. of the mean of
    e^2, std(e^2) / sqrt(n), divided by 2 RMSE; about RMSE / sqrt(2 n) for unbiased Gaussian errors, larger
    with outliers, smaller where a bias dominates)."""
    e = np.asarray(e, dtype=float)
    if len(e) < 2:
        return float("nan")
    rmse = np.sqrt(np.mean(e ** 2))
    return float(np.std(e ** 2, ddof=1) / np.sqrt(len(e)) / (2 * rmse)) if rmse > 0 else 0.0


def classify(ratio, se, limit: float = 1.1, k: float = 2.0):
    """'within' (ratio + k s.e. <= limit), 'beyond' (ratio - k s.e. > limit) or 'undecided' (the Monte-Carlo
    scatter cannot tell) per element of ``ratio``; NaN -> ''."""
    ratio, se = np.asarray(ratio, dtype=float), np.asarray(se, dtype=float)
    return np.where(np.isnan(ratio), "", np.where(ratio + k * se <= limit, "within",
                                                  np.where(ratio - k * se > limit, "beyond", "undecided")))


def kcr_table(df: pd.DataFrame) -> pd.DataFrame:
    """Per (arc, noise, N, method, params): centre and radius RMSE, radius bias, and their ratios to the KCR bound."""
    rows = []
    for (arc, noise, n, m, p), g in df.groupby(["data_arc_deg", "data_noise", "data_n", "method", "params"], sort=False):
        ok = g[g["status"] == "ok"]
        kc, kr = kcr_bound(arc, int(n), noise)
        r = {"arc_deg": arc, "noise": noise, "n": int(n), "method": m, "params": p, "runs": len(g), "ok": len(ok)}
        if len(ok):
            ce = ok["center_error"].astype(float)
            re = ok["radius_error"].astype(float)
            r.update(center_rmse=float(np.sqrt(np.mean(ce ** 2))), radius_bias=float(re.mean()),
                     radius_rmse=float(np.sqrt(np.mean(re ** 2))), kcr_center=kc, kcr_radius=kr)
            r["center_rmse_over_kcr"] = r["center_rmse"] / kc
            r["radius_rmse_over_kcr"] = r["radius_rmse"] / kr
            r["radius_rmse_over_kcr_se"] = rmse_standard_error(re.to_numpy()) / kr
            r["radius_bias_over_sigma"] = r["radius_bias"] / noise
        rows.append(r)
    return pd.DataFrame(rows)


def below_bound_text(table: pd.DataFrame) -> str:
    """A sentence on the ratios below 1 of ``table`` (kcr_table rows): how many standard errors below 1 they lie.
    Within about 3 they are Monte-Carlo scatter of an estimator at the bound, not an estimator beating it."""
    t = table.dropna(subset=["radius_rmse_over_kcr", "radius_rmse_over_kcr_se"])
    low = t[t["radius_rmse_over_kcr"] < 1]
    if not len(low):
        return ""
    z = (1 - low["radius_rmse_over_kcr"]) / low["radius_rmse_over_kcr_se"]
    w = low.loc[low["radius_rmse_over_kcr"].idxmin()]
    text = (f" Radius RMSE below the bound in {len(low)} of {len(t)} least-squares cells (all σ, N and arcs; lowest "
            f"{w['radius_rmse_over_kcr']:.2f}, {w['method']} on the {w['arc_deg']:g}° arc at σ = {w['noise']:g} R, "
            f"N = {int(w['n'])})")
    far = low[z > 3]
    if not len(far):
        return text + (f": all within {z.max():.1f} standard errors of 1, Monte-Carlo scatter of estimators at the bound, "
                       "not estimators beating it.")
    names = ", ".join(f"{r.method} {r.arc_deg:g}° σ = {r.noise:g} R N = {int(r.n)} ({zi:.1f} s.e.)"
                      for r, zi in zip(far.itertuples(), z[z > 3]))
    return text + (f": {len(low) - len(far)} within 3 standard errors of 1 (Monte-Carlo scatter), beyond 3: {names}, "
                   "beyond the Monte-Carlo scatter.")


class NoiseStudy(Study):
    """The ``noise`` study (see the module's docstring)."""

    values = None  # its analysis names its values

    def analyse(self, df, cfg, target, log):
        """The KCR table (kcr.csv), the redrawn KCR figure, and which least-squares estimators reach the bound."""
        table = kcr_table(df)
        save_csv(table, target / "kcr.csv", index=False, float_format="%.6g")
        kcr_figure(table, target / "noise_kcr.png")
        sigma, n = table["noise"].max(), int(table["n"].max())
        worst = table[(table["noise"] == sigma) & (table["n"] == n)]
        piv = worst.pivot_table(index="method", columns="arc_deg", values="radius_rmse_over_kcr", aggfunc="mean", sort=False)
        piv = piv[sorted(piv.columns, reverse=True)]
        log(f"  radius RMSE / KCR bound at sigma = {sigma:g} R, N = {n} (1.00 = the statistical limit):")
        log("  " + f"{'method':<28}" + "".join(f"{f'{c:g}° arc':>11}" for c in piv.columns))
        for m, vals in piv.iterrows():
            log("  " + f"{m:<28}" + "".join(f"{v:11.2f}" for v in vals))
        # the least-squares estimators: methods whose rows are not zone results (plugins included)
        zone = set(df.loc[df["inner_radius"].notna(), "method"]) if "inner_radius" in df else set()
        lsq = piv[~piv.index.isin(zone)]
        pse = worst.pivot_table(index="method", columns="arc_deg", values="radius_rmse_over_kcr_se", aggfunc="mean",
                                sort=False).reindex(index=piv.index, columns=piv.columns)
        lsq_se = pse.loc[lsq.index]
        # within 10 % only where the Monte-Carlo scatter (2 standard errors) cannot carry the ratio past 1.1
        verdict = pd.DataFrame(classify(lsq, lsq_se), index=lsq.index, columns=lsq.columns)
        worst_ratio = lsq.max(axis=1)
        within = sorted(m for m in lsq.index if (verdict.loc[m] == "within").all())
        values = {"sigma": float(sigma), "n": n, "arcs_deg": [float(a) for a in piv.columns],
                  "within_10_percent": within, "worst_ratio": {m: float(v) for m, v in worst_ratio.items()},
                  "radius_rmse_over_kcr": {m: {f"{c:g}": float(v) for c, v in vals.items()} for m, vals in piv.iterrows()},
                  "radius_rmse_over_kcr_se": {m: {f"{c:g}": float(v) for c, v in vals.items()} for m, vals in pse.iterrows()}}
        by = {k: {f"{a:g}°": sorted(m for m in lsq.index if verdict.loc[m, a] == k) for a in lsq.columns}
              for k in ("within", "beyond", "undecided")}
        values["within_10_percent_by_arc"] = by["within"]
        values["beyond_10_percent_by_arc"] = by["beyond"]
        values["undecided_by_arc"] = by["undecided"]
        rel = (lsq_se / lsq).to_numpy(float)
        rel = rel[np.isfinite(rel)]
        reps = int(worst["ok"].median()) if len(worst) else 0
        se_text = (f"{100 * rel.min():.2g} to {100 * rel.max():.2g} %" if len(rel) else "unknown")
        findings = (f"At σ = {sigma:g} R and N = {n} ({reps} repetitions, one Monte-Carlo standard error of a ratio {se_text} "
                    f"of it), least-squares estimators reaching the KCR bound on the radius within 10 % by more than 2 "
                    f"standard errors: {counts_by_group(by['within'], len(lsq), 'arc')}, beyond 10 % by more than 2 "
                    f"standard errors: {counts_by_group(by['beyond'], len(lsq), 'arc')}"
                    + (f", the others undecided at {reps} repetitions." if any(by["undecided"].values()) else "."))
        if any(by["undecided"].values()):
            findings += (f" Undecided (the ratio ± 2 standard errors straddles 1.1): "
                         f"{counts_by_group(by['undecided'], len(lsq), 'arc', names=False)}.")
        if len(lsq):
            far = worst_ratio.idxmax()
            arc = lsq.loc[far].idxmax()
            findings += (f" The farthest from it is {far}: {worst_ratio[far]:.2f} × the bound (± {pse.loc[far, arc]:.2f}) "
                         f"on the {arc:g}° arc.")
        findings += below_bound_text(table[~table["method"].isin(zone)])
        shown = pd.DataFrame({"method": piv.index})
        for c in piv.columns:
            shown[f"{c:.0f}° arc"] = piv[c].to_numpy()
            shown[f"{c:.0f}° s.e."] = pse[c].to_numpy()
        caption = (f"Radius RMSE divided by the KCR lower bound (dimensionless, 1 = the statistical limit) and its Monte-Carlo "
                   f"standard error (s.e.), every circle method on synthetic unit circles and arcs, sigma = {sigma:g} R "
                   f"isotropic noise, N = {n}, {int(worst['runs'].max())} repetitions")
        fig_caption = ("Radius RMSE / KCR bound (top) and radius bias / σ (bottom) of the least-squares estimators "
                       "against the noise σ / R on synthetic unit circles and arcs; dashed: closed-form (algebraic) fits; "
                       f"each ratio's Monte-Carlo standard error is in kcr.csv ({se_text} of it at σ = {sigma:g} R, N = {n})")
        # one resolution for every column (a ratio known to a few % needs 2 decimals; 21.18 beside 2.708 misled)
        decimals = {c: 2 for c in shown.columns if c != "method"}
        return Analysis(tables=[Table(caption=caption, data=shown, unit="", decimals=decimals)],
                        figures=[Figure(caption=fig_caption, file="noise_kcr.png")], values=values, findings=findings)


# ---------------------------------------------------------------- figures (drawn in experiments.render.style)

#: least-squares circle estimators (the KCR bound applies to them); the others estimate other circles
_ALGEBRAIC_KINDS = ("closed form",)


def _kind(method_id: str) -> str | None:
    try:
        import methods
        return methods.get(method_id).kind
    except Exception:
        return None


def kcr_figure(kcr: pd.DataFrame, path, *, methods: list[str] | None = None, n: int | None = None):
    """Radius RMSE / KCR bound (top) and radius bias / σ (bottom) against σ / R, one column per arc.

    ``kcr``: results/noise/kcr.csv (arc_deg, noise, n, method, params, radius_rmse_over_kcr,
    radius_bias_over_sigma). ``methods``: which to draw (default: every method whose registry kind is not
    'convex program': the least-squares estimators the KCR bound is about; the zone fits estimate other
    circles and stay in the table)."""
    from experiments.render import style
    plt = style.plotting()
    n = int(kcr["n"].max()) if n is None else n
    t = kcr[(kcr["n"] == n) & (kcr["params"].fillna("{}") == "{}")].copy()
    if methods is None:
        methods = sorted(m for m in t["method"].unique() if _kind(m) != "convex program")
    t = t[t["method"].isin(methods)]
    arcs = sorted(t["arc_deg"].unique(), reverse=True)
    with style.figure_style():
        fig, axes = plt.subplots(2, len(arcs), figsize=style.size(1.0, 0.62), sharex=True, sharey="row",
                                 squeeze=False)
        for j, arc in enumerate(arcs):
            for m, g in t[t["arc_deg"] == arc].groupby("method"):
                g = g.sort_values("noise")
                kw = style.method_style(m)
                if _kind(m) in _ALGEBRAIC_KINDS:
                    kw["linestyle"] = "--"
                axes[0, j].plot(g["noise"], g["radius_rmse_over_kcr"], **kw)
                axes[1, j].plot(g["noise"], g["radius_bias_over_sigma"], **kw)
            axes[0, j].axhline(1.0, color="0.2", lw=0.8)
            axes[1, j].axhline(0.0, color="0.2", lw=0.8)
            axes[0, j].set_title(f"{arc:.0f}° arc")
            axes[1, j].set_xlabel("σ / R")
            for i in (0, 1):
                axes[i, j].set_xscale("log")
            axes[0, j].set_yscale("log")
        axes[0, 0].set_ylabel("radius RMSE /\nKCR bound")
        axes[1, 0].set_ylabel("radius bias / σ")
        for ax in axes.ravel():
            style.plain_log_ticks(ax)
        style.legend_outside(fig, axes=[axes[0, 0]], title=f"N = {n} points; dashed: closed-form (algebraic) fits")
        return style.save(fig, path)
