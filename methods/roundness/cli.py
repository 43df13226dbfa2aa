"""``python -m methods roundness FILE``: an ISO 12181 roundness report (table, JSON, polar and spectrum plot)."""
from __future__ import annotations

import json
import math
import os
import tempfile
import warnings

import numpy as np

from methods._errors import InvalidInputError
from methods.units import UNIT_CHOICES, to_mm
from methods.roundness.evaluation import REFERENCE_NAMES
from methods.roundness.filter import UndersampledWarning, parse_cutoff, transmission



def add_parser(subparsers):
    p = subparsers.add_parser("roundness", help="ISO 12181 roundness: filtered profile, RONt/p/v/q about the "
                                                "reference circles, harmonic spectrum")
    p.add_argument("file", metavar="FILE", help="a points file (x, y) or a published data set name")
    p.add_argument("--cutoff", default="50", metavar="UPR",
                   help="Gaussian filter cut-off in undulations per revolution: none, 15, 50 (default), 150, 500, "
                        "1500 or any positive value (ISO 16610-21)")
    p.add_argument("--reference", choices=("lsci", "mzci", "mici", "mcci", "all"), default="all",
                   help="reference circle(s) (default: all four)")
    p.add_argument("--unit", choices=UNIT_CHOICES, default="mm", help="length unit of the file (default mm)")
    p.add_argument("--json", action="store_true", help="print one JSON object (lengths in mm)")
    p.add_argument("--plot", metavar="PNG", help="write the polar plot and the harmonic spectrum")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    import methods
    from datasets import points_from

    cutoff = parse_cutoff(args.cutoff, "--cutoff")
    source, points = points_from(args.file)
    points = to_mm(np.asarray(points, dtype=float), args.unit)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UndersampledWarning)
        res = methods.fit("roundness.iso12181", points, cutoff_upr=cutoff, reference=args.reference)
    for w in caught:
        if issubclass(w.category, UndersampledWarning):
            print(f"fitbench: warning: {w.message}", file=os.sys.stderr)
    if args.plot:
        plot(res, args.plot, title=f"{source}")
    if args.json:
        d = res.to_dict(residuals=False)
        d["spectrum"] = {k: np.asarray(v).tolist() for k, v in res.spectrum.items()}
        d.update(source=source, input_unit=args.unit,
                 units={"lengths": "mm", "angles": "rad", "cutoff_upr": "undulations per revolution",
                        "spectrum.amplitude": "mm", "spectrum.phase": "rad"})
        d.pop("extra", None)
        print(json.dumps(d))
        return 0 if res.converged else 1
    print(report(res, source))
    return 0 if res.converged else 1


def report(res, source: str) -> str:
    """The instrument-style table: one row per reference circle, lengths in µm (centre and radius in mm)."""
    cut = "none (unfiltered)" if res.cutoff_upr is None else f"{res.cutoff_upr:g} UPR Gaussian (ISO 16610-21)"
    lines = [f"data          {source} ({res.n_points} points)",
             f"filter        {cut}" + ("" if res.cutoff_upr is None else f"; {res.filter_path}"),
             f"raw LSCI      centre ({res.raw_lsci['center'][0]:.6f}, {res.raw_lsci['center'][1]:.6f}) mm, "
             f"radius {res.raw_lsci['radius']:.6f} mm (deviations filtered about it)", ""]
    head = (f"{'reference':<38} {'RONt [µm]':>10} {'RONp [µm]':>10} {'RONv [µm]':>10} {'RONq [µm]':>10} "
            f"{'centre x [mm]':>14} {'centre y [mm]':>14} {'radius [mm]':>12}  status")
    lines += [head, "-" * len(head)]
    for kind, r in res.references.items():
        lines.append(f"{REFERENCE_NAMES[kind]:<38} {r['RONt'] * 1e3:10.4f} {r['RONp'] * 1e3:10.4f} "
                     f"{r['RONv'] * 1e3:10.4f} {r['RONq'] * 1e3:10.4f} {r['center'][0]:14.6f} "
                     f"{r['center'][1]:14.6f} {r['radius']:12.6f}  "
                     + ("ok" if r["converged"] else f"NOT CERTIFIED ({r['message']})"))
    lobes = ", ".join(f"{d['upr']} UPR {d['amplitude'] * 1e3:.4f} µm" for d in res.dominant_lobes)
    lines += ["", f"dominant lobes (amplitude of the filtered deviation): {lobes or '-'}"]
    lines += [f"warning: {w}" for w in res.warnings]
    return "\n".join(lines)


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


def plot(res, path, title: str = "") -> None:
    """Polar plot of the filtered profile (deviation magnified, µm per division) with the reference circles,
    beside the bar plot of the harmonic spectrum (µm per UPR) with the filter's transmission."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c0, r0 = res.raw_lsci["center"], res.raw_lsci["radius"]
    theta = res.angles
    dev_um = res.deviations * 1e3
    fig = plt.figure(figsize=(12, 5.4))
    ax = fig.add_subplot(1, 2, 1, projection="polar")
    t_fine = np.linspace(0, 2 * np.pi, 721)
    curves = {k: _circle_deviation(r["center"], r["radius"], c0, r0, t_fine) * 1e3 for k, r in res.references.items()}
    lo = min(dev_um.min(), *(c.min() for c in curves.values()))
    hi = max(dev_um.max(), *(c.max() for c in curves.values()))
    step = _nice_step(max(hi - lo, 1e-9))
    lo_t, hi_t = math.floor(lo / step) * step, math.ceil(hi / step) * step
    ax.set_rorigin(lo_t - 0.6 * (hi_t - lo_t))
    ax.set_rlim(lo_t, hi_t)
    ax.set_rticks(np.arange(lo_t, hi_t + step / 2, step))
    ax.set_yticklabels([])
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
    ax.set_title(f"{title}\n{cut}, {step:g} µm/div", fontsize=9)
    ax.legend(loc="upper left", bbox_to_anchor=(-0.25, -0.08), fontsize=7, ncol=2)

    bx = fig.add_subplot(1, 2, 2)
    k = np.asarray(res.spectrum["upr"])
    amp = np.asarray(res.spectrum["amplitude"]) * 1e3
    sel = k >= 1
    kmax = int(min(k.max(), 3 * res.cutoff_upr if res.cutoff_upr else k.max()))
    sel &= k <= max(kmax, 10)
    bx.bar(k[sel], amp[sel], width=0.8 if sel.sum() < 200 else 1.0, color="tab:gray")
    for d in res.dominant_lobes[:3]:
        bx.annotate(f"{d['upr']}", (d["upr"], d["amplitude"] * 1e3), fontsize=7, ha="center", va="bottom")
    bx.set_xlabel("undulations per revolution [UPR]")
    bx.set_ylabel("amplitude of the filtered deviation [µm]")
    bx.set_title("harmonic spectrum (about the raw LSCI centre)", fontsize=9)
    if res.cutoff_upr:
        tx = bx.twinx()
        kk = np.linspace(0, max(kmax, 10), 400)
        tx.plot(kk, transmission(kk, res.cutoff_upr), color="tab:orange", lw=1)
        tx.set_ylabel("filter transmission a(k)", color="tab:orange")
        tx.set_ylim(0, 1.05)
    fig.tight_layout()
    path = os.fspath(path)
    fd, tmp = tempfile.mkstemp(suffix=os.path.splitext(path)[1] or ".png", dir=os.path.dirname(os.path.abspath(path)))
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=110)
        os.replace(tmp, path)
    except Exception as exc:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise InvalidInputError(f"cannot write the plot {path}: {exc}") from None
    finally:
        plt.close(fig)
