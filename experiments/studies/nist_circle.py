"""Study ``nist_circle``: every circle method against NIST's Circle2d least-squares reference fits.

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

import methods
from datasets import read_points
from experiments.config import ConfigError
from experiments.studies.published_circle import method_runs, safe_fit


def _folder() -> Path:
    value = os.environ.get("FITBENCH_NIST_DIR")
    if not value or not Path(value).is_dir():
        raise ConfigError("nist_circle needs FITBENCH_NIST_DIR set to the folder of nist_cir2d_*.csv/.json "
                          f"(got {value!r})")
    return Path(value)


def run(cfg: dict, log=print):
    folder = _folder()
    rows = []
    runs = method_runs(cfg)
    for meta_path in sorted(folder.glob("nist_cir2d_*.json")):
        meta = json.loads(meta_path.read_text())
        pts = read_points(meta_path.with_suffix(".csv"))
        ref = meta["reference_least_squares"]
        center = np.array([float(Decimal(v)) for v in ref["center"]])
        radius = float(Decimal(ref["diameter"])) / 2
        for mid, params in runs:
            res, problem = safe_fit(mid, pts, params)
            if res is None:
                rows.append({"study": cfg["name"], "dataset": meta["name"], "n_points": len(pts), "method": mid,
                             "params": json.dumps(params, sort_keys=True), "status": problem.split(":", 1)[0],
                             "message": problem, "max_error": float("nan")})
                continue
            err = max(float(np.abs(np.array(res.center) - center).max()), abs(res.radius - radius))
            rows.append({"study": cfg["name"], "dataset": meta["name"], "n_points": len(pts), "method": mid,
                         "params": json.dumps(params, sort_keys=True),
                         "status": "ok" if res.converged else "not converged", "message": res.message,
                         "center_error": float(np.abs(np.array(res.center) - center).max()),
                         "radius_error": abs(res.radius - radius), "max_error": err,
                         "iterations": res.iterations, "nfev": res.nfev})
    summary = {}
    log(f"  {'method':<28} {'params':<16} {'max error':>10} {'median error':>12} {'sets > 1e-9':>11} {'not converged':>13}")
    for mid, params in runs:
        key = json.dumps(params, sort_keys=True)
        mine = [r for r in rows if r["method"] == mid and r["params"] == key]
        errs = np.array([r["max_error"] for r in mine if r["status"] in ("ok", "not converged")])
        errs = errs if errs.size else np.array([np.nan])
        label = ",".join(f"{k}={v}" for k, v in params.items()) or "-"
        summary[f"{mid} {label}"] = {"max_error": float(errs.max()), "median_error": float(np.median(errs)),
                                      "sets_over_1e-9": int((errs > 1e-9).sum()),
                                      "not_converged": sum(r["status"] != "ok" for r in mine), "sets": len(mine)}
        s = summary[f"{mid} {label}"]
        log(f"  {mid:<28} {label:<16} {s['max_error']:10.1e} {s['median_error']:12.1e} {s['sets_over_1e-9']:>11} {s['not_converged']:>13}")
    return rows, {"summary": summary}
