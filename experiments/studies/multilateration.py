"""Study ``multilateration``: the multilateration paper's comparison (Holub et al., Machines 2022, 10, 833,
tables 5-9 and figures 5-6) with the simulator's truth in place of the unavailable Trac-Cal software.

Every scheme runs on simulated LaserTRACER campaigns of the MCV 754 (Monte Carlo over the instrument's noise),
once locating the stations itself (step 1 + step 2) and once with the true stations given (step 2 alone).
Rows: station and dead-path errors, volumetric-error errors (raw and after the best rigid alignment, which
multilateration with self-located stations cannot observe), condition numbers (SVD and Theorem 1), the error
of the 21 geometric errors identified from the volumetric errors, runtime.
"""
from __future__ import annotations

import json
import textwrap
import time
from typing import Annotated, Any

import numpy as np
import pandas as pd
from pydantic import Field

import methods
from datasets import multilateration as sim
from methods.multilateration.kinematics import COMPONENTS, SQUARENESS, design_matrix, identify
from methods.multilateration.solvers import kabsch
from methods.results import Tolerance
from experiments.outputs import save_csv
from experiments.rows import base_row
from experiments.study import Analysis, ConfigError, ConfigTable, Figure, Study, Table


SCENARIO_KEYS = {"stations", "noise", "errors", "grid"}
MODES = ("located", "known")


def _scenario(params):
    p = dict(params)
    if isinstance(p.get("stations"), list):
        p["stations"] = tuple(p["stations"])
    if "grid" in p:
        p["grid"] = tuple(p["grid"])
    if p.get("errors") == "none":
        p["errors"] = None
    return p


def simulate(task):
    rng = np.random.default_rng(np.random.SeedSequence(task["seed"], spawn_key=tuple(task["stream"])))
    return sim.simulate(rng=rng, **_scenario(task["dataset"]["params"]))


def _in_result_frame(res, data, truth, mode):
    """The true points and stations in the frame the result is reported in: a scheme whose located result is
    aligned to the nominal points (``res.frame == "nominal"``) is compared with the truth aligned the same way."""
    actual, stations = truth["actual"], truth["stations"]
    if res.frame == "nominal":
        R, t = kabsch(actual, data.points)
        actual = actual @ R.T + t
        stations = np.column_stack([stations[:, :3] @ R.T + t, stations[:, 3]])
    return actual, stations


def metrics(res, data, truth, mode) -> dict:
    actual, stations = _in_result_frame(res, data, truth, mode)
    out = {}
    if mode == "located":
        out["station_error_um"] = 1e3 * float(np.max(np.linalg.norm(res.stations[:, :3] - stations[:, :3], axis=1)))
        out["dead_path_error_um"] = 1e3 * float(np.max(np.abs(res.stations[:, 3] - stations[:, 3])))
        out["station_deltas_um"] = json.dumps({str(sid): [round(1e3 * float(v), 6) for v in res.stations[k] - stations[k]]
                                               for k, sid in enumerate(res.station_ids)})
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
        # the share of parameters within 2 standard uncertainties: defined with measurement noise only (on exact
        # lengths u is rounding noise, and whether |error| <= 2u is a matter of the CPU's last bits)
        z = (ident.vector[:-6] - model.vector()) / ident.std[:-6]
        out["identified_within_2u"] = float(np.mean(np.abs(z) <= 2)) if truth.get("noise", 1.0) > 0 else float("nan")
    return out


# ---------------------------------------------------------------- exact-length conditioning check (tasks)

def conditioning_tasks(cfg):
    """One task per (station set, mode) of the TOML's ``conditioning_check``: the published scheme against
    the same estimator in a well-conditioned form, and a reference scheme, on exact lengths."""
    chk = cfg.get("conditioning_check")
    if not chk:
        return []
    out = []
    for j, stations in enumerate(chk["stations"]):
        label = "-".join(map(str, stations)) if isinstance(stations, list) else str(stations)
        spec = {"entry": len(cfg["scenarios"]), "point": j, "label": f"exact lengths, stations {label}",
                "params": {"stations": stations, "noise": 0.0}}
        for mode in MODES:
            out.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": spec, "repetition": 0,
                        "stream": [len(cfg["scenarios"]), j, 0], "seed": cfg["seed"], "method": chk["published"],
                        "params": {}, "timing": None, "x_mode": mode,
                        "x_conditioning": {"same_estimator": chk["same_estimator"], "reference": chk["reference"]}})
    return out


def conditioning_row(task):
    """What the published scheme's conditioning costs in double precision on exact lengths."""
    chk = task["x_conditioning"]
    data, truth = sim.simulate(**_scenario(task["dataset"]["params"]))
    if task["x_mode"] == "known":
        data = data.with_stations(truth["stations"])
    b = methods.fit(task["method"], data)
    c = methods.fit(chk["same_estimator"], data)
    a = methods.fit(chk["reference"], data)
    return {**base_row(task), "stations": task["x_mode"], "status": "ok", "message": "",
            "published_vs_centred_um": 1e3 * float(np.max(np.abs(b.points - c.points))),
            "kappa_points_published": float(np.median(b.condition_numbers["points"]["svd"])),
            "kappa_points_centred": float(np.median(c.condition_numbers["points"]["svd"])),
            "case_b_vs_truth_um": 1e3 * float(np.max(np.abs(b.points - truth["actual"]))),
            "case_a_vs_truth_um": 1e3 * float(np.max(np.abs(a.points - truth["actual"])))}


# ---------------------------------------------------------------- analysis

def _first_noisy(cfg):
    """The scenario of the stations table and the x-axis figure: the first with noise, 6 stations, machine errors."""
    for i, s in enumerate(cfg["scenarios"]):
        p = s["params"]
        if p.get("noise", 1.0) > 0 and p.get("stations", 6) == 6 and p.get("errors", "default") != "none":
            return i, s
    return 0, cfg["scenarios"][0]


def _campaign_rows(df, cfg):
    i, s = _first_noisy(cfg)
    g = df[(df["dataset"] == s["label"]) & (df["repetition"] == 0) & (df["stations"] == "located")]
    return s, g


def stations_table(df, cfg):
    """Tables 5-9 of the paper: each scheme's stations of one simulated campaign against the truth [µm] (from
    the rows: ``station_deltas_um`` of repetition 0, stations located)."""
    s, g = _campaign_rows(df, cfg)
    rows = []
    for r in g.itertuples():
        if not isinstance(r.station_deltas_um, str):
            continue
        for sid, d in json.loads(r.station_deltas_um).items():
            rows.append({"method": r.method.split(".", 1)[1], "station": sid, "dx_um": d[0], "dy_um": d[1],
                         "dz_um": d[2], "dL_um": d[3]})
    return s["label"], pd.DataFrame(rows)


def _tie_band(tol: Tolerance):
    """The largest amount a median may move on another machine while verify says "agree": every row within
    ``atol + rtol |x|`` of its value (experiments.compare), so their median within ``atol + rtol |median|``
    (x - atol - rtol |x| is increasing in x for rtol < 1)."""
    return lambda x: tol.atol + tol.rtol * np.abs(x)


def winner(acc, tol: Tolerance, column: str = "aligned_error_rms_um"):
    """The most accurate schemes per scenario and mode (median ``column``), ties named.

    Schemes whose medians could swap order on a machine whose rows agree within ``tol`` (verify's declared
    tolerance of the column) tie: ``m_i - m_min <= band(m_i) + band(m_min)``, band(x) = atol + rtol |x|. So the
    scheme that is the most accurate on any such machine is one of those named here, and the exact-length
    scenarios (every scheme within rounding of the truth, far below atol) are a tie of all. Row order and
    sort algorithm decide nothing: schemes are ordered by (median, name) with a stable sort, tied ones listed by name.
    Columns: best (tied schemes, ", "-joined), tied (their number), best_rms_um (the lowest median), runner_up
    and runner_up_rms_um (the most accurate scheme outside the tie; empty when all tie)."""
    band = _tie_band(tol)
    out = []
    for (scen, mode), g in acc.groupby(["dataset", "stations"], sort=False):
        g = g.sort_values([column, "method"], kind="mergesort")
        v = g[column].to_numpy(float)
        tied = (v - v[0]) <= band(v) + band(v[0])
        best, rest = g[tied], g[~tied]
        out.append({"scenario": scen, "stations": mode, "best": ", ".join(sorted(best["method"])), "tied": int(tied.sum()),
                    "best_rms_um": float(v[0]),
                    "runner_up": rest["method"].iloc[0] if len(rest) else "",
                    "runner_up_rms_um": float(rest[column].iloc[0]) if len(rest) else float("nan")})
    return pd.DataFrame(out)


def winner_counts(win) -> pd.Series:
    """How often each (set of tied) most accurate scheme(s) occurs: most frequent first, then by name."""
    counts = win.groupby("best").size()
    order = sorted(counts.index, key=lambda k: (-counts[k], k))
    return counts[order]


def winner_text(win, n_methods: int) -> str:
    """'case_a_distance = case_b_taylor = joint (tied) in 4, joint alone in 4, all 6 tied in 1' from :func:`winner`:
    commas only (the abstract cuts a finding at its first '; ' or '. ')."""
    def name(best):
        ms = best.split(", ")
        if len(ms) == 1:
            return f"{ms[0]} alone"
        return f"all {n_methods} tied" if len(ms) == n_methods else " = ".join(ms) + " (tied)"
    return ", ".join(f"{name(b)} in {n}" for b, n in winner_counts(win).items())


def figure_axis_line(cfg, target):
    """Figures 5-6 of the paper: volumetric errors along the x axis (y = 0, z = 0, no tool offset), truth
    against the schemes of the TOML's ``axis_figure`` list, stations located."""
    from experiments.render import style
    plt = style.plotting()
    i, s = _first_noisy(cfg)
    params = _scenario(s["params"])
    params["grid"] = (16, 4, 4)
    data, truth = sim.simulate(rng=np.random.default_rng(cfg["seed"]), **params)
    on = np.flatnonzero((truth["axes"][:, 1] == 0) & (truth["axes"][:, 2] == 0) & np.all(truth["offsets"] == 0, axis=1))
    x = truth["axes"][on, 0]
    shown = [("truth", truth["volumetric_errors"], dict(color="k", lw=2))]
    for m in cfg.get("axis_figure", []):
        res = methods.fit(m, data)
        actual, _ = _in_result_frame(res, data, truth, "located")
        # compare in the result's frame: subtract the frame change of the truth
        vol = res.volumetric_errors - (actual - truth["actual"])
        kw = style.method_style(m)
        shown.append((kw["label"], vol, dict(color=kw["color"], marker=kw["marker"], ms=3)))
    with style.figure_style():
        fig, axes = plt.subplots(1, 3, figsize=style.size(1.0, 0.38), sharex=True)
        for c, ax in enumerate(axes):
            for label, vol, kw in shown:
                ax.plot(x, vol[on, c] * 1e3, label=label, **kw)
            ax.set_title(f"Δ{'xyz'[c]} on the x axis")
            ax.set_xlabel("x [mm]")
        axes[0].set_ylabel("volumetric error [µm]")
        style.legend_outside(fig, ncol=4)
        style.save(fig, target / "x_axis.png")
        plt.close(fig)


class ConditioningCheck(ConfigTable):
    """The exact-length check: the published scheme, the same estimator well conditioned, a reference scheme."""
    published: str
    same_estimator: str
    reference: str
    stations: Annotated[list[Any], Field(min_length=1)]


class MultilaterationConfig(ConfigTable):
    """The keys of the multilateration study."""
    conditioning_check: ConditioningCheck = None
    axis_figure: list[str] = None
    scenarios: Annotated[list[dict[str, Any]], Field(min_length=1)]


class MultilaterationStudy(Study):
    """The ``multilateration`` study (see the module's docstring)."""

    #: verify's tolerances of this study's own columns
    tolerances = {
        # multilateration (lengths in µm of a 1000-mm machine): least-squares adjustments with condition numbers 1e4-1e8 (4-6
        # stations) and up to 9e11 (4 stations within 1.3 mm of a plane, the paper's bad case). Between OpenBLAS's
        # Haswell and Sandybridge kernels (tests/test_cpu_independence.py) the near-planar case's values moved by up to
        # 1e-5 relative (1.1e-3 µm of 116 µm), the identified coefficients' relative error by 1e-4 of itself, the others
        # by 3e-8 relative or 1.2e-4 µm; the exact-length check measures the published scheme's own rounding (~1e-4 µm).
        # Declared: 1e-4 relative and 1e-2 µm (10 nm), a margin of 10.
        **dict.fromkeys(("station_error_um", "dead_path_error_um", "volumetric_error_rms_um", "volumetric_error_max_um",
                         "aligned_error_rms_um", "model_error_rms_um", "published_vs_centred_um", "case_a_vs_truth_um",
                         "case_b_vs_truth_um"),
                        Tolerance(1e-4, 1e-2, "a µm length of an adjustment with condition numbers up to 9e11: CPU rounding")),
        "identified_max_relative_error": Tolerance(1e-3, 1e-7, "relative error of 21 identified coefficients: moved 1e-4 "
                                                               "of itself between BLAS kernels (near-planar stations)"),
        # condition numbers by SVD: sigma_min carries an absolute error of eps sigma_max (seen: 2e-7 relative)
        **dict.fromkeys(("kappa_stations", "kappa_stations_max", "kappa_points", "kappa_points_max",
                         "kappa_stations_theorem1", "kappa_points_theorem1"),
                        Tolerance(1e-5, 0.0, "a condition number sigma_max / sigma_min: sigma_min is known to eps sigma_max")),
        # the per-station deltas as a JSON list for the report, rounded to 1e-6 µm: their size is station_error_um
        "station_deltas_um": None,
    }

    values = None  # its analysis names its values

    #: this study's own config keys (typed; the schema is generated from the model)
    config_schema = MultilaterationConfig

    def validate(self, cfg, where):
        for i, s in enumerate(cfg["scenarios"]):  # a non-empty list of tables: the schema (MultilaterationConfig)
            bad = set(s.get("params", {})) - SCENARIO_KEYS
            if bad or "label" not in s:
                raise ConfigError(f"{where} scenarios[{i}]: needs a label; unknown params {sorted(bad)} "
                                  f"(allowed: {sorted(SCENARIO_KEYS)})")
        for m in cfg.get("methods", []):
            methods.get(f"multilateration.{m}")
        named = [*cfg.get("axis_figure", [])]
        if cfg.get("conditioning_check"):
            c = cfg["conditioning_check"]
            named += [c["published"], c["same_estimator"], c["reference"]]
        for m in named:
            try:
                methods.get(m)
            except methods.UnknownMethodError as exc:
                raise ConfigError(f"{where}: {exc}") from None

    def tasks(self, cfg):
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
        return out + conditioning_tasks(cfg)

    def execute(self, task):
        if "x_conditioning" in task:
            return conditioning_row(task)
        data, truth = simulate(task)
        mode = task["x_mode"]
        if mode == "known":
            data = data.with_stations(truth["stations"])
        row = {**base_row(task), "stations": mode, "n_points": len(data.points), "n_stations": len(data.stations)}
        t0 = time.perf_counter()
        res = methods.fit(task["method"], data)
        row["time_single_s"] = time.perf_counter() - t0  # one call: a timing column (time_ prefix)
        row.update(status="ok" if res.converged else "not converged", message="" if res.converged else res.message,
                   converged=res.converged)
        row.update(metrics(res, data, truth, mode))
        return row

    def analyse(self, df, cfg, target, log):
        """Accuracy and conditioning per scenario, stations table, winners, the exact-length conditioning check,
        the redrawn conditioning figure and the x-axis figure; findings from the winners."""
        is_check = df["dataset"].str.startswith("exact lengths, stations ") if "published_vs_centred_um" in df else \
            pd.Series(False, index=df.index)
        check, df = df[is_check], df[~is_check]
        ok = df[df["status"] == "ok"].copy()
        ok["method"] = ok["method"].str.replace("multilateration.", "", regex=False)
        cols = ["station_error_um", "dead_path_error_um", "volumetric_error_rms_um", "volumetric_error_max_um",
                "aligned_error_rms_um", "model_error_rms_um", "identified_max_relative_error", "identified_within_2u",
                "kappa_stations", "kappa_stations_theorem1", "kappa_points", "kappa_points_theorem1", "time_single_s"]
        cols = [c for c in cols if c in ok.columns]
        acc = ok.groupby(["dataset", "stations", "method"], sort=False)[cols].median().reset_index()
        acc.insert(3, "runs", ok.groupby(["dataset", "stations", "method"], sort=False).size().to_numpy())
        save_csv(acc, target / "accuracy.csv", index=False, float_format="%.6g")
        for r in acc.itertuples():
            log(f"  {r.dataset[:62]:<62} {r.stations:<8} {r.method:<16} vol RMS {r.volumetric_error_rms_um:10.3f} µm "
                f"aligned {r.aligned_error_rms_um:8.3f} µm")
        scen_label, st = stations_table(df, cfg)
        save_csv(st, target / "stations_table.csv", index=False, float_format="%.6f")
        tol = self.tolerances["aligned_error_rms_um"]
        win = winner(acc, tol)
        conditioning_figure(acc, target / "multilateration.png")
        figure_axis_line(cfg, target)
        runs = int(acc["runs"].max())
        tables = []
        if len(st):
            tables.append(Table(caption=f"Stations located by each scheme in one simulated campaign ({scen_label}): "
                                        "difference from the true station and dead path (the paper's tables 5-9; the "
                                        "joint adjustment in its gauge)", data=st, unit="µm"))
        keep = ["dataset", "stations", "method", "runs", "station_error_um", "volumetric_error_rms_um",
                "aligned_error_rms_um", "model_error_rms_um"]
        tables.append(Table(caption=f"Median over {runs} simulated LaserTRACER campaigns of the MCV 754 per scenario: largest "
                                    "station error, RMS error of the volumetric errors (raw, and after the best rigid "
                                    "alignment), RMS error of the map from the 21 identified errors",
                            data=acc[[c for c in keep if c in acc.columns]].rename(columns={
                                "dataset": "scenario", "stations": "stations are", "station_error_um": "station [µm]",
                                "volumetric_error_rms_um": "vol. RMS [µm]", "aligned_error_rms_um": "aligned RMS [µm]",
                                "model_error_rms_um": "21-error map RMS [µm]"}), unit="µm", digits=3))
        kap = [c for c in ("kappa_stations", "kappa_stations_theorem1", "kappa_points", "kappa_points_theorem1") if c in acc]
        tables.append(Table(caption=f"Median condition numbers (2-norm by SVD, and Theorem 1's lower estimate) of step 1 "
                                    f"(stations) and step 2 (points) over {runs} simulated campaigns per scenario "
                                    "(dimensionless)", data=acc[["dataset", "stations", "method"] + kap], digits=3))
        tie = f"{tol.rtol:g} relative + {tol.atol * 1e3:g} nm"
        tables.append(Table(caption=f"Most accurate scheme per scenario and mode: median RMS error of the volumetric errors "
                                    f"after alignment over {runs} simulated campaigns; schemes whose medians lie within "
                                    f"verify's tolerance ({tie} each) of the lowest tie and are named together (by name), "
                                    "the runner-up is the most accurate scheme outside the tie",
                            data=win.rename(columns={"best": "most accurate", "tied": "n tied", "best_rms_um": "median RMS [µm]",
                                                     "runner_up": "runner-up", "runner_up_rms_um": "runner-up RMS [µm]"}),
                            unit="µm", digits=3))
        if len(check):
            spec = cfg.get("conditioning_check") or {}
            pub, same, ref = (str(spec.get(k, d)).removeprefix("multilateration.") for k, d in (
                ("published", "case B"), ("same_estimator", "centred"), ("reference", "case A")))
            chk = check[["dataset", "stations", "published_vs_centred_um", "kappa_points_published", "kappa_points_centred",
                         "case_b_vs_truth_um", "case_a_vs_truth_um"]].rename(columns={
                             "published_vs_centred_um": f"{pub} vs {same}, largest [µm]",
                             "kappa_points_published": f"kappa points {pub}", "kappa_points_centred": f"kappa points {same}",
                             "case_b_vs_truth_um": f"{pub} vs truth, largest [µm]",
                             "case_a_vs_truth_um": f"{ref} vs truth, largest [µm]"})
            tables.append(Table(caption=f"Exact lengths (simulated, no noise): what the published Case B's ({pub}) "
                                        "conditioning costs in double precision (the largest coordinate difference "
                                        f"between its points and those of the centred form of the same equations, {same}), "
                                        f"and the error against the truth of {pub} and of Case A with the distance residuals "
                                        f"({ref}, eq. 7): the largest coordinate error max |X - X_true| over all points "
                                        "and x, y, z, without alignment [µm]. With located stations it holds the rigid "
                                        "motion that self-located stations cannot observe and the error of step 1 (the "
                                        "stations fitted to the nominal points), so it is not the RMS (raw or after the best "
                                        "rigid alignment) of the accuracy table; with known stations the frame is the "
                                        "truth's. Condition numbers dimensionless",
                                data=chk, unit="µm", digits=3))
        counts = winner_counts(win)
        values = {"winners": win.to_dict(orient="records"), "best_counts": counts.to_dict(),
                  "tie_tolerance": {"rtol": tol.rtol, "atol_um": tol.atol}, "accuracy": acc.to_dict(orient="records")}
        findings = (f"Over {len(win)} scenario/mode combinations ({runs} simulated campaigns each), the most accurate scheme "
                    f"(median volumetric-error RMS after alignment, medians within verify's tolerance of the lowest, {tie} "
                    "each, counted as a tie since their order could swap on another machine) is "
                    + winner_text(win, acc["method"].nunique()) + ".")
        if len(check):
            findings += (f" On exact lengths the published Case B departs from the centred solution of the same equations "
                         f"by up to {check['published_vs_centred_um'].max():.3g} µm (condition number up to "
                         f"{check['kappa_points_published'].max():.3g} against {check['kappa_points_centred'].max():.3g}).")
        figs = [Figure(caption="Condition numbers of both steps (median κ₂ and Theorem 1's estimate) and the median "
                               f"volumetric-error RMS after alignment [µm] per scheme; first scenario, {runs} simulated "
                               "campaigns, stations located", file="multilateration.png"),
                Figure(caption="One simulated campaign: volumetric errors along the x axis [µm] against x [mm], truth and "
                               "three schemes with self-located stations (the paper's figures 5-6)", file="x_axis.png")]
        return Analysis(tables=tables, figures=figs, values=values, findings=findings)


# ---------------------------------------------------------------- figures (drawn in experiments.render.style)
def conditioning_figure(accuracy: pd.DataFrame, path, *, scenario: str | None = None,
                                 stations: str = "located"):
    """Condition numbers of both steps per scheme (categorical x: dots, no joining line) and the volumetric
    error RMS after alignment in a panel of its own. ``accuracy``: results/multilateration/accuracy.csv."""
    from experiments.render import style
    plt = style.plotting()
    sub = accuracy[accuracy["stations"] == stations]
    scenario = scenario or sub["dataset"].iloc[0]
    g = sub[sub["dataset"] == scenario].reset_index(drop=True)
    xs = np.arange(len(g))
    names = [m.replace("_", " ") for m in g["method"]]
    with style.figure_style():
        fig, axes = plt.subplots(1, 3, figsize=style.size(1.0, 0.45))
        for ax, step, title in ((axes[0], "stations", "step 1: stations"), (axes[1], "points", "step 2: points")):
            if f"kappa_{step}" not in g or g[f"kappa_{step}"].isna().all():
                ax.set_visible(False)
                continue
            ax.plot(xs, g[f"kappa_{step}"], "o", color=style.PALETTE[0], label="κ₂ (SVD), median")
            ax.plot(xs, g[f"kappa_{step}_theorem1"], "v", color=style.PALETTE[1], label="Theorem 1 lower estimate")
            ax.axhline(100, color="0.2", ls="--", lw=0.8, label="100: the paper's 'satisfactory'")
            ax.set_yscale("log")
            style.plain_log_ticks(ax, "y")
            ax.set_title(title)
            ax.set_ylabel("condition number")
        axes[2].plot(xs, g["aligned_error_rms_um"], "s", color=style.PALETTE[2], label="volumetric error RMS")
        axes[2].set_ylabel("volumetric error RMS\nafter alignment [µm]")
        axes[2].set_ylim(0, None)
        axes[2].set_title("accuracy")
        for ax in axes:
            ax.set_xticks(xs, names, rotation=35, ha="right")
            ax.set_xlim(-0.5, len(xs) - 0.5)
            ax.grid(axis="x", visible=False)
        style.legend_outside(fig, ncol=2, title="; ".join(textwrap.wrap(scenario, 90)) + f" (stations {stations})")
        return style.save(fig, path)
