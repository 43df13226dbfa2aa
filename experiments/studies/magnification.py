"""Study ``magnification``: continuity (largest magnified step / (eta x largest measured step)) and loops
(self-intersections) of the magnified trajectory, per example and algorithm, with side-by-side figures."""
from __future__ import annotations

import numpy as np
import pandas as pd

import methods
from datasets.contouring import EXAMPLES
from experiments.engine import ConfigError
from methods.magnify import MagnifyInput
from experiments.study import save_csv, save_figure

VARIANTS = {  # label -> (method, selection, delta rule)
    "nearest (conventional)": ("magnify.nearest", None, None),
    "offset as printed, delta = 10 e_max": ("magnify.offset", "nearest_of_both", ("e", 10.0)),
    "offset same side, delta = 2 e_max": ("magnify.offset", "same_side", ("e", 2.0)),
    "offset same side, delta = 10 e_max": ("magnify.offset", "same_side", ("e", 10.0)),
    "offset same side, delta = 1.2 eta e_max": ("magnify.offset", "same_side", ("eta_e", 1.2)),
}


def validate(cfg, where):
    bad = set(cfg.get("examples", {})) - set(EXAMPLES)
    if bad or not cfg.get("examples"):
        raise ConfigError(f"{where}: examples must name some of {', '.join(EXAMPLES)} (got {sorted(bad) or 'none'})")


def tasks(cfg):
    out = []
    for i, (name, eta) in enumerate(cfg["examples"].items()):
        for label in VARIANTS:
            out.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": {"entry": i, "point": 0, "label": name},
                        "repetition": 0, "stream": [i, 0, 0], "seed": cfg["seed"], "method": label, "params": {},
                        "timing": None, "x_eta": float(eta)})
    return out


def run_variant(name, label, eta):
    ref, meas = EXAMPLES[name]()
    data = MagnifyInput(ref, meas)
    method, selection, rule = VARIANTS[label]
    params = {"eta": eta}
    emax = methods.fit("magnify.nearest", data, eta=eta).form_error
    if method == "magnify.offset":
        params["selection"] = selection
        params["delta"] = rule[1] * emax * (eta if rule[0] == "eta_e" else 1.0)
    return data, methods.fit(method, data, **params), params, emax


def execute(task):
    name, label, eta = task["dataset"]["label"], task["method"], task["x_eta"]
    try:
        _, res, params, emax = run_variant(name, label, eta)
    except methods.InvalidInputError as exc:
        return {"study": task["study"], "dataset": name, "repetition": 0, "seed": task["seed"], "data_stream": "0",
                "method": label, "params": "{}", "param_eta": eta, "status": "skipped", "message": str(exc)}
    return {"study": task["study"], "dataset": name, "repetition": 0, "seed": task["seed"], "data_stream": "0",
            "method": label, "params": "{}", "param_eta": eta, "param_delta": params.get("delta"),
            "status": "ok" if res.converged else "not converged", "message": res.message,
            "max_error_um": emax * 1e3, "continuity": res.extra["continuity"], "loops": res.extra["self_intersections"],
            "nearest_point_used": res.extra.get("nearest_point_used", 0)}


def finalize(df, cfg, target, log):
    table = df.pivot_table(index="dataset", columns="method", values=["continuity", "loops"], sort=False)
    save_csv(table, target / "metrics.csv", float_format="%.4g")
    labels = list(VARIANTS)
    log("  continuity (<= ~1: continuous) / loops, per example and algorithm:")
    log("  " + f"{'example':<26}" + "".join(f"{lab[:22]:>24}" for lab in labels))
    for name in dict.fromkeys(df["dataset"]):
        g = df[df["dataset"] == name].set_index("method")
        cells = []
        for lab in labels:
            c, lo = g.loc[lab].get("continuity"), g.loc[lab].get("loops")
            cells.append(f"{'skipped':>24}" if c is None or c != c else f"{c:>16.2f} / {int(lo):<5d}")
        log("  " + f"{name:<26}" + "".join(cells))
    figures(cfg, target)
    return {"metrics": "metrics.csv", "figure": "magnification.png"}


def figures(cfg, target):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = [("corner_inside_convex", ["nearest (conventional)", "offset as printed, delta = 10 e_max",
                                       "offset same side, delta = 10 e_max"], None),
             ("free_form_0.1mm", ["nearest (conventional)", "offset same side, delta = 2 e_max",
                                  "offset same side, delta = 1.2 eta e_max"], (15.0, 16.6, 1.65, 2.45))]
    fig, axes = plt.subplots(len(shown), 3, figsize=(13, 8.4))
    for row, (name, labels, box) in enumerate(shown):
        for col, label in enumerate(labels):
            data, res, params, emax = run_variant(name, label, cfg["examples"][name])
            ax = axes[row, col]
            ax.plot(*data.reference.T, color="0.6", lw=1.0)
            ax.plot(*res.points.T, lw=0.8, color="tab:blue")
            if box:  # a zoom (the loops are small); else the whole magnified corner
                ax.set_xlim(box[0], box[1])
                ax.set_ylim(box[2], box[3])
            ax.set_aspect("equal")
            ax.set_title(f"{name}: {label}\ncontinuity {res.extra['continuity']:.2f}, loops {res.extra['self_intersections']}",
                         fontsize=8)
    fig.tight_layout()
    save_figure(fig, target / "magnification.png", dpi=110)
    plt.close(fig)


def report_tables(folder, f):
    """The tables a reader wants from this study (moved here from the report, which names no study)."""
    import pandas as pd

    from experiments.study import Table
    out = []
    df = pd.read_csv(folder / "results.csv")
    df["cell"] = df.apply(lambda r: "skipped" if r["status"] != "ok" else f"{r['continuity']:.2f} / {int(r['loops'])}", axis=1)
    piv = df.pivot_table(index="dataset", columns="method", values="cell", aggfunc="first", sort=False).reset_index()
    out.append(("Continuity (about 1 or less: continuous) / loops of the magnified trajectories", piv))
    return [Table(caption=c, data=t) for c, t in out if t is not None and len(t)]
