"""Study ``roundness``: RONt of published and synthetic profiles versus the ISO 16610-21 cut-off (UPR), about
the four ISO 12181 reference circles. One row per (profile, cut-off, repetition) with RONt/RONq of each
circle and whether its solver certified it. Cut-offs above N/7 UPR are skipped (ISO 12181-2 sampling).
The analysis (``rank_table``, ``cutoff_table``) is pure functions of the rows."""
from __future__ import annotations

import textwrap
from typing import Annotated, Any, Literal, Union

import numpy as np
import pandas as pd
from pydantic import Field

import datasets
import methods
from methods.results import Tolerance
from experiments.outputs import save_csv
from experiments.rows import base_row
from experiments.study import Analysis, ConfigError, ConfigTable, Figure, Study, Table
from methods.roundness.filter import POINTS_PER_CUTOFF, parse_cutoff


REFS = ("lsci", "mzci", "mici", "mcci")


def synthetic_profile(spec: dict, rng) -> np.ndarray:
    """r(theta) = R + sum A_k cos(k theta + phi_k) + noise on N equal angles; phases drawn from ``rng``."""
    n = int(spec["n"])
    t = 2 * np.pi * np.arange(n) / n
    r = np.full(n, float(spec["radius"]))
    for k, a in spec["lobes"]:
        r += a * np.cos(k * t + rng.uniform(0, 2 * np.pi))
    r += spec.get("noise", 0.0) * rng.standard_normal(n)
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def load(spec, seed, stream):
    if "published" in spec:
        return datasets.load(spec["published"], drop_repeated_closing_point=True).points
    return synthetic_profile(spec["synthetic"], np.random.default_rng(np.random.SeedSequence(seed, spawn_key=tuple(stream))))


def cutoff_table(df: pd.DataFrame) -> pd.DataFrame:
    """Mean RONt (µm) of the certified fits per profile and cut-off for each reference circle, with the share
    of certified fits (NaN: none certified)."""
    ok = df[df["status"].isin(["ok", "not converged"])].copy()
    # a cut-off as a person writes it: 50, not 50.0 (a CSV column mixing numbers and 'none' reads as text)
    ok["cutoff_upr"] = ok["cutoff_upr"].map(lambda c: c if str(c) == "none" else f"{float(c):g}")
    for k in REFS:  # an uncertified circle's RONt is not averaged in (its solver claimed no optimum)
        ok[f"RONt_{k}_um"] = ok[f"RONt_{k}_um"].where(ok[f"certified_{k}"].astype(bool))
    agg = {f"RONt_{k}_um": "mean" for k in REFS}
    agg.update({f"certified_{k}": "mean" for k in REFS})
    return ok.groupby(["dataset", "cutoff_upr"], sort=False).agg(agg).reset_index()


def rank_table(df: pd.DataFrame) -> pd.DataFrame:
    """How often each circle gives the smallest/largest RONt, and its mean excess over MZCI's RONt in % (rows
    where all four circles are certified)."""
    ok = df[df["status"] == "ok"]
    vals = ok[[f"RONt_{k}_um" for k in REFS]].to_numpy()
    out = []
    for j, k in enumerate(REFS):
        out.append({"reference": k, "rows": len(ok), "smallest": int(np.sum(np.argmin(vals, axis=1) == j)) if len(ok) else 0,
                    "largest": int(np.sum(np.argmax(vals, axis=1) == j)) if len(ok) else 0,
                    "mean_excess_over_mzci_pct": float(np.mean((vals[:, j] - vals[:, 1]) / vals[:, 1]) * 100)
                    if len(ok) else float("nan")})
    return pd.DataFrame(out)


def ranking_shown(ranks: pd.DataFrame) -> pd.DataFrame:
    """``rank_table`` as the report shows it: each column with its own unit (the counts are counts of rows,
    integers without a unit; the mean excess in %)."""
    shown = ranks.rename(columns={"smallest": "rows with smallest RONt", "largest": "rows with largest RONt",
                                  "mean_excess_over_mzci_pct": "mean excess over MZCI [%]"})
    shown["reference"] = shown["reference"].str.upper()   # LSCI, MZCI, ... as in the RONt table
    for c in ("rows", "rows with smallest RONt", "rows with largest RONt"):
        shown[c] = shown[c].astype("int64")
    return shown


def figure(table: pd.DataFrame, path):
    from experiments.render import style
    plt = style.plotting()
    profiles = list(dict.fromkeys(table["dataset"]))
    ncol = min(3, len(profiles))
    nrow = int(np.ceil(len(profiles) / ncol))
    colours = style.category_styles([k.upper() for k in REFS])
    with style.figure_style():
        fig, axes = plt.subplots(nrow, ncol, figsize=style.size(1.0, 0.32 * nrow), squeeze=False)
        for ax, p in zip(axes.ravel(), profiles):
            g = table[table["dataset"] == p]
            x = np.arange(len(g))
            for k in REFS:
                kw = colours[k.upper()]
                ax.plot(x, g[f"RONt_{k}_um"], marker=kw.get("marker", "o"), color=kw["color"], ms=3, label=k.upper())
            ax.set_xticks(x, [c.replace(".0", "") for c in g["cutoff_upr"]])
            ax.set_xlabel("cut-off [UPR]")
            ax.set_title("\n".join(textwrap.wrap(p, 36)))
        for ax in axes.ravel()[len(profiles):]:
            ax.set_visible(False)
        for row in axes:
            row[0].set_ylabel("RONt [µm]")
        style.legend_outside(fig, axes=[axes[0, 0]], ncol=4)
        style.save(fig, path)
        plt.close(fig)


class RoundnessConfig(ConfigTable):
    """The keys of the roundness study."""
    cutoffs: Annotated[list[Union[Annotated[float, Field(gt=0)], Literal["none"]]], Field(min_length=1)]  # UPR
    published: Annotated[list[str], Field(min_length=1)] = None
    synthetic: Annotated[list[dict[str, Any]], Field(min_length=1)] = None


class RoundnessStudy(Study):
    """The ``roundness`` study (see the module's docstring)."""

    #: verify's tolerances of this study's own columns
    tolerances = {
        # roundness (ISO 12181): RONt/RONq in µm of profiles up to D 25 mm (2.5e4 µm) after the ISO 16610-21 filter; at a
        # cut-off of 1 UPR the filtered profile of a near-perfect part is ~1e-4 µm, rounding itself, and its MCC/MZ moved
        # by up to 1.5e-7 µm between BLAS kernels: 1e-9 relative and 1e-5 µm (10 pm) absolute
        **{f"RON{q}_{k}_um": Tolerance(1e-9, 1e-5, "a µm roundness of a filtered profile: absolute resolution 1e-5 µm")
           for q in ("t", "q") for k in ("lsci", "mzci", "mici", "mcci")},
    }

    values = None  # its analysis names its values

    #: this study's own config keys (typed; the schema is generated from the model)
    config_schema = RoundnessConfig

    def validate(self, cfg, where):
        for c in cfg["cutoffs"]:  # a non-empty list of positive numbers or 'none': the schema (RoundnessConfig)
            parse_cutoff(c, f"{where} cutoffs")
        for name in cfg.get("published", []):
            if name not in datasets.list():
                raise ConfigError(f"{where}: unknown published data set {name!r}; known: {', '.join(datasets.list())}")
        for i, s in enumerate(cfg.get("synthetic", [])):
            missing = {"label", "n", "radius", "lobes"} - set(s)
            if missing:
                raise ConfigError(f"{where} synthetic[{i}]: missing {', '.join(sorted(missing))}")

    def tasks(self, cfg):
        out = []
        profiles = [{"entry": i, "point": 0, "published": p, "label": p} for i, p in enumerate(cfg.get("published", []))]
        base = len(profiles)
        profiles += [{"entry": base + i, "point": 0, "synthetic": s, "label": s["label"]}
                     for i, s in enumerate(cfg.get("synthetic", []))]
        for spec in profiles:
            reps = 1 if "published" in spec else cfg["repetitions"]
            for r in range(reps):
                for c in cfg["cutoffs"]:
                    cut = parse_cutoff(c)
                    out.append({"study": cfg["name"], "kind": cfg["kind"], "dataset": spec, "repetition": r,
                                "stream": [spec["entry"], 0, r], "seed": cfg["seed"], "method": "roundness.iso12181",
                                "params": {"cutoff_upr": cut, "reference": "all"}, "timing": None})
        return out

    def execute(self, task):
        spec = task["dataset"]
        pts = load(spec, task["seed"], task["stream"])
        cut = task["params"]["cutoff_upr"]
        row = {**base_row(task), "cutoff_upr": "none" if cut is None else cut, "n_points": int(pts.shape[0])}
        if cut is not None and pts.shape[0] < POINTS_PER_CUTOFF * cut:
            return {**row, "status": "skipped", "message": f"{pts.shape[0]} points cannot carry a {cut:g} UPR cut-off "
                                                           f"(ISO 12181-2: >= {POINTS_PER_CUTOFF} x cut-off points)"}
        res = methods.fit(task["method"], pts, **task["params"])
        row.update(status="ok" if res.converged else "not converged", message=res.message, converged=res.converged)
        for k, ref in res.references.items():
            row[f"RONt_{k}_um"] = ref["RONt"] * 1e3
            row[f"RONq_{k}_um"] = ref["RONq"] * 1e3
            row[f"certified_{k}"] = ref["converged"]
        row["dominant_upr"] = res.dominant_lobes[0]["upr"] if res.dominant_lobes else None
        return row

    def analyse(self, df, cfg, target, log):
        """RONt by cut-off (certified fits) and the ranking of the four reference circles; figure; findings."""
        table = cutoff_table(df)
        ranks = rank_table(df)
        save_csv(table, target / "ront_by_cutoff.csv", index=False, float_format="%.5g")
        save_csv(ranks, target / "ranking.csv", index=False, float_format="%.5g")
        for r in table.itertuples(index=False):
            d = r._asdict()
            log(f"  {d['dataset']:<42} {d['cutoff_upr']:>7} " + " ".join(f"{d[f'RONt_{k}_um']:8.3f} µm" for k in REFS)
                + "  " + "/".join(f"{d[f'certified_{k}']:.0%}" for k in REFS))
        skipped = df[df["status"] == "skipped"]
        figure(table, target / "roundness.png")
        reps = int(df.groupby(["dataset", "cutoff_upr"]).size().max()) if len(df) else 0
        r = ranks.set_index("reference")
        values = {"ranking": ranks.to_dict(orient="records"), "skipped_undersampled": int(len(skipped)),
                  "rows_all_certified": int(r["rows"].iloc[0]) if len(r) else 0,
                  "mzci_smallest": int(r.loc["mzci", "smallest"]) if "mzci" in r.index else 0}
        n_all = values["rows_all_certified"]
        others = [k for k in REFS if k != "mzci"]
        most = max(others, key=lambda k: int(r.loc[k, "largest"])) if n_all else None
        # MZCI's RONt is the smallest by its definition (ISO 12181-1): a check of the solvers, not a finding
        check = (f"As the minimum zone's definition requires (ISO 12181-1), MZCI's RONt is the smallest in all {n_all}."
                 if values["mzci_smallest"] == n_all else
                 f"MZCI's RONt is the smallest in only {values['mzci_smallest']} of {n_all}, which its definition "
                 f"(ISO 12181-1) forbids: a solver failed to reach the minimum zone.")
        findings = (f"Where all four reference circles are certified ({n_all} rows), RONt exceeds the minimum zone's "
                    "(MZCI) on average by "
                    + ", ".join(f"{k.upper()} {r.loc[k, 'mean_excess_over_mzci_pct']:.1f} %" for k in others)
                    + (f", and {most.upper()} gives the largest RONt in {int(r.loc[most, 'largest'])} of them" if most else "")
                    + f". {check} {len(skipped)} (profile, cut-off) rows are skipped: fewer than 7 "
                    "points per cut-off wavelength (ISO 12181-2).")
        shown = table.copy()
        for k in REFS:
            shown[f"certified_{k}"] = 100 * shown[f"certified_{k}"]
        shown = shown.rename(columns={"dataset": "profile", "cutoff_upr": "cut-off [UPR]",
                                      **{f"RONt_{k}_um": f"RONt {k.upper()} [µm]" for k in REFS},
                                      **{f"certified_{k}": f"{k.upper()} certified [%]" for k in REFS}})
        tables = [Table(caption=f"RONt (mean of certified fits) of each ISO 12181 reference circle against the ISO 16610-21 "
                                f"Gaussian cut-off, on the published roundness profiles and synthetic lobed profiles "
                                f"({reps} repetition(s) of the noisy ones), with the share of certified fits", data=shown,
                        unit="µm, %", digits=4),
                  Table(caption="How often each reference circle gives the smallest and the largest RONt (counts of "
                                "rows), and its mean excess over the minimum-zone RONt [%], over the rows where all four "
                                "circles are certified", data=ranking_shown(ranks), unit="", digits=3)]
        fig = Figure(caption="RONt [µm] of the four reference circles against the Gaussian cut-off [UPR] per profile "
                             "(certified fits; none = unfiltered)", file="roundness.png")
        return Analysis(tables=tables, figures=[fig], values=values, findings=findings)
