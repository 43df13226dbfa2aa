"""Study ``positioning``: Monte Carlo coverage of the true deviation curve (approach '+') by three bands:
the standard's point-wise evaluation (mean +- 2 s at the targets, linear in between, the view of the
positioning paper's figure 2), an ordinary least-squares cubic, and the paper's GLS cubic with
U(P) = 2 sqrt(x^T Cov x) (its figure 3). Positions are drawn uniformly along the travel."""
from __future__ import annotations

import textwrap
from typing import Annotated, Any

import numpy as np
import pandas as pd
from pydantic import Field

import methods
from datasets.positioning import axis_test
from methods.positioning.model import evaluate_band
from experiments.render.text import joined
from experiments.outputs import save_csv
from experiments.rows import base_row
from experiments.study import Analysis, ConfigError, ConfigTable, Figure, Study, Table


#: the nominal coverage of a k = 2 band, and how many standard errors of the Monte-Carlo mean decide above / below it
NOMINAL, NOMINAL_SE = 0.95, 2.0


def example(cfg, target) -> str:
    """The paper's figures 2 and 3 for one synthetic axis with the periodic error; returns what the figure's right
    panel shows: the model's band, or the lack-of-fit test that rejects the model (then no band is drawn)."""
    from fitbench.plots.positioning import plot
    from experiments.render import style
    s = cfg["scenarios"][-1]
    data, _ = axis_test(rng=np.random.default_rng(cfg["seed"]), **s["params"])
    band = next(b for b in cfg["bands"] if b["label"] == cfg["example_band"])
    res = methods.fit(band["method"], data, **{k: s.get(k) for k in band.get("scenario_params", [])})
    plot(res, target / "example.png", title=f"synthetic axis: {s['label']}",
         save=lambda fig, path: style.save(fig, path, dpi=120))      # PNG and the vector PDF
    tests = {d: p.get("lack_of_fit") or {} for d, p in res.polynomial.items()}
    rejected = [d for d, t in tests.items() if t.get("rejected")]
    if not rejected:
        return f"the ISO 230-2 band and that of {band['label']}"
    worst = max(tests[d]["chi2_per_dof"] for d in rejected)
    return (f"the ISO 230-2 band; {band['label']}'s model is drawn without its band: its lack-of-fit test rejects it "
            f"(chi2/nu up to {worst:.3g} > {tests[rejected[0]]['critical']:.3g}), so its U(P) is not the uncertainty "
            f"along the travel")


class Band(ConfigTable):
    """A band compared: a label (the rows' method column), the positioning method that gives the band, and the
    scenario keys passed to it as parameters (e.g. the instrument's uncertainty for the GLS model)."""
    label: Annotated[str, Field(min_length=1)]
    method: Annotated[str, Field(min_length=1)]
    scenario_params: list[str] = None


class PositioningConfig(ConfigTable):
    """The keys of the positioning study."""
    scenarios: Annotated[list[dict[str, Any]], Field(min_length=1)]
    positions_per_test: Annotated[int, Field(ge=1)] = None
    bands: Annotated[list[Band], Field(min_length=1)]
    # the band whose model the example figure draws (the paper's figures 2 and 3), on the last scenario
    example_band: Annotated[str, Field(min_length=1)] = None


class PositioningStudy(Study):
    """The ``positioning`` study (see the module's docstring)."""

    values = None  # its analysis names its values

    #: this study's own config keys (typed; the schema is generated from the model)
    config_schema = PositioningConfig

    def validate(self, cfg, where):
        for j, b in enumerate(cfg["bands"]):  # types and presence: the schema (PositioningConfig)
            try:
                spec = methods.get(b["method"])
            except methods.UnknownMethodError as exc:
                raise ConfigError(f"{where} bands[{j}]: {exc}") from None
            unknown = set(b.get("scenario_params", [])) - set(spec.defaults)
            if unknown:
                raise ConfigError(f"{where} bands[{j}]: {spec.id} has no parameter(s) {', '.join(sorted(unknown))}")
        labels = [b["label"] for b in cfg["bands"]]
        if cfg.get("example_band") is not None and cfg["example_band"] not in labels:
            raise ConfigError(f"{where}: example_band must be one of the [[bands]] labels {labels}, got {cfg['example_band']!r}")
        sc = cfg["scenarios"]
        allowed = {"runs", "instrument_sd", "repeatability", "mpe", "periodic_amplitude", "periodic_period", "targets",
                   "reversal"}
        for i, s in enumerate(sc):
            bad = set(s.get("params", {})) - allowed
            if bad or "label" not in s:
                raise ConfigError(f"{where} scenarios[{i}]: needs a label; unknown params {sorted(bad)}")

    def tasks(self, cfg):
        out = []
        for i, s in enumerate(cfg["scenarios"]):
            spec = {"entry": i, "point": 0, "scenario": s, "label": s["label"]}
            for r in range(cfg["repetitions"]):
                for band in cfg["bands"]:
                    out.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": spec, "repetition": r,
                                "stream": [i, 0, r], "seed": cfg["seed"], "method": band["label"], "params": {},
                                "timing": None, "band": band, "x_positions": cfg.get("positions_per_test", 50)})
        return out

    def execute(self, task):
        s = task["dataset"]["scenario"]
        rng = np.random.default_rng(np.random.SeedSequence(task["seed"], spawn_key=tuple(task["stream"])))
        data, truth = axis_test(rng=rng, **s["params"])
        P = rng.uniform(data.targets.min(), data.targets.max(), task["x_positions"])
        band = task["band"]
        res = methods.fit(band["method"], data, **{k: s.get(k) for k in band.get("scenario_params", [])})
        if res.polynomial:  # a model: its value and expanded uncertainty U(P) = 2 sqrt(x^T Cov x)
            v, U = evaluate_band(res.polynomial["up"], P)
        else:  # the standard's point-wise evaluation: mean +- 2 s at the targets, linear in between
            per = res.per_target
            v = np.interp(P, data.targets, per["mean_up"])
            U = np.interp(P, data.targets, 2 * per["s_up"])
        err = v - truth["up"](P)
        return {**base_row(task), "status": "ok", "message": "", "coverage": float(np.mean(np.abs(err) <= U)),
                "band_halfwidth_mean": float(np.mean(U)), "error_rms": float(np.sqrt(np.mean(err ** 2)))}

    def analyse(self, df, cfg, target, log):
        """Coverage table (coverage.csv), the redrawn coverage figure, the example axis; findings: per band, in how
        many scenarios its mean coverage is above, below or (within NOMINAL_SE standard errors of the mean over the
        tests) undecided against the nominal 95 %."""
        table = df.groupby(["dataset", "method"], sort=False).agg(coverage=("coverage", "mean"),
                                                                  halfwidth_um=("band_halfwidth_mean", "mean"),
                                                                  error_rms_um=("error_rms", "mean")).reset_index()
        table["halfwidth_um"] *= 1e3
        table["error_rms_um"] *= 1e3
        save_csv(table, target / "coverage.csv", index=False, float_format="%.4g")
        for r in table.itertuples():
            log(f"  {r.dataset:<55} {r.method:<34} {r.coverage:8.3f} {r.halfwidth_um:8.2f} um {r.error_rms_um:7.2f} um")
        coverage_figure(table, target / "positioning.png")
        shows = example(cfg, target) if cfg.get("example_band") else None
        worst = table.groupby("method", sort=False)["coverage"].min()
        # a band's mean coverage against the nominal 95 %, counted only beyond NOMINAL_SE standard errors of the mean
        # over the tests (the noise study's rule): 95.48 % of 1000 tests is 95.5 +- 1.2 % (2 s.e.), undecided
        per_test = df.groupby(["dataset", "method"], sort=False)["coverage"]
        se = (per_test.std(ddof=1) / np.sqrt(per_test.count())).to_numpy()
        side = np.where(table["coverage"] - NOMINAL_SE * se >= NOMINAL, "above",
                        np.where(table["coverage"] + NOMINAL_SE * se < NOMINAL, "below", "undecided"))
        verdicts = table.assign(se=se, side=side)
        n_sc = table["dataset"].nunique()
        counts = {b: {k: int((g["side"] == k).sum()) for k in ("above", "undecided", "below")}
                  for b, g in verdicts.groupby("method", sort=False)}
        values = {"lowest_coverage": {b: float(v) for b, v in worst.items()},
                  "bands_at_nominal": [b for b, c in counts.items() if c["below"] == 0],
                  "mean_halfwidth_um": table.groupby("method", sort=False)["halfwidth_um"].mean().to_dict(),
                  "scenarios_vs_nominal": counts,
                  "coverage_se": {f"{r.dataset} | {r.method}": float(r.se) for r in verdicts.itertuples()}}
        low = worst.min()
        reps = int(per_test.count().max())

        def band_part(b, g):
            und = g[g["side"] == "undecided"]
            parts = [f"{k} in {counts[b][k]}" + (f" ({joined(f'{100 * r.coverage:.1f} ± {100 * NOMINAL_SE * r.se:.1f} %' for r in und.itertuples())})"
                                                 if k == "undecided" else "")
                     for k in ("above", "undecided", "below") if counts[b][k]]
            return f"{b} {', '.join(parts)}"
        findings = (f"Over {n_sc} scenarios ({reps} simulated tests each), the mean coverage of the true deviation curve "
                    f"against the nominal 95 %, counted above or below only beyond {NOMINAL_SE:g} standard errors "
                    f"(± {NOMINAL_SE:g} s.e. shown): "
                    + " / ".join(band_part(b, g) for b, g in verdicts.groupby("method", sort=False))
                    + f"; lowest coverage: {100 * low:.1f} % ({joined(b for b, v in worst.items() if v == low)}).")
        reps = int(df.groupby(["dataset", "method"]).size().max())
        shown = table.rename(columns={"dataset": "scenario", "method": "band", "halfwidth_um": "mean half-width [µm]",
                                      "error_rms_um": "RMS error [µm]"})
        shown["coverage"] = shown["coverage"] * 100   # unrounded: the report chooses the digits shown
        shown = shown.rename(columns={"coverage": "coverage [%]"})
        caption = (f"Coverage of the true deviation curve (approach +) by each band at {cfg.get('positions_per_test', 50)} "
                   f"random positions per test, mean band half-width and RMS error of the band's centre line; "
                   f"{reps} simulated ISO 230-2 axis tests per scenario")
        figs = [Figure(caption=f"Coverage of the true deviation curve by each band per scenario ({reps} simulated ISO 230-2 "
                               "axis tests each), with the nominal 95 %", file="positioning.png")]
        if cfg.get("example_band"):
            figs.append(Figure(caption=f"One simulated axis ({cfg['scenarios'][-1]['label']}): measured deviations [µm] "
                                       f"against the target position [mm], with {shows}", file="example.png"))
        return Analysis(tables=[Table(caption=caption, data=shown, unit="%, µm")], figures=figs, values=values,
                        findings=findings)


# ---------------------------------------------------------------- figures (drawn in experiments.render.style)
def coverage_figure(coverage: pd.DataFrame, path, *, nominal: float = 0.95):
    """Coverage of the true deviation curve by each band, per scenario: horizontal grouped bars (scenario
    names readable on the y axis), the nominal coverage as a line, the legend below the axes.
    ``coverage``: results/positioning/coverage.csv (dataset, method, coverage)."""
    from experiments.render import style
    plt = style.plotting()
    scen = list(dict.fromkeys(coverage["dataset"]))
    bands = list(dict.fromkeys(coverage["method"]))
    with style.figure_style():
        fig, ax = plt.subplots(figsize=style.size(1.0, 0.12 * len(scen) * len(bands) / 3 + 0.25))
        h = 0.8 / len(bands)
        y = np.arange(len(scen))[::-1]
        colours = style.category_styles(bands)
        for b, band in enumerate(bands):
            vals = [coverage[(coverage["dataset"] == s) & (coverage["method"] == band)]["coverage"].mean() for s in scen]
            kw = colours[band]
            bars = ax.barh(y + (len(bands) / 2 - b - 0.5) * h, vals, h, color=kw["color"], label=band.replace("+-", "±"))
            ax.bar_label(bars, labels=[f"{100 * v:.0f} %" for v in vals], padding=2, fontsize=8)
        ax.axvline(nominal, color="0.2", lw=0.9, ls="--", label=f"nominal {100 * nominal:.0f} %")
        ax.set_yticks(y, ["\n".join(textwrap.wrap(s.replace(" um", " µm"), 32)) for s in scen])
        ax.set_xlim(0, 1.12)
        ax.set_xticks(np.linspace(0, 1, 6), [f"{100 * v:.0f} %" for v in np.linspace(0, 1, 6)])
        ax.set_xlabel("share of positions where the band covers the true deviation curve")
        ax.grid(axis="y", visible=False)
        style.legend_outside(fig, ncol=2)
        return style.save(fig, path)
