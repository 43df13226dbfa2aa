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
import pandas as pd

from experiments.study import Analysis, ConfigError, Figure, Study, Table


def _folder() -> Path:
    """FITBENCH_NIST_DIR, refused in one line unless it holds converted sets (each nist_cir2d_*.json with its .csv)."""
    value = os.environ.get("FITBENCH_NIST_DIR")
    why = ("not set" if not value else f"{value!r} is not a folder" if not Path(value).is_dir() else None)
    if why is None:
        sets = sorted(Path(value).glob("nist_cir2d_*.json"))
        lone = [p.name for p in sets if not p.with_suffix(".csv").is_file()]
        why = (f"{value!r} holds no nist_cir2d_*.json" if not sets else
               f"{value!r} holds {lone[0]} without {Path(lone[0]).stem}.csv" if lone else None)
    if why:
        raise ConfigError(f"nist_circle needs FITBENCH_NIST_DIR set to the folder of nist_cir2d_*.csv/.json ({why}); "
                          "make them from NIST's Circle2d reference pairs with python -m datasets.nist_circle2d "
                          "CIRCLE2D_FOLDER OUT (docs/methods.md)")
    return Path(value)


def error_table(df):
    """Per method and parameters: largest and median error against NIST (centre coordinates and radius, mm), sets
    above 1e-9 mm, fits not converged."""
    df = df.copy()
    df["max_error"] = np.maximum(df["center_error_x"].abs().combine(df["center_error_y"].abs(), max),
                                 df["radius_error"].abs())
    rows = []
    for (m, p), g in df.groupby(["method", "params"], sort=False):
        errs = g["max_error"].to_numpy(dtype=float)
        rows.append({"method": m + ("" if p == "{}" else " " + p), "max_error": float(np.nanmax(errs)),
                     "median_error": float(np.nanmedian(errs)), "sets_over_1e-9": int((errs > 1e-9).sum()),
                     "not_converged": int((g["status"] != "ok").sum()), "sets": len(g)})
    return pd.DataFrame(rows)


def figure(table, target):
    from experiments.render import style
    plt = style.plotting()
    labels = [style.short_label(m).replace('{"backend": "nlopt"}', "(nlopt)") for m in table["method"]]
    x = np.arange(len(table))
    with style.figure_style():
        fig, ax = plt.subplots(figsize=style.size(1.0, 0.45))
        ax.bar(x, table["max_error"], color=style.PALETTE[0], label="largest")
        ax.bar(x, table["median_error"], color=style.PALETTE[1], width=0.5, label="median")
        ax.axhline(1e-9, color="0.2", ls="--", lw=0.8, label="1e-9 mm")
        ax.set_yscale("log")
        ax.set_xticks(x, labels, rotation=35, ha="right")
        ax.set_ylabel("error against NIST [mm]")
        ax.grid(axis="x", visible=False)
        style.legend_outside(fig, ncol=3)
        style.save(fig, target / "nist_errors.png")
        plt.close(fig)


class NistCircleStudy(Study):
    """The ``nist_circle`` study (see the module's docstring)."""

    values = None  # its analysis names its values

    def validate(self, cfg, where):
        cfg.expand_methods()

    def data_sets(self, cfg):
        """One data set per converted Circle2d set of ``FITBENCH_NIST_DIR``, its truth NIST's reference fit."""
        specs = []
        for i, meta_path in enumerate(sorted(_folder().glob("nist_cir2d_*.json"))):
            try:
                meta = json.loads(meta_path.read_text(encoding="utf-8"))
                ref = meta["reference_least_squares"]
                truth = {"family": "circle", "center": [float(Decimal(v)) for v in ref["center"]],
                         "radius": float(Decimal(ref["diameter"])) / 2}
                label = str(meta["name"])
            except (OSError, UnicodeError, ValueError, KeyError, TypeError, ArithmeticError) as exc:
                raise ConfigError(f"nist_circle: {meta_path} is not a set python -m datasets.nist_circle2d makes "
                                  f"({type(exc).__name__}: {exc}); make the folder again with it") from None
            specs.append({"entry": i, "point": 0, "file": str(meta_path.with_suffix(".csv")), "truth": truth,
                          "label": label})
        return specs

    def tasks(self, cfg):
        out = []
        for spec in self.data_sets(cfg):
            for m, extra in cfg.expand_methods():
                out.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": spec, "repetition": 0,
                            "stream": [spec["entry"], 0, 0], "seed": cfg["seed"], "method": m,
                            "params": extra["params"], "timing": None})
        return out

    def analyse(self, df, cfg, target, log):
        """Error table, bar chart, findings: which methods match NIST's certified values to 1e-9 mm on every set."""
        table = error_table(df)
        log(table.to_string(index=False))
        figure(table, target)
        exact = [m for m, n, nc in zip(table["method"], table["sets_over_1e-9"], table["not_converged"]) if n == 0 and nc == 0]
        n_sets = int(table["sets"].max()) if len(table) else 0
        values = {"within_1e-9_on_every_set": exact, "sets": n_sets,
                  "max_error_mm": dict(zip(table["method"], table["max_error"]))}
        findings = (f"{len(exact)} of {len(table)} method variants match NIST's reference least-squares circle within "
                    f"1e-9 mm on all {n_sets} Circle2d sets ({', '.join(exact) or 'none'}); the others minimise other "
                    "objectives or stop earlier (their error is their distance from the least-squares circle).")
        shown = table.rename(columns={"max_error": "largest error [mm]", "median_error": "median error [mm]",
                                      "sets_over_1e-9": "sets > 1e-9 mm", "not_converged": "not converged"})
        caption = (f"Error of each circle method against NIST's certified least-squares circles (Circle2d, {n_sets} sets): "
                   "largest absolute difference of the centre coordinates and the radius [mm]")
        fig = Figure(caption=f"Largest and median error [mm] against NIST's reference circles ({n_sets} Circle2d sets), "
                             "log scale, with the 1e-9 mm line", file="nist_errors.png")
        return Analysis(tables=[Table(caption=caption, data=shown, unit="mm", digits=3)], figures=[fig], values=values,
                        findings=findings)
