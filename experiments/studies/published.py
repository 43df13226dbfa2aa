"""Study ``published``: every circle method on the roundness paper's published profiles, and its
table 1 (LSQ, Voronoi minimum zone, MIC, MCC) published against reproduced. Where a figure is not
reproduced, coordinates consistent with the printed digits (uniform within half a unit of the last
printed decimal) are refitted to measure the spread that the rounding alone allows."""
from __future__ import annotations

import numpy as np

import datasets
import methods
from experiments.study import save_figure

#: table 1 columns of the roundness paper and the method that reproduces each
PUBLISHED_COLUMNS = {"LSQ (paper's Gauss-Newton)": "circle.gauss_newton",
                     "Voronoi (minimum zone)": "circle.minimum_zone",
                     "MIC": "circle.max_inscribed", "MCC": "circle.min_circumscribed"}


def rounding_spread(points: np.ndarray, decimals: int, *, samples: int, rng, method: str) -> np.ndarray:
    """Circularity by ``method`` of ``samples`` data sets whose coordinates round to the printed ones."""
    half = 0.5 * 10.0 ** (-decimals)
    widths = np.full(samples, np.nan)
    for k in range(samples):
        res = methods.fit(method, points + rng.uniform(-half, half, points.shape))
        if res.converged:
            widths[k] = res.form_error
    return widths[np.isfinite(widths)]


def compare(ds, variant: str, column: str, method_id: str, pub: float, samples: int, rng) -> dict:
    res = methods.fit(method_id, ds.points)
    digits = len(repr(pub).split(".")[1]) if "." in repr(pub) else 0
    reproduced = round(res.form_error, digits) == pub
    decimals = int(ds.meta.get("decimals_printed", 6))
    widths = rounding_spread(ds.points, decimals, samples=samples, rng=rng, method=method_id)
    lo, med, hi = np.percentile(widths, [0.5, 50, 99.5])
    pct = float(np.mean(widths <= pub) * 100)
    inside = bool(widths.min() <= pub <= widths.max())
    if reproduced:
        verdict = f"reproduced: {res.form_error:.7f} rounds to the published {pub}"
    elif inside:
        verdict = (f"not reproduced from the printed data (difference {res.form_error - pub:+.7f}); coordinates "
                   f"consistent with the {decimals} printed decimals give {lo:.6f} .. {hi:.6f} (99 % range) and the "
                   f"published value lies at their {pct:.1f}th percentile: consistent with the paper having "
                   "evaluated the unrounded source data")
    else:
        verdict = (f"NOT reproduced and not explained by the rounding of the printed data (difference "
                   f"{res.form_error - pub:+.7f}; rounding range {widths.min():.6f} .. {widths.max():.6f})")
    return {"dataset": ds.name, "variant": variant, "column": column, "method": method_id, "published": pub,
            "reproduced_value": res.form_error, "difference": res.form_error - pub, "reproduced": reproduced,
            "decimals_printed": decimals, "rounding_p0_5": lo, "rounding_median": med, "rounding_p99_5": hi,
            "rounding_min": float(widths.min()), "rounding_max": float(widths.max()),
            "published_percentile": pct, "explained_by_rounding": inside, "samples": len(widths), "verdict": verdict}


def finalize(df, cfg, target, log):
    samples = int(cfg.get("rounding", {}).get("samples", 1000))
    rng = np.random.default_rng(np.random.SeedSequence(cfg["seed"], spawn_key=(99,)))
    out = []
    for spec in cfg["datasets"]:
        name, variant = spec["published"], spec.get("variant")
        ds = datasets.load(name, drop_repeated_closing_point=variant == "drop_repeated_closing_point")
        label = name + (f":{variant}" if variant else "")
        mine = df[df["dataset"] == label]
        log(f"\n  {label} ({ds.meta['table']}, {len(ds.points)} points); published: "
            + ", ".join(f"{k} {v}" for k, v in ds.published.items() if v is not None))
        log(f"  {'method':<28} {'params':<20} {'circularity':>12} {'centre x':>13} {'centre y':>13} {'status':<8} {'time':>10}")
        for r in mine.itertuples():
            t = f"{r.time_median_s * 1e6:8.1f} µs" if hasattr(r, "time_median_s") and r.time_median_s == r.time_median_s else ""
            params = "" if r.params == "{}" else r.params
            log(f"  {r.method:<28} {params:<20} {r.form_error:12.7f} {r.center_x:13.7f} {r.center_y:13.7f} "
                f"{r.status:<8} {t:>10}")
        for column, method_id in PUBLISHED_COLUMNS.items():
            pub = ds.published.get(column)
            if pub is None:
                continue
            c = compare(ds, variant or "as published", column, method_id, pub, samples, rng)
            log(f"  {column:<27} [{method_id}] published {pub}: {c['verdict']}")
            out.append(c)
    figure(out, target)
    return {"published_vs_reproduced": out, "figure": "published.png"}


def figure(rows, target):
    """Published against reproduced circularity, with the 99 % range the printed digits allow."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(rows), figsize=(1.5 * len(rows) + 1, 3.6))
    for ax, r in zip(np.atleast_1d(axes), rows):
        ax.errorbar([0], [r["rounding_median"]], yerr=[[r["rounding_median"] - r["rounding_p0_5"]],
                                                       [r["rounding_p99_5"] - r["rounding_median"]]],
                    fmt="none", ecolor="0.6", capsize=6, lw=2, label="99 % rounding range")
        ax.plot([0], [r["reproduced_value"]], "o", color="tab:blue", label="reproduced")
        ax.plot([0], [r["published"]], "x", color="tab:red", ms=9, label="published")
        ax.set_xticks([])
        set_name = r["dataset"].replace("roundness_", "") + ("*" if r["variant"] != "as published" else "")
        ax.set_title(f"{set_name}\n{r['column'].split(' ')[0]}", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.ticklabel_format(axis="y", useOffset=False)
    np.atleast_1d(axes)[0].legend(fontsize=6, loc="lower left")
    fig.suptitle("Roundness paper, table 1: published vs reproduced circularity [mm] (*: repeated point dropped)",
                 fontsize=9)
    fig.tight_layout()
    save_figure(fig, target / "published.png", dpi=110)
    plt.close(fig)


def report_tables(folder, f):
    """The tables a reader wants from this study (moved here from the report, which names no study)."""
    import pandas as pd

    from experiments.study import Table
    out = []
    rows = [{"set": r["dataset"] + ("" if r["variant"] == "as published" else f" ({r['variant']})"),
             "column": r["column"], "published": r["published"], "reproduced": round(r["reproduced_value"], 7),
             "difference": round(r["difference"], 7),
             "explanation": "reproduced" if r["reproduced"] else
             (f"rounding of the printed coordinates: 99 % range {r['rounding_p0_5']:.6f}..{r['rounding_p99_5']:.6f}, "
              f"published at the {r['published_percentile']:.0f}th percentile" if r["explained_by_rounding"]
              else "NOT explained")}
            for r in f.get("published_vs_reproduced", [])]
    out.append(("Roundness paper, table 1: published against reproduced circularity [mm]", pd.DataFrame(rows)))
    return [Table(caption=c, data=t) for c, t in out if t is not None and len(t)]
