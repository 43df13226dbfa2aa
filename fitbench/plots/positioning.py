"""Text report and plots of a positioning test: the axis figures, the per-target table, the polynomial
in readable units, and a plot like laser-interferometer software's (every run, the mean bidirectional
curves, the ±k s bands, A/E/B/M/R annotated) beside the model with its expanded-uncertainty band
(the positioning paper's figures 2 and 3)."""
from __future__ import annotations

import textwrap

import numpy as np

from fitbench.plots import report_figure, tight
from methods.positioning.model import evaluate_band

ARROW = {"up": "↑", "down": "↓"}
#: the figure's size (inches) and its smallest font (pt): shown 800 px wide (the report's figure width)
#: 8.5 pt is about 9.4 px high
FIGSIZE = (10.0, 5.2)
MIN_FONT_PT = 8.5
TITLES = {"iso230-2:2014": "ISO 230-2:2014 (k = 2)", "iso230-2:1988": "ISO 230-2:1988 (k = 3)",
          "vdi3441": "VDI/DGQ 3441"}


def coefficients_readable(poly: dict) -> list[tuple[int, float, str]]:
    """The polynomial's coefficients c_k (mm / mm^k, increasing powers of P in mm) as µm per m^k:
    c_k [µm/m^k] = c_k [mm/mm^k] x 1e3 x 1e3^k, with the unit string."""
    out = []
    for k, c in enumerate(poly["coefficients"]):
        out.append((k, float(c) * 1e3 * (1e3 ** k), "µm" if k == 0 else ("µm/m" if k == 1 else f"µm/m^{k}")))
    return out


def arrows(figures: dict) -> dict:
    """The direction marks: ↑ / ↓, or ? for a test whose file named no approach direction (ISO 230-2's ↑ is an
    approach in the + direction, which nothing said)."""
    return dict(ARROW, up="?") if "direction not given" in str(figures.get("directions", "")) else ARROW


def text(res, degree: int | None = None) -> str:
    f, per = res.figures, res.per_target
    ARROW = arrows(f)
    std = f["standard"]
    um = 1e3
    lines = [f"{TITLES.get(std, std)}: {f['targets']} targets x {f['runs']} run{'s' if f['runs'] != 1 else ''}, {f.get('directions', 'bidirectional')} "
             "(all values in µm)"]
    if std == "vdi3441":
        lines += [f"  P  (positional uncertainty)        {f['P'] * um:10.3f}",
                  f"  Pa (positional deviation)          {f['Pa'] * um:10.3f}",
                  f"  Ps (largest positional scatter)    {f['Ps'] * um:10.3f}",
                  f"  U  (largest reversal span)         {f['U'] * um:10.3f}"]
    else:
        names = {"A": "accuracy, bidirectional", "A_up": "accuracy ↑", "A_down": "accuracy ↓",
                 "E": "systematic deviation, bidirectional", "E_up": "systematic deviation ↑",
                 "E_down": "systematic deviation ↓", "M": "mean bidirectional positional deviation",
                 "R": "repeatability, bidirectional", "R_up": "repeatability ↑", "R_down": "repeatability ↓",
                 "B": "reversal value", "B_mean": "mean reversal value"}
        if f.get("directions", "bidirectional") != "bidirectional":
            names = {k: v.replace(", bidirectional", f", {f['directions']}").replace("↑", ARROW["up"])
                     for k, v in names.items()}
        width = max([40] + [len(v) for key, v in names.items() if key in f])
        for key, label in names.items():
            if key in f:
                lines.append(f"  {key:<7} {label:<{width}} {f[key] * um:10.3f}")
    vdi = "Ps_i" in per     # VDI/DGQ 3441's per-position figures, not ISO 230-2's B_i and R_i
    lines.append("per target (µm; target in mm" + ("; VDI/DGQ 3441: reversal span U_i = |mean ↑ - mean ↓|, positional "
                                                   "scatter Ps_i = 6 s_i, s_i pooled over both directions)" if vdi else ")"))
    cols = [(f"mean {ARROW[d]}", f"mean_{d}", 9) for d in ("up", "down") if f"mean_{d}" in per] + \
           [(f"s {ARROW[d]}", f"s_{d}", 7) for d in ("up", "down") if f"s_{d}" in per] + \
           [(n, k, 8) for n, k in ((("U_i", "U_i"), ("Ps_i", "Ps_i")) if vdi else (("B_i", "B_i"), ("R_i", "R_i")))
            + (("x̄_i", "mean_bidirectional"),) if k in per]
    if "R_i" not in per:
        cols += [(f"R_i {ARROW[d]}", f"R_i_{d}", 8) for d in ("up", "down") if f"R_i_{d}" in per]
    lines.append(f"  {'target':>10} " + " ".join(f"{n:>{w}}" for n, _, w in cols))
    for i, t in enumerate(per["targets"]):
        lines.append(f"  {t:10.3f} " + " ".join(f"{per[k][i] * um:{w}.3f}" for _, k, w in cols))
    if res.polynomial:
        ud = res.extra.get("u_delta", 0.0)
        lines.append(f"model: degree-{degree if degree is not None else next(iter(res.polynomial.values()))['degree']} "
                     f"polynomial by GLS in the position P (mm), u(delta) = {ud * um:.4g} µm; coefficients c_k of P^k "
                     "in µm per m^k (P in m)")
        for d, p in res.polynomial.items():
            coefs = ", ".join(f"{c:+.4g} {u}" for _, c, u in coefficients_readable(p))
            lof = p.get("lack_of_fit") or {}
            band = (f"U(P) not given: the model is rejected by its lack of fit" if lof.get("rejected") else
                    f"max U(P_i) = {p['U_at_targets'].max() * um:.3f} µm (k = {p['k']:g})"
                    + (", without the instrument's error (u(delta) = 0)" if not ud else ""))
            lines.append(f"  {ARROW.get(d, d)} {coefs}; {band}")
        lines += lack_of_fit_lines(res.polynomial, ARROW)
    return "\n".join(lines)


def model_name(degree: int) -> str:
    return {1: "straight line", 2: "parabola", 3: "cubic"}.get(int(degree), f"degree-{int(degree)} polynomial")


def rejected_directions(polynomial: dict) -> list[str]:
    """The directions whose model the lack-of-fit test rejects (:func:`methods.positioning.model.lack_of_fit`)."""
    return [d for d, p in (polynomial or {}).items() if (p.get("lack_of_fit") or {}).get("rejected")]


def lack_of_fit_lines(polynomial: dict, ARROW: dict = ARROW) -> list[str]:
    """One line per direction: the model's weighted chi-square against the means at the targets (u(x_i) =
    s_i / sqrt(n), the paper's eq. 10), its limit and what a rejection means for U(P) and a compensation table."""
    out = []
    for d, p in (polynomial or {}).items():
        lof = p.get("lack_of_fit")
        if not lof:
            continue
        miss = f"largest |mean - model| at a target {lof['max_abs_residual'] * 1e3:.3f} µm"
        if not lof["tested"]:
            out.append(f"  lack of fit {ARROW.get(d, d)}: not tested ({lof['reason']}); {miss}; U(P) assumes the "
                       f"{model_name(p['degree'])} holds")
            continue
        head = (f"  lack of fit {ARROW.get(d, d)}: χ²/ν = {lof['chi2_per_dof']:.3g} (χ² = {lof['chi2']:.4g}, "
                f"ν = {lof['dof']}; {lof['level']:.0%} limit {lof['critical']:.3g} from {lof['reference']}), {miss}")
        if lof["rejected"]:
            out.append(f"{head}: the {model_name(p['degree'])} is REJECTED: U(P) is not the uncertainty of the "
                       f"deviation between the targets; use the means at the targets (--compensation-from mean) or "
                       f"another --degree")
        else:
            out.append(f"{head}: not rejected; U(P) holds between the targets as far as the targets can tell")
    return out


def plot(result, path, title: str = "", *, data=None, save=None, into=None) -> dict:
    """Left: every run (thin), the mean deviations of each direction, the mean bidirectional curve, the
    ±k s bands and the figures A, E, B, M, R annotated; right: the model with U(P). Returns the axes'
    labels (for tests)."""
    with report_figure(path, dpi=120, save=save, into=into, figsize=FIGSIZE) as fig:
        per, figs = result.per_target, result.figures
        ARROW = arrows(figs)
        k = figs.get("k", 2.0)
        P = per["targets"]
        um = 1e3
        axes = fig.subplots(1, 2, sharey=True)
        ax = axes[0]
        colours = {"up": "tab:blue", "down": "tab:red"}
        dirs = [d for d in ("up", "down") if f"mean_{d}" in per]
        if data is not None:
            for d in dirs:
                arr = getattr(data, d)
                for j in range(arr.shape[1]):
                    ax.plot(P, arr[:, j] * um, lw=0.5, alpha=0.5, color=colours[d],
                            label=f"runs {ARROW[d]}" if j == 0 else None)
        for d in dirs:
            x = per[f"mean_{d}"]
            ax.plot(P, x * um, "o-", color=colours[d], ms=4, lw=1.4, label=f"mean {ARROW[d]}")
            if f"s_{d}" in per:      # one run per direction (ISO 230-2 over 2000 mm) has no s
                s = per[f"s_{d}"]
                ax.fill_between(P, (x - k * s) * um, (x + k * s) * um, color=colours[d], alpha=0.15,
                                label=f"±{k:g}s {ARROW[d]}")
        if "mean_bidirectional" in per:
            ax.plot(P, per["mean_bidirectional"] * um, "k-", lw=1.2, label="mean bidirectional")
        if figs.get("standard") == "vdi3441":
            notes = [f"P = {figs['P'] * um:.2f} µm", f"Pa = {figs['Pa'] * um:.2f} µm", f"Ps = {figs['Ps'] * um:.2f} µm",
                     f"U = {figs['U'] * um:.2f} µm"]
        else:
            notes = [f"{key} = {figs[key] * um:.2f} µm" for key in ("A", "E", "B", "M", "R") if key in figs]
        ax.text(0.02, 0.98, "\n".join(notes), transform=ax.transAxes, va="top", ha="left", fontsize=9.5,
                family="monospace", bbox=dict(boxstyle="round", fc="white", ec="0.6", alpha=0.9))
        ax.set_title(f"{TITLES.get(figs.get('standard'), figs.get('standard'))}: {figs['targets']} targets x "
                     f"{figs['runs']} run{'s' if figs['runs'] != 1 else ''}", fontsize=10)
        grid = np.linspace(P.min(), P.max(), 400)
        rejected = rejected_directions(result.polynomial)
        for d in dirs:
            axes[1].plot(P, per[f"mean_{d}"] * um, "o", color=colours[d], ms=4)
            if d in (result.polynomial or {}):
                v, U = evaluate_band(result.polynomial[d], grid, result.polynomial[d]["k"])
                axes[1].plot(grid, v * um, color=colours[d],
                             label=f"degree-{result.polynomial[d]['degree']} fit {ARROW[d]}")
                if d not in rejected:     # a rejected model's U(P) is not the uncertainty of the deviation
                    axes[1].fill_between(grid, (v - U) * um, (v + U) * um, color=colours[d], alpha=0.2,
                                         label=f"U(P), k = {result.polynomial[d]['k']:g}"
                                               + ("" if result.extra.get("u_delta") else ", no instrument error"))
        lofs = {d: p["lack_of_fit"] for d, p in (result.polynomial or {}).items() if p.get("lack_of_fit")}
        chi = ", ".join(f"{lof['chi2_per_dof']:.3g} {ARROW[d]}" for d, lof in lofs.items() if lof["tested"])
        if rejected:
            limit = max(lofs[d]["critical"] for d in rejected)
            axes[1].set_title(f"model REJECTED by its lack of fit:\nχ²/ν {chi} > {limit:.3g}; no U(P) band",
                              fontsize=10, color="tab:red")
        elif not result.polynomial:
            axes[1].set_title("no model: its uncertainty needs repeated runs\n(one run per direction)", fontsize=10)
        elif chi:
            axes[1].set_title(f"model: fitted curve and expanded uncertainty U(P)\nlack of fit χ²/ν {chi}: not rejected",
                              fontsize=10)
        else:
            axes[1].set_title("model: fitted curve and expanded uncertainty U(P)\nlack of fit not tested", fontsize=10)
        for a in axes:
            a.set_xlabel("target position P [mm]")
            a.grid(alpha=0.3)
            a.tick_params(labelsize=9)
            n = len(a.get_legend_handles_labels()[1])     # below the axes: inside, it hid the runs
            if n:
                a.legend(fontsize=MIN_FONT_PT, loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=(n + 1) // 2,
                         frameon=False, columnspacing=1.0, handlelength=1.6)
        axes[0].set_ylabel("positional deviation [µm]")
        if title:
            fig.suptitle("\n".join(textwrap.wrap(title, 110)), fontsize=10)
        tight(fig)
        labels = {"x": axes[0].get_xlabel(), "y": axes[0].get_ylabel(), "notes": notes,
                  "model_title": axes[1].get_title(), "model_labels": axes[1].get_legend_handles_labels()[1]}
        return labels
