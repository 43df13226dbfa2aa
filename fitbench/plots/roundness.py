"""The roundness figure: the filtered profile on a polar chart (deviation magnified, µm per division) with
the reference circles, beside the harmonic spectrum with the filter's transmission (ISO 12181-1, ISO 16610-21)."""
from __future__ import annotations

import math
import textwrap

import numpy as np

from fitbench.plots import report_figure, ring_label, tight
from methods.roundness.filter import transmission

#: the figure's size (inches) and its smallest font (pt): 8.5 pt is about 9.4 px high with the figure 800 px wide
FIGSIZE = (10.0, 5.8)
MIN_FONT_PT = 8.5
#: the polar panel's title is wrapped at this many characters (10 pt text, the panel about 4.5 in wide)
TITLE_CHARS = 56


def _nice_step(span_um: float) -> float:
    raw = span_um / 5
    p = 10 ** math.floor(math.log10(raw))
    return min((m * p for m in (1, 2, 5, 10) if m * p >= raw), default=10 * p)


def _circle_deviation(center, radius, c0, r0, theta):
    """Radial position of a reference circle along the rays from the raw LSCI centre c0, minus R0."""
    d = np.asarray(center) - np.asarray(c0)
    u = np.stack([np.cos(theta), np.sin(theta)])
    proj = d @ u
    return proj + np.sqrt(np.maximum(radius ** 2 - (d @ d - proj ** 2), 0.0)) - r0


def plot(res, path, title: str = "", *, save=None, into=None) -> None:
    """Polar plot of the filtered profile (deviation magnified, µm per division) with the reference circles,
    beside the bar plot of the harmonic spectrum (µm per UPR) with the filter's transmission."""
    with report_figure(path, dpi=120, save=save, into=into, figsize=FIGSIZE) as fig:
        c0, r0 = res.raw_lsci["center"], res.raw_lsci["radius"]
        theta = res.angles
        dev_um = res.deviations * 1e3
        ax = fig.add_subplot(1, 2, 1, projection="polar")
        t_fine = np.linspace(0, 2 * np.pi, 721)
        curves = {k: _circle_deviation(r["center"], r["radius"], c0, r0, t_fine) * 1e3 for k, r in res.references.items()}
        lo = min(dev_um.min(), *(c.min() for c in curves.values()))
        hi = max(dev_um.max(), *(c.max() for c in curves.values()))
        step = _nice_step(max(hi - lo, 1e-9))
        lo_t, hi_t = math.floor(lo / step) * step, math.ceil(hi / step) * step
        ax.set_rorigin(lo_t - 0.6 * (hi_t - lo_t))
        ax.set_rlim(lo_t, hi_t)
        rings = np.arange(lo_t, hi_t + step / 2, step)
        ax.set_rticks(rings)
        # ring labels (µm about the raw LSCI radius) along the ray where the profile is innermost: there the
        # profile and the reference circles lie below the labelled rings instead of across them
        ax.set_yticklabels([ring_label(v) for v in rings], fontsize=MIN_FONT_PT, color="0.3",
                           bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7))
        ax.yaxis.set_zorder(4)                                 # the ring labels over the profile
        ray = float(np.degrees(theta[int(np.argmin(dev_um))])) % 360
        ax.set_rlabel_position(ray)
        # the angle labels every 45°, but not the one the ring labels' ray would run into at the rim
        angles = [a for a in range(0, 360, 45) if abs((a - ray + 180) % 360 - 180) > 15]
        ax.set_thetagrids(angles, labels=[f"{a}°" for a in angles])
        ax.plot(np.append(theta, theta[0]), np.append(dev_um, dev_um[0]), color="k", lw=0.8, label="filtered profile")
        colors = {"lsci": "tab:blue", "mzci": "tab:red", "mici": "tab:green", "mcci": "tab:purple"}
        for kind, c in curves.items():
            r = res.references[kind]
            if not r["converged"]:  # drawn faint and labelled: its solver claimed no optimum
                ax.plot(t_fine, c, color="0.6", lw=0.6, ls=":", label=f"{kind.upper()}: not certified by {r['method']}")
                continue
            ax.plot(t_fine, c, color=colors[kind], lw=0.9, ls="--",
                    label=f"{kind.upper()}: RONt {r['RONt'] * 1e3:.3f} µm")
            if kind == "mzci":
                ax.plot(t_fine, _circle_deviation(r["center"], r["inner_radius"], c0, r0, t_fine) * 1e3,
                        color=colors[kind], lw=0.6, ls=":")
                ax.plot(t_fine, _circle_deviation(r["center"], r["outer_radius"], c0, r0, t_fine) * 1e3,
                        color=colors[kind], lw=0.6, ls=":")
        cut = "unfiltered" if res.cutoff_upr is None else f"Gaussian {res.cutoff_upr:g} UPR"
        ax.tick_params(axis="x", labelsize=9, pad=9)   # the angle labels clear of the ring labels at the rim
        # the title (the file and a verdict) wrapped to the polar panel's width, as the circular-test plot does: one
        # line ran past the figure's left edge and over the spectrum's title
        # lines break only after a comma or semicolon: a figure stays with its name, value, unit and tolerance
        keep = title.replace(" ", "\u00a0").replace(",\u00a0", ", ").replace(";\u00a0", "; ")
        head = "\n".join(textwrap.wrap(keep, TITLE_CHARS)) + "\n" if title else ""
        ax.set_title(f"{head}{cut}, {step:g} µm/div", fontsize=10)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.08), fontsize=MIN_FONT_PT, ncol=2, frameon=False,
                  columnspacing=1.0, handlelength=1.8)

        bx = fig.add_subplot(1, 2, 2)
        k = np.asarray(res.spectrum["upr"])
        amp = np.asarray(res.spectrum["amplitude"]) * 1e3
        sel = k >= 1
        kmax = int(min(k.max(), 3 * res.cutoff_upr if res.cutoff_upr else k.max()))
        sel &= k <= max(kmax, 10)
        bx.bar(k[sel], amp[sel], width=0.8 if sel.sum() < 200 else 1.0, color="tab:gray")
        shown = []  # label a visible dominant lobe only where it does not overlap a label already placed
        top = max((d["amplitude"] for d in res.dominant_lobes), default=0.0)
        for d in res.dominant_lobes[:5]:
            if d["amplitude"] >= 0.05 * top and all(abs(d["upr"] - u) > 0.02 * max(kmax, 10) for u in shown):
                bx.annotate(f"{d['upr']}", (d["upr"], d["amplitude"] * 1e3), fontsize=MIN_FONT_PT, ha="center",
                            va="bottom")
                shown.append(d["upr"])
        bx.set_xlabel("undulations per revolution [UPR]")
        bx.set_ylabel("amplitude of the filtered deviation [µm]")
        bx.set_title("harmonic spectrum (about the raw LSCI centre)", fontsize=10)
        bx.tick_params(labelsize=9)
        if res.cutoff_upr:
            tx = bx.twinx()
            kk = np.linspace(0, max(kmax, 10), 400)
            tx.plot(kk, transmission(kk, res.cutoff_upr), color="tab:orange", lw=1)
            tx.set_ylabel("filter transmission a(k)", color="tab:orange")
            tx.set_ylim(0, 1.05)
            tx.tick_params(labelsize=9)
        tight(fig)
        if hasattr(fig, "canvas") and hasattr(fig, "tight_layout"):
            for _ in range(2):  # a polar title is placed above its angle labels when drawn: lay out again around it
                fig.canvas.draw()
                tight(fig)
