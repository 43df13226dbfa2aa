"""Dolan–Moré performance profiles (Dolan & Moré, Math. Program. 91 (2002) 201–213).

For problems p and methods s with cost t_{p,s} (error against the reference, runtime; a failure is +inf),
the performance ratio is r_{p,s} = t_{p,s} / min_s t_{p,s} and the profile is
rho_s(tau) = |{p : r_{p,s} <= tau}| / n_p: rho_s(1) is the share of problems on which s is best, and
lim rho_s(tau) the share it solves at all. Costs below ``floor`` are raised to it (two errors of 1e-16 and
3e-16 are equally exact, not "3 times worse").

    table = problem_table(rows, metric="center_error", problem=("study", "dataset", "data_stream"))
    fig = plot_profiles({"centre error": table}, path)
"""
from __future__ import annotations

import json
import warnings

import numpy as np
import pandas as pd

from experiments.render import style


def method_label(method: str, params) -> str:
    """'circle.nelder_mead' or 'circle.nelder_mead backend=nlopt' (the params of a variant)."""
    if params is None or (isinstance(params, float) and np.isnan(params)) or params in ("{}", ""):
        return method
    p = json.loads(params) if isinstance(params, str) else dict(params)
    return method + " " + ",".join(f"{k}={v}" for k, v in p.items())


def problem_table(rows: pd.DataFrame, *, metric: str, problem=("study", "dataset", "data_stream"),
                  ok=lambda r: r["status"] == "ok", methods=None, floor: float = 0.0,
                  complete: bool = True) -> pd.DataFrame:
    """Problems x methods table of ``metric`` from long rows (one row per problem and method).

    A row that is not ``ok`` (default: status != 'ok') or whose metric is missing or not finite costs +inf.
    ``problem``: the columns that identify a problem (missing ones are ignored). ``methods``: keep these
    method labels only (``method_label``). ``complete``: drop problems on which a kept method has no row at
    all (it was not run there: neither a success nor a failure). Returns a DataFrame indexed by problem,
    one column per method; ``attrs['dropped_problems']`` counts the dropped ones.
    """
    if metric not in rows.columns:
        raise ValueError(f"problem_table: no column {metric!r} in the rows (columns: {', '.join(rows.columns)})")
    keys = [c for c in problem if c in rows.columns]
    if not keys:
        raise ValueError(f"problem_table: none of the problem columns {list(problem)} is in the rows")
    df = rows.copy()
    df["_method"] = [method_label(m, p) for m, p in zip(df["method"], df.get("params", [None] * len(df)))]
    if methods is not None:
        df = df[df["_method"].isin(methods)]
    cost = pd.to_numeric(df[metric], errors="coerce").astype(float)
    good = ok(df).astype(bool) & np.isfinite(cost)
    df["_cost"] = np.where(good, np.maximum(cost.abs(), floor), np.inf)
    df["_problem"] = [" | ".join(map(str, vals)) for vals in zip(*(df[k].tolist() for k in keys))]
    dup = df.duplicated(["_problem", "_method"])
    if dup.any():
        raise ValueError(f"problem_table: {int(dup.sum())} rows repeat a (problem, method) pair: add the column that "
                         f"tells them apart to problem= (now {keys})")
    table = df.pivot(index="_problem", columns="_method", values="_cost")
    table.index.name, table.columns.name = "problem", "method"
    dropped = 0
    if complete:
        has_all = table.notna().all(axis=1)
        dropped = int((~has_all).sum())
        table = table[has_all]
    table.attrs.update(metric=metric, floor=floor, dropped_problems=dropped)
    return table


TIE_RTOL = 1e-6   #: costs within this relative distance of the best are ties (ratio 1)


def performance_ratios(table: pd.DataFrame, rtol: float = TIE_RTOL) -> pd.DataFrame:
    """r_{p,s} = t_{p,s} / min_s t_{p,s}; inf where the method failed, and on a problem every method failed.
    Ratios below 1 + ``rtol`` count as 1: two fits that land on the same optimum differ in the last digits,
    and which of them is "best" must not be decided by rounding."""
    t = table.to_numpy(float)
    if np.any(t <= 0):
        raise ValueError("performance ratios need positive costs: give problem_table a floor > 0 for errors that "
                         "can be exactly zero")
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a problem no method ran on: NaN
        best = np.nanmin(t, axis=1, keepdims=True)
        r = np.where(np.isfinite(best), t / best, np.inf)
    r = np.where(r <= 1.0 + rtol, 1.0, r)
    r = np.where(np.isnan(t), np.nan, r)  # a method not run on a problem has no ratio there
    return pd.DataFrame(r, index=table.index, columns=table.columns)


def profile(table: pd.DataFrame, taus=None, rtol: float = TIE_RTOL) -> pd.DataFrame:
    """rho_s(tau) for every method (columns) at the ratios ``taus`` (index; default every distinct ratio), over the
    problems the method ran on (its non-NaN costs)."""
    r = performance_ratios(table, rtol)
    finite = r.to_numpy()[np.isfinite(r.to_numpy())]
    if taus is None:
        taus = np.unique(np.concatenate([[1.0], finite]))
    taus = np.asarray(taus, float)
    out = {}
    for m in r.columns:
        ran = r[m].to_numpy()[~np.isnan(r[m].to_numpy())]  # the share of the problems the method ran on
        out[m] = np.searchsorted(np.sort(ran), taus, side="right") / max(len(ran), 1)
    return pd.DataFrame(out, index=pd.Index(taus, name="tau"))


#: markers drawn along each profile curve
MARKS = 4


def plot_profiles(tables: dict[str, pd.DataFrame], path=None, *, tau_max: float | None = None, title=None):
    """One panel per table (e.g. {'accuracy': ..., 'runtime': ...}): rho_s(tau) against log2(tau) as step
    curves, a method's colour/marker from ``style.method_style``, one legend outside the panels. Returns the
    written path (the figure is closed), or the open figure when ``path`` is None."""
    import matplotlib.pyplot as plt
    with style.figure_style():
        ncol = min(2, len(tables))
        nrow = int(np.ceil(len(tables) / ncol))
        fig, axes = plt.subplots(nrow, ncol, figsize=style.size(1.0, 0.42 * nrow if ncol > 1 else 0.6),
                                 sharey=True, squeeze=False)
        for ax in axes.ravel()[len(tables):]:
            ax.set_visible(False)
        for ax, (name, table) in zip(axes.ravel(), tables.items()):
            r = performance_ratios(table)
            fin = r.to_numpy()[np.isfinite(r.to_numpy())]
            top = tau_max or min(2.0 ** 12, max(2.0, float(np.nanmax(fin)) * 1.2 if len(fin) else 2.0))
            prof = profile(table)
            x_end = np.log2(top)
            shown = sorted(prof.columns)
            for i, m in enumerate(shown):
                taus = prof.index.to_numpy()
                keep = taus <= top
                xs = np.concatenate([np.log2(taus[keep]), [x_end]])
                ys = np.concatenate([prof[m].to_numpy()[keep], [prof[m].to_numpy()[keep][-1]]])
                kw = style.method_style(m)
                ax.step(xs, ys, where="post", color=kw["color"], linestyle=kw["linestyle"], lw=1.3)
                # the method's marker along its curve, staggered between methods: curves of like colours that
                # cross or overlap stay apart by their markers (13 methods share a 12-colour palette)
                at = x_end * (np.arange(MARKS) + (i + 0.5) / len(shown)) / MARKS
                on = ys[np.clip(np.searchsorted(xs, at, side="right") - 1, 0, len(ys) - 1)]
                ax.plot(at, on, kw["marker"], color=kw["color"], ms=3.8, mec="white", mew=0.4)
                ax.plot([], [], color=kw["color"], linestyle=kw["linestyle"], marker=kw["marker"], ms=4,
                        label=kw["label"], lw=1.3)   # the legend's entry: line and marker together
            ax.set_xlim(0, x_end)
            ax.set_ylim(-0.02, 1.02)
            ax.set_xlabel(r"$\log_2\,\tau$ (cost / best cost)")
            dropped = table.attrs.get("dropped_problems", 0)
            ax.set_title(f"{name}\n{len(table)} problems" + (f" ({dropped} incomplete dropped)" if dropped else ""),
                         fontsize=8.5)
        for row in axes:
            row[0].set_ylabel(r"share of problems $\rho_s(\tau)$")
        if title:
            fig.suptitle(title)
        style.legend_outside(fig, axes=[axes[0, 0]], where="below")
        if path is not None:
            return style.save(fig, path)
        return fig
