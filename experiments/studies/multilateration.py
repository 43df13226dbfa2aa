"""Study ``multilateration``: the multilateration paper's comparison (Holub et al., Machines 2022, 10, 833,
tables 5-9 and figures 5-6) with the simulator's truth in place of the unavailable Trac-Cal software.

Every scheme runs on simulated LaserTRACER campaigns of the MCV 754 (Monte Carlo over the instrument's noise),
once locating the stations itself (step 1 + step 2) and once with the true stations given (step 2 alone).
Rows: station and dead-path errors, volumetric-error errors (raw and after the best rigid alignment, which
multilateration with self-located stations cannot observe), condition numbers (SVD and Theorem 1), the error
of the 21 geometric errors identified from the volumetric errors, runtime.
"""
from __future__ import annotations

import time

import numpy as np
import pandas as pd

import methods
from datasets import multilateration as sim
from experiments.engine import ConfigError
from methods.multilateration.kinematics import COMPONENTS, SQUARENESS, design_matrix, identify
from methods.multilateration.solvers import kabsch
from experiments.study import save_csv, save_figure

SCENARIO_KEYS = {"stations", "noise", "errors", "grid"}
MODES = ("located", "known")


def validate(cfg, where):
    sc = cfg.get("scenarios")
    if not isinstance(sc, list) or not sc:
        raise ConfigError(f"{where}: needs [[scenarios]] tables with a label and params")
    for i, s in enumerate(sc):
        bad = set(s.get("params", {})) - SCENARIO_KEYS
        if bad or "label" not in s:
            raise ConfigError(f"{where} scenarios[{i}]: needs a label; unknown params {sorted(bad)} "
                              f"(allowed: {sorted(SCENARIO_KEYS)})")
    for m in cfg.get("methods", []):
        methods.get(f"multilateration.{m}")


def _scenario(params):
    p = dict(params)
    if isinstance(p.get("stations"), list):
        p["stations"] = tuple(p["stations"])
    if "grid" in p:
        p["grid"] = tuple(p["grid"])
    if p.get("errors") == "none":
        p["errors"] = None
    return p


def tasks(cfg):
    out = []
    for i, s in enumerate(cfg["scenarios"]):
        reps = s.get("repetitions", cfg["repetitions"])
        for r in range(reps):
            for mode in MODES:
                for m in cfg["methods"]:
                    out.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": {"entry": i, "label": s["label"],
                                                                                      "params": s["params"]},
                                "repetition": r, "stream": [i, 0, r], "seed": cfg["seed"],
                                "method": f"multilateration.{m}", "params": {}, "timing": None,
                                "x_mode": mode})
    return out


def simulate(task):
    rng = np.random.default_rng(np.random.SeedSequence(task["seed"], spawn_key=tuple(task["stream"])))
    return sim.simulate(rng=rng, **_scenario(task["dataset"]["params"]))


def execute(task):
    data, truth = simulate(task)
    mode = task["x_mode"]
    if mode == "known":
        data = data.with_stations(truth["stations"])
    row = {"study": task["study"], "dataset": task["dataset"]["label"], "repetition": task["repetition"],
           "seed": task["seed"], "data_stream": ".".join(map(str, task["stream"])), "method": task["method"],
           "params": "{}", "stations": mode, "n_points": len(data.points), "n_stations": len(data.stations)}
    t0 = time.perf_counter()
    res = methods.fit(task["method"], data)
    row["runtime_s"] = time.perf_counter() - t0
    row.update(status="ok" if res.converged else "not converged", message="" if res.converged else res.message,
               converged=res.converged)
    row.update(metrics(res, data, truth, mode))
    return row


def metrics(res, data, truth, mode) -> dict:
    actual, stations = truth["actual"], truth["stations"]
    if res.method.endswith(".joint") and mode == "located":        # the joint result is aligned to the nominal grid
        R, t = kabsch(actual, data.points)
        actual = actual @ R.T + t
        stations = np.column_stack([stations[:, :3] @ R.T + t, stations[:, 3]])
    out = {}
    if mode == "located":
        out["station_error_um"] = 1e3 * float(np.max(np.linalg.norm(res.stations[:, :3] - stations[:, :3], axis=1)))
        out["dead_path_error_um"] = 1e3 * float(np.max(np.abs(res.stations[:, 3] - stations[:, 3])))
    e = np.linalg.norm(res.points - actual, axis=1)
    out["volumetric_error_rms_um"] = 1e3 * float(np.sqrt(np.mean(e ** 2)))
    out["volumetric_error_max_um"] = 1e3 * float(e.max())
    R, t = kabsch(res.points, truth["actual"])
    ea = np.linalg.norm(res.points @ R.T + t - truth["actual"], axis=1)
    out["aligned_error_rms_um"] = 1e3 * float(np.sqrt(np.mean(ea ** 2)))
    for step in ("stations", "points"):
        c = res.condition_numbers.get(step)
        if c is not None:
            out[f"kappa_{step}"] = float(np.median(c["svd"]))
            out[f"kappa_{step}_max"] = float(np.max(c["svd"]))
            out[f"kappa_{step}_theorem1"] = float(np.median(c["theorem1"]))
    # the 21 errors from these volumetric errors (a rigid motion absorbed: it is not observable)
    model = truth["model"]
    if model is not None:
        ident = identify(truth["axes"], truth["offsets"], res.volumetric_errors, degree=model.degree, rigid=True)
        G = design_matrix(truth["axes"], truth["offsets"], model.degree, rigid=False)
        diff = (G @ (ident.vector[:-6] - model.vector())).reshape(-1, 3)
        out["model_error_rms_um"] = 1e3 * float(np.sqrt(np.mean(np.sum(diff ** 2, axis=1))))
        rel = [np.max(np.abs(ident.model.coefficients[n] - model.coefficients[n])) / np.max(np.abs(model.coefficients[n]))
               for n in COMPONENTS]
        rel += [abs(ident.model.squareness[n] - model.squareness[n]) / abs(model.squareness[n]) for n in SQUARENESS]
        out["identified_max_relative_error"] = float(np.max(rel))
        z = (ident.vector[:-6] - model.vector()) / ident.std[:-6]
        out["identified_within_2u"] = float(np.mean(np.abs(z) <= 2))
    return out


# ---------------------------------------------------------------- tables and figures

def finalize(df, cfg, target, log):
    ok = df[df["status"] == "ok"].copy()
    ok["method"] = ok["method"].str.replace("multilateration.", "", regex=False)
    cols = ["station_error_um", "dead_path_error_um", "volumetric_error_rms_um", "volumetric_error_max_um",
            "aligned_error_rms_um", "model_error_rms_um", "identified_max_relative_error", "identified_within_2u",
            "kappa_stations", "kappa_stations_theorem1", "kappa_points", "kappa_points_theorem1", "runtime_s"]
    cols = [c for c in cols if c in ok.columns]
    acc = ok.groupby(["dataset", "stations", "method"], sort=False)[cols].median().reset_index()
    acc.insert(3, "runs", ok.groupby(["dataset", "stations", "method"], sort=False).size().to_numpy())
    save_csv(acc, target / "accuracy.csv", index=False, float_format="%.6g")
    log(f"  {'scenario':<62} {'stations':<8} {'method':<16} {'station um':>10} {'vol RMS um':>10} {'aligned':>8} "
        f"{'kappa st':>9} {'kappa pt':>9}")
    for r in acc.itertuples():
        log(f"  {r.dataset[:62]:<62} {r.stations:<8} {r.method:<16} {getattr(r, 'station_error_um', np.nan):10.3f} "
            f"{r.volumetric_error_rms_um:10.3f} {r.aligned_error_rms_um:8.3f} {getattr(r, 'kappa_stations', np.nan):9.3g} "
            f"{r.kappa_points:9.3g}")
    findings = {"accuracy": acc.to_dict(orient="records")}
    findings["stations_table"] = stations_table(cfg, target)
    findings["rounding"] = rounding(cfg)
    findings["winner"] = winner(acc)
    figure_axis_line(cfg, target)
    figure_kappa(acc, target)
    findings["figure"] = "multilateration.png"
    findings["example"] = "x_axis.png"
    return findings


def _first_noisy(cfg):
    for i, s in enumerate(cfg["scenarios"]):
        p = s["params"]
        if p.get("noise", 1.0) > 0 and p.get("stations", 6) == 6 and p.get("errors", "default") != "none":
            return i, s
    return 0, cfg["scenarios"][0]


def stations_table(cfg, target):
    """Tables 5-9 of the paper: each scheme's stations of one simulated campaign against the truth."""
    i, s = _first_noisy(cfg)
    task = {"seed": cfg["seed"], "stream": [i, 0, 0], "dataset": {"params": s["params"]}}
    data, truth = simulate(task)
    rows = []
    for m in cfg["methods"]:
        res = methods.fit(f"multilateration.{m}", data)
        st = truth["stations"]
        if m == "joint":
            R, t = kabsch(truth["actual"], data.points)
            st = np.column_stack([st[:, :3] @ R.T + t, st[:, 3]])
        for k, sid in enumerate(res.station_ids):
            d = (res.stations[k] - st[k]) * 1e3
            rows.append({"method": m, "station": sid, "x": res.stations[k, 0], "y": res.stations[k, 1],
                         "z": res.stations[k, 2], "L": res.stations[k, 3], "dx_um": d[0], "dy_um": d[1], "dz_um": d[2],
                         "dL_um": d[3]})
    for k, sid in enumerate(data.stations):
        st = truth["stations"][k]
        rows.append({"method": "truth", "station": sid, "x": st[0], "y": st[1], "z": st[2], "L": st[3],
                     "dx_um": 0.0, "dy_um": 0.0, "dz_um": 0.0, "dL_um": 0.0})
    table = pd.DataFrame(rows)
    save_csv(table, target / "stations_table.csv", index=False, float_format="%.6f")
    return {"scenario": s["label"], "rows": table.to_dict(orient="records")}


def rounding(cfg):
    """What the published Case B's conditioning costs in double precision: its solution against the centred
    one (the same estimator) on exact lengths, stations located and given."""
    out = []
    for stations in (6, 4, (1, 2, 3, 4)):
        data, truth = sim.simulate(stations=stations, noise=0.0)
        for mode in MODES:
            d = data if mode == "located" else data.with_stations(truth["stations"])
            b = methods.fit("multilateration.case_b_linear", d)
            c = methods.fit("multilateration.case_b_centred", d)
            a = methods.fit("multilateration.case_a_distance", d)
            out.append({"stations": "-".join(map(str, stations)) if isinstance(stations, tuple) else str(stations),
                        "mode": mode,
                        "published_vs_centred_um": 1e3 * float(np.max(np.abs(b.points - c.points))),
                        "kappa_points_published": float(np.median(b.condition_numbers["points"]["svd"])),
                        "kappa_points_centred": float(np.median(c.condition_numbers["points"]["svd"])),
                        "case_b_vs_truth_um": 1e3 * float(np.max(np.abs(b.points - truth["actual"]))),
                        "case_a_vs_truth_um": 1e3 * float(np.max(np.abs(a.points - truth["actual"])))})
    return out


def winner(acc):
    """The most accurate scheme per scenario and mode (median aligned volumetric-error RMS)."""
    out = []
    for (scen, mode), g in acc.groupby(["dataset", "stations"], sort=False):
        g = g.sort_values("aligned_error_rms_um")
        best, second = g.iloc[0], g.iloc[1]
        a = g[g["method"] == "case_a_distance"]["aligned_error_rms_um"]
        b = g[g["method"] == "case_b_linear"]["aligned_error_rms_um"]
        out.append({"scenario": scen, "stations": mode, "best": best["method"],
                    "best_rms_um": float(best["aligned_error_rms_um"]), "runner_up": second["method"],
                    "runner_up_rms_um": float(second["aligned_error_rms_um"]),
                    "case_a_rms_um": float(a.iloc[0]) if len(a) else None,
                    "case_b_rms_um": float(b.iloc[0]) if len(b) else None})
    return out


def figure_axis_line(cfg, target):
    """Figures 5-6 of the paper: volumetric errors along the x axis (y = 0, z = 0, no tool offset), truth
    against Case A, Case B and the joint adjustment, stations located."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    i, s = _first_noisy(cfg)
    params = _scenario(s["params"])
    params["grid"] = (16, 4, 4)
    data, truth = sim.simulate(rng=np.random.default_rng(cfg["seed"]), **params)
    on = np.flatnonzero((truth["axes"][:, 1] == 0) & (truth["axes"][:, 2] == 0) & np.all(truth["offsets"] == 0, axis=1))
    x = truth["axes"][on, 0]
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6), sharex=True)
    shown = [("truth", truth["volumetric_errors"], dict(color="k", lw=2)),]
    for m, style in (("case_a_distance", dict(color="tab:red", marker="o", ms=3)),
                     ("case_b_linear", dict(color="tab:blue", marker="s", ms=3, ls="--")),
                     ("joint", dict(color="tab:green", marker="^", ms=3, ls=":"))):
        res = methods.fit(f"multilateration.{m}", data)
        vol = res.volumetric_errors
        if m == "joint":   # its gauge: compare after the truth's own best alignment
            R, t = kabsch(truth["actual"], data.points)
            vol = vol - ((truth["actual"] @ R.T + t) - truth["actual"])
        shown.append((m, vol, style))
    for c, ax in enumerate(axes):
        for label, vol, style in shown:
            ax.plot(x, vol[on, c] * 1e3, label=label, **style)
        ax.set_title(f"Δ{'xyz'[c]} on the x axis", fontsize=9)
        ax.set_xlabel("x [mm]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("volumetric error [µm]")
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{s['label']}: stations located by each scheme", fontsize=9)
    fig.tight_layout()
    save_figure(fig, target / "x_axis.png", dpi=110)
    plt.close(fig)


def figure_kappa(acc, target):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    sub = acc[acc["stations"] == "located"]
    scen = sub["dataset"].iloc[0]
    g = sub[sub["dataset"] == scen]
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    xs = np.arange(len(g))
    for ax, step in zip(axes, ("stations", "points")):
        ax.bar(xs, g[f"kappa_{step}"], color="tab:blue", label="κ₂ by SVD (median)")
        ax.scatter(xs, g[f"kappa_{step}_theorem1"], color="tab:red", zorder=3, label="Theorem 1 lower estimate")
        ax.set_yscale("log")
        ax.set_xticks(xs, g["method"], rotation=25, fontsize=7)
        ax.axhline(100, color="k", ls="--", lw=0.8, label="100 (the paper's 'satisfactory')")
        ax.set_title(f"step {'1: stations' if step == 'stations' else '2: points'}", fontsize=9)
    axes[0].legend(fontsize=7)
    ax2 = axes[1].twinx()
    ax2.plot(xs, g["aligned_error_rms_um"], "ko-", label="volumetric error RMS [µm]")
    ax2.set_ylabel("volumetric error RMS after alignment [µm]", fontsize=8)
    ax2.legend(fontsize=7, loc="upper right")
    fig.suptitle(scen, fontsize=9)
    fig.tight_layout()
    save_figure(fig, target / "multilateration.png", dpi=110)
    plt.close(fig)


def report_tables(folder, f):
    """The tables a reader wants from this study (moved here from the report, which names no study)."""
    import pandas as pd

    from experiments.study import Table
    out = []
    st = f.get("stations_table", {})
    t = pd.DataFrame(st.get("rows", []))
    if len(t):
        t = t[t["method"] != "truth"][["method", "station", "dx_um", "dy_um", "dz_um", "dL_um"]].round(3)
        out.append((f"Stations located by each scheme, one campaign ({st.get('scenario', '')}): difference from the "
                    "truth [um] (the paper's tables 5-9; the joint adjustment in its gauge)", t))
    acc = pd.DataFrame(f.get("accuracy", []))
    if len(acc):
        keep = ["dataset", "stations", "method", "runs", "station_error_um", "volumetric_error_rms_um",
                "aligned_error_rms_um", "model_error_rms_um", "kappa_stations", "kappa_stations_theorem1",
                "kappa_points", "kappa_points_theorem1"]
        acc = acc[[c for c in keep if c in acc.columns]].rename(columns={
            "dataset": "scenario", "stations": "stations are", "station_error_um": "station [um]",
            "volumetric_error_rms_um": "vol. RMS [um]", "aligned_error_rms_um": "aligned RMS [um]",
            "model_error_rms_um": "21-error map RMS [um]", "kappa_stations": "kappa st.",
            "kappa_stations_theorem1": "Thm 1 st.", "kappa_points": "kappa pt.", "kappa_points_theorem1": "Thm 1 pt."})
        for c in acc.columns[4:]:
            acc[c] = acc[c].map(lambda v: "" if pd.isna(v) else f"{v:.3g}")
        out.append(("Median over the Monte Carlo runs: largest station error, volumetric-error error (RMS, and after "
                    "the best rigid alignment), error of the map from the 21 identified errors, condition numbers", acc))
    out.append(("Most accurate scheme per scenario (median aligned RMS [um])", pd.DataFrame(f.get("winner", [])).round(3)))
    r = pd.DataFrame(f.get("rounding", []))
    if len(r):
        for c in r.columns[2:]:
            r[c] = r[c].map(lambda v: f"{v:.3g}")
        out.append(("Exact lengths: what the published Case B's conditioning costs in double precision (its points "
                    "against the centred solution of the same equations) and its error against the truth [um]", r))
    return [Table(caption=c, data=t) for c, t in out if t is not None and len(t)]
