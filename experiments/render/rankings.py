"""Rankings across data sets: Dolan–Moré performance profiles pooled over every study that declares them.

A study opts in with ``[[rankings]]`` entries in its TOML (kept in its ``meta.json`` config)::

    [[rankings]]
    profile = "centre error against the true centre"   # studies declaring the same name are pooled
    metric = "center_error"                             # a column of the rows; lower is better
    methods = "circle.*"                                # fnmatch pattern on the method id (default: all)
    unit = "um"                                         # optional; problem = ["dataset", "data_stream", "repetition"]
                                                        # default: the values' own unit (lengths: mm for data
                                                        # in mm, else the study's length_unit or data units);
                                                        # another length unit converts mm (x 1000 for um);
                                                        # for a generator's lengths it names them ("R": unit circle)
    floor = 1e-12                                       # costs below it are equal, in the ranking's unit (that
                                                        # of its costs: unit, else the values' own); default 0
                                                        # for a time, else 1e-12 of the metric's own unit
                                                        # (1e-12 mm on mm data, 1e-9 when ranked in um)

The report names no study: it reads the declarations of whichever study folders exist. A problem is one
(study, data set, data stream, repetition); a method is a method id with its parameters. Every method run on
the pooled problems is profiled, with no config edit (a plugin method run by a study naming ``circle.*``
joins): a method not run on a problem is absent there (not a failure), and its ρ is the share of the
problems it ran on; so a study that declares a ranking adds problems and never removes a method from it.
A problem no method solved is left out (it counts for nobody: no inf == inf "win") and counted in
``unsolved``. Rows that finished (status ok) without the metric at all (the published study's rounding Monte
Carlo rows have no form error or runtime) are not problems of the ranking: a problem on which no row carries
the metric and every row is ok is left out without being called unsolved (counted in ``not_measured``).
"""
from __future__ import annotations

import fnmatch
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from experiments.render.profiles import method_label, problem_table

DEFAULT_PROBLEM = ("dataset", "data_stream", "repetition")


@dataclass
class Ranking:
    profile: str
    metric: str
    unit: str = ""
    studies: list[str] = field(default_factory=list)
    rows: list[pd.DataFrame] = field(default_factory=list, repr=False)
    left_out: list[str] = field(default_factory=list)   #: methods left out (none: every method run is profiled)
    unsolved: int = 0   #: pooled problems that no method solved (left out of the table)
    not_measured: int = 0   #: pooled problems whose rows are all ok and none carries the metric (not ranked)
    runs: dict = field(default_factory=dict)   #: method -> number of problems it ran on (of the table's)
    table: pd.DataFrame | None = field(default=None, repr=False)
    by_dataset: pd.DataFrame | None = field(default=None, repr=False)
    units: dict = field(default_factory=dict)   #: study -> the unit of its costs
    dataset_notes: list = field(default_factory=list)   #: data sets whose medians are over fewer problems (by_dataset)

    def unit_words(self) -> str:
        """Which rows are in which unit ('' when all share ``unit``): 'mm: published, scaling; R (relative to the
        radius R of the data's circle): noise'."""
        if len(set(self.units.values())) <= 1:
            return ""
        by_unit: dict = {}
        for study, u in self.units.items():
            by_unit.setdefault(u, []).append(study)
        return "; ".join(f"{UNIT_WORDS.get(u, u)}: {', '.join(st)}" for u, st in by_unit.items())


UNIT_WORDS = {"R": "R (relative to the radius R of the data's circle)"}


def ranking_unit(study: str, decl: dict, cfg: dict | None = None) -> tuple[str, float]:
    """(the unit of a declared ranking's costs, the factor the rows' values are multiplied by):
    ``experiments.units.ranking_unit`` for the study's config ``cfg`` (its ``unit`` converts lengths of a known unit
    and times, names a generator's lengths, R for unit circles; default: the values' own unit). ValueError naming the
    study when the unit cannot apply (a length ranked in s, R on mm data, a unit fitbench does not know)."""
    from experiments.units import ranking_unit as unit_of
    try:
        return unit_of(cfg if cfg is not None else {"rankings": [decl]}, decl["metric"], decl.get("unit"))
    except ValueError as exc:
        raise ValueError(f"rankings: study {study!r} declares unit {decl.get('unit')!r} for metric "
                         f"{decl['metric']!r}: {exc}") from None


#: the default floor of a ranking of a metric other than a time, in the metric's own unit (costs below it are exact)
DEFAULT_FLOOR = 1e-12


def ranking_floor(decl: dict, factor: float) -> float:
    """The floor of a declared ranking's costs (costs below it are equal, :func:`problem_table`), in the ranking's
    unit, the unit its costs are in (``factor``: the values' own unit to it, :func:`ranking_unit`): its ``floor`` as
    given, else 0 for a time (a runtime is never exact: every difference counts, whether ranked in s or ms) and
    :data:`DEFAULT_FLOOR` of the metric's own unit for another metric, converted (1e-12 mm is 1e-9 in um), so the
    default ties the same costs whatever unit they are shown in."""
    from experiments.units import column_unit
    if decl.get("floor") is not None:
        return float(decl["floor"])
    return 0.0 if column_unit(str(decl["metric"])) == "s" else DEFAULT_FLOOR * float(factor)


def collect(studies: list[tuple[str, Path, dict]]) -> dict[str, Ranking]:
    """``studies``: (name, folder, meta) of every readable study. Returns the rankings by profile name;
    a study's unreadable rows raise ValueError naming the study."""
    out: dict[str, Ranking] = {}
    for name, folder, meta in studies:
        decls = (meta.get("config") or {}).get("rankings") or []
        if not decls:
            continue
        try:
            rows = pd.read_csv(folder / "results.csv", keep_default_na=False, na_values=[""], low_memory=False)
        except (OSError, ValueError, pd.errors.ParserError) as exc:
            raise ValueError(f"rankings: the rows of study {name!r} are unreadable ({exc})") from None
        for d in decls:
            metric = d["metric"]
            if metric not in rows.columns:
                raise ValueError(f"rankings: study {name!r} declares metric {metric!r}, which its rows do not have")
            sel = rows[[fnmatch.fnmatchcase(str(m), d.get("methods", "*")) for m in rows["method"]]]
            for k, v in (d.get("where") or {}).items():
                sel = sel[sel[k].isin(v if isinstance(v, list) else [v])]
            problem = [c for c in d.get("problem", DEFAULT_PROBLEM) if c in sel.columns]
            unit, factor = ranking_unit(name, d, meta.get("config") or {})
            part = pd.DataFrame({"study": name, "problem": sel[problem].astype(str).agg(" | ".join, axis=1),
                                 "dataset": sel["dataset"].astype(str) if "dataset" in sel else "",
                                 "method": sel["method"], "params": sel.get("params", pd.Series("", index=sel.index)),
                                 "status": sel["status"], "cost": pd.to_numeric(sel[metric], errors="coerce") * factor,
                                 "floor": ranking_floor(d, factor)})
            r = out.setdefault(d["profile"], Ranking(d["profile"], metric, unit))
            # a problem whose rows all finished without the metric does not measure it: not a problem here
            blank = (part["cost"].isna() & (part["status"] == "ok")).groupby(part["problem"]).transform("all")
            r.not_measured += int(part.loc[blank, "problem"].nunique())
            part = part[~blank]
            r.units[name] = unit
            if r.unit != unit:          # rows in different units: the table says which (Ranking.unit_words)
                r.unit = ""
            r.studies.append(name)
            r.rows.append(part)
    for r in out.values():
        _tabulate(r)
    return out


def _tabulate(r: Ranking) -> None:
    labelled = []
    for part in r.rows:
        part = part.assign(label=[method_label(m, p) for m, p in zip(part["method"], part["params"])])
        labelled.append(part)
    r.left_out = []
    rows = pd.concat(labelled, ignore_index=True)
    # each study's costs are floored in its own unit (pooled rankings may mix mm and µm rows): the largest floor
    # of them all applied to every row would tie costs of another unit far above their own floor
    rows = rows.assign(cost=np.maximum(rows["cost"].abs(), rows["floor"]))
    floor = float(rows["floor"].min()) if len(rows) else 0.0
    rows = rows.assign(problem=rows["study"] + " | " + rows["problem"])
    table = problem_table(rows.assign(**{r.metric: rows["cost"]}).drop(columns=["method", "params"])
                          .rename(columns={"label": "method"}),
                          metric=r.metric, problem=("problem",), floor=floor, complete=False)
    solved = np.isfinite(table.to_numpy(float)).any(axis=1)
    r.unsolved = int((~solved).sum())
    attrs = dict(table.attrs)
    table = table[solved]
    table.attrs.update(attrs, unsolved_problems=r.unsolved)
    r.table = table
    r.runs = {m: int(table[m].notna().sum()) for m in table.columns}
    r.by_dataset, r.dataset_notes = by_dataset(r.table)


def by_dataset(table: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """(the median cost of each method per data set, the sentences saying over which problems). The medians of a
    data set are over the same problems for every method: those every method run on the data set ran on (a method
    skipped on its largest problems, max_n or ``on``, would otherwise have a median over its easier problems only,
    and look best); a median of inf is a method that failed on at least half of them, NaN one never run on the data
    set (absent, not failed). A data set without a problem that every method of its row ran on is left out, and
    said so."""
    sets = pd.Series([p.split(" | ")[0] + ": " + p.split(" | ")[1] for p in table.index], index=table.index)
    medians, notes, left_out = {}, [], []
    for name in dict.fromkeys(sets):
        costs = table[(sets == name).to_numpy()]
        ran = costs.columns[costs.notna().any(axis=0).to_numpy()]
        common = costs[ran].notna().all(axis=1).to_numpy()
        if not common.any():
            left_out.append(name)
            continue
        medians[name] = costs[common].median()
        if not common.all():
            fewer = ", ".join(f"{m} ran on {int(costs[m].notna().sum())}" for m in ran
                              if costs[m].notna().sum() < len(costs))
            notes.append(f"{name}: {int(common.sum())} of its {len(costs)} problems ({fewer})")
    if left_out:
        notes.append(f"left out, no problem that every method of the row ran on: {', '.join(left_out)}")
    med = pd.DataFrame.from_dict(medians, orient="index", columns=table.columns)
    med.index.name, med.columns.name = "data set", None
    return med, notes
