"""Study ``roundness``: RONt of published and synthetic profiles versus the ISO 16610-21 cut-off (UPR), about
the four ISO 12181 reference circles. One row per (profile, cut-off, repetition) with RONt/RONq of each
circle and whether its solver certified it. Cut-offs above N/7 UPR are skipped (ISO 12181-2 sampling).
The analysis (``rank_table``, ``cutoff_table``) is pure functions of the rows."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd

import datasets
import methods
from experiments.engine import ConfigError
from methods.roundness.filter import POINTS_PER_CUTOFF, parse_cutoff

REFS = ("lsci", "mzci", "mici", "mcci")


def validate(cfg, where):
    if not isinstance(cfg.get("cutoffs"), list) or not cfg["cutoffs"]:
        raise ConfigError(f"{where}: cutoffs must be a non-empty list of UPR values or 'none'")
    for c in cfg["cutoffs"]:
        parse_cutoff(c, f"{where} cutoffs")
    for name in cfg.get("published", []):
        if name not in datasets.list():
            raise ConfigError(f"{where}: unknown published data set {name!r}; known: {', '.join(datasets.list())}")
    for i, s in enumerate(cfg.get("synthetic", [])):
        missing = {"label", "n", "radius", "lobes"} - set(s)
        if missing:
            raise ConfigError(f"{where} synthetic[{i}]: missing {', '.join(sorted(missing))}")


def synthetic_profile(spec: dict, rng) -> np.ndarray:
    """r(theta) = R + sum A_k cos(k theta + phi_k) + noise on N equal angles; phases drawn from ``rng``."""
    n = int(spec["n"])
    t = 2 * np.pi * np.arange(n) / n
    r = np.full(n, float(spec["radius"]))
    for k, a in spec["lobes"]:
        r += a * np.cos(k * t + rng.uniform(0, 2 * np.pi))
    r += spec.get("noise", 0.0) * rng.standard_normal(n)
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def tasks(cfg):
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


def load(spec, seed, stream):
    if "published" in spec:
        return datasets.load(spec["published"], drop_repeated_closing_point=True).points
    return synthetic_profile(spec["synthetic"], np.random.default_rng(np.random.SeedSequence(seed, spawn_key=tuple(stream))))


def execute(task):
    spec = task["dataset"]
    pts = load(spec, task["seed"], task["stream"])
    cut = task["params"]["cutoff_upr"]
    row = {"study": task["study"], "dataset": spec["label"], "repetition": task["repetition"], "seed": task["seed"],
           "data_stream": ".".join(map(str, task["stream"])), "method": task["method"],
           "params": json.dumps(task["params"], sort_keys=True), "cutoff_upr": "none" if cut is None else cut,
           "n_points": int(pts.shape[0])}
    if cut is not None and pts.shape[0] < POINTS_PER_CUTOFF * cut:
        return {**row, "status": "skipped", "message": f"{pts.shape[0]} points cannot carry a {cut:g} UPR cut-off "
                                                       f"(ISO 12181-2: >= {POINTS_PER_CUTOFF} x cut-off points)"}
    res = methods.fit("roundness.iso12181", pts, cutoff_upr=cut, reference="all")
    row.update(status="ok" if res.converged else "not converged", message=res.message, converged=res.converged)
    for k, ref in res.references.items():
        row[f"RONt_{k}_um"] = ref["RONt"] * 1e3
        row[f"RONq_{k}_um"] = ref["RONq"] * 1e3
        row[f"certified_{k}"] = ref["converged"]
    row["dominant_upr"] = res.dominant_lobes[0]["upr"] if res.dominant_lobes else None
    return row


def cutoff_table(df: pd.DataFrame) -> pd.DataFrame:
    """Mean RONt (µm) of the certified fits per profile and cut-off for each reference circle, with the share
    of certified fits (NaN: none certified)."""
    ok = df[df["status"].isin(["ok", "not converged"])].copy()
    ok["cutoff_upr"] = ok["cutoff_upr"].astype(str)
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


def finalize(df, cfg, target, log):
    table = cutoff_table(df)
    ranks = rank_table(df)
    table.to_csv(target / "ront_by_cutoff.csv", index=False, float_format="%.5g")
    ranks.to_csv(target / "ranking.csv", index=False, float_format="%.5g")
    log(f"  {'profile':<42} {'cut-off':>7} " + " ".join(f"{k.upper() + ' RONt':>11}" for k in REFS) + "  certified")
    for r in table.itertuples(index=False):
        d = r._asdict()
        log(f"  {d['dataset']:<42} {d['cutoff_upr']:>7} " + " ".join(f"{d[f'RONt_{k}_um']:8.3f} µm" for k in REFS)
            + "  " + "/".join(f"{d[f'certified_{k}']:.0%}" for k in REFS))
    skipped = df[df["status"] == "skipped"]
    if len(skipped):
        log(f"  skipped (under-sampled for the cut-off): {len(skipped)} rows")
    for r in ranks.itertuples():
        log(f"  {r.reference.upper()}: smallest RONt in {r.smallest}/{r.rows} certified rows, largest in {r.largest}, "
            f"RONt above MZCI's by {r.mean_excess_over_mzci_pct:.1f} % on average")
    figure(table, target / "roundness.png")
    return {"ront_by_cutoff": table.to_dict(orient="records"), "ranking": ranks.to_dict(orient="records"),
            "figure": "roundness.png", "skipped_undersampled": int(len(skipped))}


def figure(table: pd.DataFrame, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    profiles = list(dict.fromkeys(table["dataset"]))
    fig, axes = plt.subplots(1, len(profiles), figsize=(3.2 * len(profiles), 3.4), squeeze=False)
    for ax, p in zip(axes[0], profiles):
        g = table[table["dataset"] == p]
        x = np.arange(len(g))
        for k in REFS:
            ax.plot(x, g[f"RONt_{k}_um"], marker="o", ms=3, label=k.upper())
        ax.set_xticks(x, [c.replace(".0", "") for c in g["cutoff_upr"]], fontsize=7)
        ax.set_xlabel("cut-off [UPR] (none = unfiltered)", fontsize=8)
        ax.set_title(p, fontsize=8)
    axes[0][0].set_ylabel("RONt [µm]")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
