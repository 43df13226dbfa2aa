"""Study ``nist_circle``: circle methods against NIST's Circle2d least-squares reference fits.

The reference centre and diameter are given to ~20 digits; the error is the largest absolute
difference in centre coordinates and radius (data units). Algebraic methods minimise other
objectives, so their 'error' is their distance from the geometric least-squares circle.
"""
from __future__ import annotations

import json
import os
from decimal import Decimal
from pathlib import Path

import numpy as np

from experiments import engine
from experiments.engine import ConfigError
from experiments.study import save_figure


def _folder() -> Path:
    value = os.environ.get("FITBENCH_NIST_DIR")
    if not value or not Path(value).is_dir():
        raise ConfigError("nist_circle needs FITBENCH_NIST_DIR set to the folder of nist_cir2d_*.csv/.json "
                          f"(got {value!r})")
    return Path(value)


def validate(cfg, where):
    engine.expand_methods(cfg, where)


def tasks(cfg):
    folder = _folder()
    out = []
    for i, meta_path in enumerate(sorted(folder.glob("nist_cir2d_*.json"))):
        meta = json.loads(meta_path.read_text())
        ref = meta["reference_least_squares"]
        truth = {"family": "circle", "center": [float(Decimal(v)) for v in ref["center"]],
                 "radius": float(Decimal(ref["diameter"])) / 2}
        spec = {"entry": i, "point": 0, "file": str(meta_path.with_suffix(".csv")), "truth": truth,
                "label": meta["name"]}
        for m, extra in engine.expand_methods(cfg, cfg["_where"]):
            out.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": spec, "repetition": 0,
                        "stream": [i, 0, 0], "seed": cfg["seed"], "method": m, "params": extra["params"], "timing": None})
    return out


def finalize(df, cfg, target, log):
    df = df.copy()
    df["max_error"] = np.maximum(df["center_error_x"].abs().combine(df["center_error_y"].abs(), max),
                                 df["radius_error"].abs())
    summary = {}
    log(f"  {'method':<28} {'params':<22} {'max error':>10} {'median error':>12} {'sets > 1e-9':>11} {'not converged':>13}")
    for (m, p), g in df.groupby(["method", "params"], sort=False):
        errs = g["max_error"].to_numpy(dtype=float)
        s = {"max_error": float(np.nanmax(errs)), "median_error": float(np.nanmedian(errs)),
             "sets_over_1e-9": int((errs > 1e-9).sum()), "not_converged": int((g["status"] != "ok").sum()),
             "sets": len(g)}
        summary[f"{m} {p}"] = s
        log(f"  {m:<28} {p if p != '{}' else '-':<22} {s['max_error']:10.1e} {s['median_error']:12.1e} "
            f"{s['sets_over_1e-9']:>11} {s['not_converged']:>13}")
    figure(summary, target)
    return {"summary": summary, "figure": "nist_errors.png"}


def figure(summary, target):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    labels = [k.replace(" {}", "").replace("circle.", "").replace('{"backend": "nlopt"}', "(nlopt)") for k in summary]
    fig, ax = plt.subplots(figsize=(8, 3.6))
    ax.bar(range(len(summary)), [v["max_error"] for v in summary.values()], color="tab:blue", label="largest")
    ax.bar(range(len(summary)), [v["median_error"] for v in summary.values()], color="tab:orange", width=0.5,
           label="median")
    ax.axhline(1e-9, color="k", ls="--", lw=0.8, label="1e-9 mm")
    ax.set_yscale("log")
    ax.set_xticks(range(len(summary)), labels, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("error against NIST [mm]")
    ax.set_title("NIST Circle2d, 30 sets: largest and median error of centre and radius", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, target / "nist_errors.png", dpi=110)
    plt.close(fig)


def report_tables(folder, f):
    """The tables a reader wants from this study (moved here from the report, which names no study)."""
    import pandas as pd

    from experiments.study import Table
    out = []
    rows = [{"method": k, "max error [mm]": v["max_error"], "median error [mm]": v["median_error"],
             "sets > 1e-9": v["sets_over_1e-9"], "not converged": v["not_converged"]}
            for k, v in f.get("summary", {}).items()]
    out.append(("NIST Circle2d (30 sets): error against the reference least-squares circle", pd.DataFrame(rows)))
    return [Table(caption=c, data=t) for c, t in out if t is not None and len(t)]
