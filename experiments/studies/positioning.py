"""Study ``positioning``: Monte Carlo coverage of the true deviation curve (approach '+') by three bands:
the standard's point-wise evaluation (mean +- 2 s at the targets, linear in between, the view of the
positioning paper's figure 2), an ordinary least-squares cubic, and the paper's GLS cubic with
U(P) = 2 sqrt(x^T Cov x) (its figure 3). Positions are drawn uniformly along the travel."""
from __future__ import annotations

import numpy as np
import pandas as pd

import methods
from datasets.positioning import axis_test
from experiments.engine import ConfigError
from methods.positioning.model import evaluate_band
from experiments.study import save_csv, save_figure, atomic_path

BANDS = ("iso230-2 point-wise (mean +- 2s)", "OLS cubic", "GLS cubic (paper)")


def validate(cfg, where):
    sc = cfg.get("scenarios")
    if not isinstance(sc, list) or not sc:
        raise ConfigError(f"{where}: needs [[scenarios]] tables")
    allowed = {"runs", "instrument_sd", "repeatability", "mpe", "periodic_amplitude", "periodic_period", "targets",
               "reversal"}
    for i, s in enumerate(sc):
        bad = set(s.get("params", {})) - allowed
        if bad or "label" not in s:
            raise ConfigError(f"{where} scenarios[{i}]: needs a label; unknown params {sorted(bad)}")


def tasks(cfg):
    out = []
    for i, s in enumerate(cfg["scenarios"]):
        spec = {"entry": i, "point": 0, "scenario": s, "label": s["label"]}
        for r in range(cfg["repetitions"]):
            for b, band in enumerate(BANDS):
                out.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": spec, "repetition": r,
                            "stream": [i, 0, r], "seed": cfg["seed"], "method": band, "params": {}, "timing": None,
                            "x_positions": cfg.get("positions_per_test", 50)})
    return out


def execute(task):
    s = task["dataset"]["scenario"]
    rng = np.random.default_rng(np.random.SeedSequence(task["seed"], spawn_key=tuple(task["stream"])))
    data, truth = axis_test(rng=rng, **s["params"])
    P = rng.uniform(data.targets.min(), data.targets.max(), task["x_positions"])
    band = task["method"]
    if band.startswith("iso230"):
        per = methods.fit("positioning.iso230_2", data).per_target
        v = np.interp(P, data.targets, per["mean_up"])
        U = np.interp(P, data.targets, 2 * per["s_up"])
    elif band.startswith("OLS"):
        v, U = evaluate_band(methods.fit("positioning.ols_polynomial", data).polynomial["up"], P)
    else:
        res = methods.fit("positioning.gls_polynomial", data, instrument_u=s.get("instrument_u"), mpe=s.get("mpe"))
        v, U = evaluate_band(res.polynomial["up"], P)
    err = v - truth["up"](P)
    return {"study": task["study"], "dataset": task["dataset"]["label"], "repetition": task["repetition"],
            "seed": task["seed"], "data_stream": ".".join(map(str, task["stream"])), "method": band, "params": "{}",
            "status": "ok", "message": "", "coverage": float(np.mean(np.abs(err) <= U)),
            "band_halfwidth_mean": float(np.mean(U)), "error_rms": float(np.sqrt(np.mean(err ** 2)))}


def finalize(df, cfg, target, log):
    table = df.groupby(["dataset", "method"], sort=False).agg(coverage=("coverage", "mean"),
                                                              halfwidth_um=("band_halfwidth_mean", "mean"),
                                                              error_rms_um=("error_rms", "mean")).reset_index()
    table["halfwidth_um"] *= 1e3
    table["error_rms_um"] *= 1e3
    save_csv(table, target / "coverage.csv", index=False, float_format="%.4g")
    log(f"  {'scenario':<55} {'band':<34} {'coverage':>8} {'half-width':>10} {'RMS error':>9}")
    for r in table.itertuples():
        log(f"  {r.dataset:<55} {r.method:<34} {r.coverage:8.3f} {r.halfwidth_um:8.2f} um {r.error_rms_um:7.2f} um")
    example(cfg, target)
    return {"coverage": table.to_dict(orient="records"), "figure": "positioning.png", "example": "example.png"}


def example(cfg, target):
    """The paper's figures 2 and 3 for one synthetic axis with the periodic error, and the coverage bars."""
    from methods.positioning.report import plot
    s = cfg["scenarios"][-1]
    data, _ = axis_test(rng=np.random.default_rng(cfg["seed"]), **s["params"])
    res = methods.fit("positioning.gls_polynomial", data, instrument_u=s.get("instrument_u"), mpe=s.get("mpe"))
    with atomic_path(target / "example.png") as tmp:
        plot(res, tmp, title=f"synthetic axis: {s['label']}")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cov = pd.read_csv(target / "coverage.csv")
    scen = list(dict.fromkeys(cov["dataset"]))
    fig, ax = plt.subplots(figsize=(10, 4))
    w = 0.8 / len(BANDS)
    for b, band in enumerate(BANDS):
        vals = [cov[(cov.dataset == sname) & (cov.method == band)]["coverage"].mean() for sname in scen]
        ax.bar(np.arange(len(scen)) + (b - 1) * w, vals, w, label=band)
    ax.axhline(0.95, color="k", lw=0.8, ls="--", label="95 %")
    ax.set_xticks(np.arange(len(scen)), [sname.replace(", ", ",\n", 1) for sname in scen], fontsize=7)
    ax.set_ylabel("coverage of the true curve")
    ax.set_ylim(0, 1.05)
    ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    save_figure(fig, target / "positioning.png", dpi=110)
    plt.close(fig)


def report_tables(folder, f):
    """The tables a reader wants from this study (moved here from the report, which names no study)."""
    import pandas as pd

    from experiments.study import Table
    out = []
    t = pd.DataFrame(f.get("coverage", []))
    if len(t):
        t = t.rename(columns={"dataset": "scenario", "method": "band", "halfwidth_um": "half-width [um]",
                              "error_rms_um": "RMS error [um]"}).round(3)
    out.append(("Coverage of the true deviation curve by the bands (1000 synthetic axes per scenario)", t))
    return [Table(caption=c, data=t) for c, t in out if t is not None and len(t)]
