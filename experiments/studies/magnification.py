"""Study ``magnification``: continuity (largest magnified step / (eta x largest measured step)) and loops
(self-intersections) of the magnified trajectory, per example and algorithm, with side-by-side figures."""
from __future__ import annotations

import numpy as np

import methods
from datasets.contouring import EXAMPLES
from experiments import engine
from experiments.engine import ConfigError
from methods.magnify import MagnifyInput
from experiments.study import Analysis, Figure, Table, save_csv

#: this study's own config keys (JSON Schema, merged by experiments/schema.py; validate() checks the values)
CONFIG_SCHEMA = {
    "examples": {"type": "object", "minProperties": 1},
}

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
    """One row per (example, variant), built on the engine's identity columns (engine.base_row)."""
    name, label, eta = task["dataset"]["label"], task["method"], task["x_eta"]
    row = {**engine.base_row(task), "param_eta": eta}
    try:
        _, res, params, emax = run_variant(name, label, eta)
    except methods.InvalidInputError as exc:
        return {**row, "status": "skipped", "message": str(exc)}
    return {**row, "param_delta": params.get("delta"), "status": "ok" if res.converged else "not converged",
            "message": res.message, "max_error_um": emax * 1e3, "continuity": res.extra["continuity"],
            "loops": res.extra["self_intersections"], "nearest_point_used": res.extra.get("nearest_point_used", 0)}


#: the trajectories drawn side by side: (example, variants, zoom box in mm or None)
SHOWN = [("corner_inside_convex", ["nearest (conventional)", "offset as printed, delta = 10 e_max",
                                   "offset same side, delta = 10 e_max"], None),
         ("free_form_0.1mm", ["nearest (conventional)", "offset same side, delta = 2 e_max",
                              "offset same side, delta = 1.2 eta e_max"], (15.0, 16.6, 1.9, 3.0))]


def _panel(name, label, eta, box):
    method, selection, rule = VARIANTS[label]
    params = {} if method == "magnify.nearest" else {"selection": selection, "delta_emax": rule[1],
                                                     "delta_times_eta": rule[0] == "eta_e"}
    return {"example": name, "eta": eta, "method": method, "params": params, "title": f"{name}:\n{label}", "box": box}


def analyse(df, cfg, target, log):
    """Continuity / loops table from the rows, the redrawn continuity chart and trajectories; findings:
    which algorithm variants stay continuous and loop-free on every example they apply to."""
    from experiments.render import figures

    table = df.pivot_table(index="dataset", columns="method", values=["continuity", "loops"], sort=False)
    save_csv(table, target / "metrics.csv", float_format="%.4g")
    cells = df.assign(cell=[("skipped" if st != "ok" else f"{c:.2f} / {int(lo)}")
                            for st, c, lo in zip(df["status"], df["continuity"], df["loops"])])
    piv = cells.pivot_table(index="dataset", columns="method", values="cell", aggfunc="first", sort=False)
    piv = piv[[v for v in VARIANTS if v in piv.columns]].rename_axis("example").reset_index()
    log(piv.to_string(index=False))
    figures.magnification_continuity(df, target / "magnification_continuity.png")
    figures.magnification_trajectories([_panel(n, lab, cfg["examples"][n], box) for n, labs, box in SHOWN
                                        if n in cfg["examples"] for lab in labs], target / "magnification.png")
    ok = df[df["status"] == "ok"]
    clean = {}
    for label, g in ok.groupby("method", sort=False):
        clean[label] = int(((g["continuity"] <= 1.0 + 1e-9) & (g["loops"] == 0)).sum())
    applied = ok.groupby("method", sort=False).size()
    values = {"continuous_loop_free": clean, "applicable": applied.to_dict(),
              "skipped": df[df["status"] != "ok"].groupby("method").size().to_dict()}
    findings = ("Examples where the magnified trajectory is continuous (continuity ≤ 1) and has no loops, out of "
                "those the algorithm applies to: " + "; ".join(f"{lab}: {clean[lab]} of {applied[lab]}"
                                                              for lab in VARIANTS if lab in clean) + ".")
    caption = (f"Continuity (largest magnified step / (eta x largest measured step); about 1 or less: continuous) and "
               f"loops (self-intersections) of the magnified trajectory, as 'continuity / loops', for "
               f"{len(cfg['examples'])} contouring examples (eta 50 to 1000, dimensionless); 'skipped': the algorithm "
               "does not apply")
    figs = [Figure(caption="Continuity (left, log scale) and loops (right) of the magnified trajectory per contouring "
                           "example and algorithm variant", file="magnification_continuity.png"),
            Figure(caption="Magnified trajectories (positions in mm, errors magnified by η) by the conventional "
                           "nearest-point rule and by offset-algorithm variants", file="magnification.png")]
    return Analysis(tables=[Table(caption=caption, data=piv)], figures=figs, values=values, findings=findings)
