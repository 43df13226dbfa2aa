"""Study ``magnification``: continuity (largest magnified step / (eta x largest measured step)) and loops
(self-intersections) of the magnified trajectory, per example and algorithm, with side-by-side figures."""
from __future__ import annotations

import numpy as np

import methods
from datasets.contouring import EXAMPLES
from experiments import engine
from experiments.engine import ConfigError
from methods.magnify import MagnifyInput
from experiments.study import Analysis, Figure, Study, Table, save_csv


def variant_params(variant: dict, eta: float) -> dict:
    """The method parameters of a [[variants]] entry for an example magnified by ``eta``."""
    params = dict(variant.get("params", {}))
    for k in variant.get("times_eta", []):
        params[k] = params[k] * eta
    return {"eta": eta, **params}


def _panels(cfg):
    """The declared [[trajectories]] as panels of figures.magnification_trajectories."""
    variants = {v["label"]: v for v in cfg["variants"]}
    return [{"example": t["example"], "eta": cfg["examples"][t["example"]], "method": variants[lab]["method"],
             "params": {k: v for k, v in variant_params(variants[lab], cfg["examples"][t["example"]]).items()
                        if k != "eta"},
             "title": f"{t['example']}:\n{lab}", "box": tuple(t["box"]) if t.get("box") else None}
            for t in cfg.get("trajectories", []) for lab in t["variants"]]


class MagnificationStudy(Study):
    """The ``magnification`` study (see the module's docstring)."""

    values = None  # its analysis names its values

    #: this study's own config keys (JSON Schema, merged into the schema; validate() checks the values)
    config_schema = {
        "examples": {"type": "object", "minProperties": 1},
        # the algorithm variants compared: a label (the rows' method column), a magnify method and its parameters;
        # ``times_eta`` names parameters multiplied by the example's eta (e.g. delta_emax = 1.2 -> 1.2 eta e_max)
        "variants": {"type": "array", "minItems": 1, "items": {
            "type": "object", "required": ["label", "method"], "additionalProperties": False,
            "properties": {"label": {"type": "string", "minLength": 1}, "method": {"type": "string", "minLength": 1},
                           "params": {"type": "object"}, "times_eta": {"type": "array", "items": {"type": "string"}}}}},
        # the trajectories drawn side by side: an example, the variants (labels) and a zoom box [x0, x1, y0, y1] in mm
        "trajectories": {"type": "array", "items": {
            "type": "object", "required": ["example", "variants"], "additionalProperties": False,
            "properties": {"example": {"type": "string"}, "variants": {"type": "array", "minItems": 1,
                                                                       "items": {"type": "string"}},
                           "box": {"type": "array", "items": {"type": "number"}, "minItems": 4, "maxItems": 4}}}},
    }

    def validate(self, cfg, where):
        bad = set(cfg.get("examples", {})) - set(EXAMPLES)
        if bad or not cfg.get("examples"):
            raise ConfigError(f"{where}: examples must name some of {', '.join(EXAMPLES)} (got {sorted(bad) or 'none'})")
        if not cfg.get("variants"):
            raise ConfigError(f"{where}: needs [[variants]] tables (label, method, params)")
        labels = [v["label"] for v in cfg["variants"]]
        if len(set(labels)) != len(labels):
            raise ConfigError(f"{where}: variant labels must be unique, got {labels}")
        for j, v in enumerate(cfg["variants"]):
            try:
                spec = methods.get(v["method"])
            except methods.UnknownMethodError as exc:
                raise ConfigError(f"{where} variants[{j}]: {exc}") from None
            unknown = (set(v.get("params", {})) | set(v.get("times_eta", []))) - set(spec.defaults) | (
                set(v.get("times_eta", [])) - set(v.get("params", {})))
            if unknown or "eta" in v.get("params", {}):
                raise ConfigError(f"{where} variants[{j}]: {spec.id} parameter(s) {', '.join(sorted(unknown)) or 'eta'} "
                                  f"cannot be set here (eta comes from [examples]; times_eta names given params); its "
                                  f"parameters are: {', '.join(k for k in spec.defaults if k != 'eta')}")
        for j, t in enumerate(cfg.get("trajectories", [])):
            if t["example"] not in cfg["examples"] or set(t["variants"]) - set(labels):
                raise ConfigError(f"{where} trajectories[{j}]: example must be one of [examples] and variants among the "
                                  f"[[variants]] labels; got {t['example']!r}, {t['variants']}")

    def tasks(self, cfg):
        out = []
        for i, (name, eta) in enumerate(cfg["examples"].items()):
            for v in cfg["variants"]:
                out.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": {"entry": i, "point": 0, "label": name},
                            "repetition": 0, "stream": [i, 0, 0], "seed": cfg["seed"], "method": v["label"],
                            "params": {}, "timing": None, "x_eta": float(eta), "x_variant": v})
        return out

    def execute(self, task):
        """One row per (example, variant), built on the engine's identity columns (engine.base_row)."""
        name, eta, variant = task["dataset"]["label"], task["x_eta"], task["x_variant"]
        row = {**engine.base_row(task), "param_eta": eta}
        try:
            ref, meas = EXAMPLES[name]()
            res = methods.fit(variant["method"], MagnifyInput(ref, meas), **variant_params(variant, eta))
        except methods.InvalidInputError as exc:
            return {**row, "status": "skipped", "message": str(exc)}
        return {**row, "delta_mm": res.extra.get("delta"), "status": "ok" if res.converged else "not converged",
                "message": res.message, "max_error_um": res.extra["max_contouring_error"] * 1e3,
                "continuity": res.extra["continuity"], "loops": res.extra["self_intersections"],
                "nearest_point_used": res.extra.get("nearest_point_used", 0)}

    def analyse(self, df, cfg, target, log):
        """Continuity / loops table from the rows, the redrawn continuity chart and trajectories; findings:
        which algorithm variants stay continuous and loop-free on every example they apply to."""
        from experiments.render import figures

        table = df.pivot_table(index="dataset", columns="method", values=["continuity", "loops"], sort=False)
        save_csv(table, target / "metrics.csv", float_format="%.4g")
        cells = df.assign(cell=[("skipped" if st != "ok" else f"{c:.2f} / {int(lo)}")
                                for st, c, lo in zip(df["status"], df["continuity"], df["loops"])])
        piv = cells.pivot_table(index="dataset", columns="method", values="cell", aggfunc="first", sort=False)
        labels = [v["label"] for v in cfg["variants"]]
        piv = piv[[v for v in labels if v in piv.columns]].rename_axis("example").reset_index()
        log(piv.to_string(index=False))
        figures.magnification_continuity(df, target / "magnification_continuity.png")
        panels = _panels(cfg)
        if panels:
            figures.magnification_trajectories(panels, target / "magnification.png")
        ok = df[df["status"] == "ok"]
        clean = {}
        for label, g in ok.groupby("method", sort=False):
            clean[label] = int(((g["continuity"] <= 1.0 + 1e-9) & (g["loops"] == 0)).sum())
        applied = ok.groupby("method", sort=False).size()
        values = {"continuous_loop_free": clean, "applicable": applied.to_dict(),
                  "skipped": df[df["status"] != "ok"].groupby("method").size().to_dict()}
        findings = ("Examples where the magnified trajectory is continuous (continuity ≤ 1) and has no loops, out of "
                    "those the algorithm applies to: " + "; ".join(f"{lab}: {clean[lab]} of {applied[lab]}"
                                                                  for lab in labels if lab in clean) + ".")
        caption = (f"Continuity (largest magnified step / (eta x largest measured step); about 1 or less: continuous) and "
                   f"loops (self-intersections) of the magnified trajectory, as 'continuity / loops', for "
                   f"{len(cfg['examples'])} contouring examples (eta 50 to 1000, dimensionless); 'skipped': the algorithm "
                   "does not apply")
        figs = [Figure(caption="Continuity (left, log scale) and loops (right) of the magnified trajectory per contouring "
                               "example and algorithm variant", file="magnification_continuity.png")]
        if panels:
            figs.append(Figure(caption="Magnified trajectories (positions in mm, errors magnified by η) by the conventional "
                                       "nearest-point rule and by offset-algorithm variants", file="magnification.png"))
        return Analysis(tables=[Table(caption=caption, data=piv)], figures=figs, values=values, findings=findings)
