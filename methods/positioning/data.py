"""Positioning measurements (ISO 230-2): a long table target / direction / run / deviation."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from methods._errors import InvalidInputError
from methods._validation import read_table

UP = {"+", "up", "u", "positive", "pos", "↑"}
DOWN = {"-", "down", "d", "negative", "neg", "↓"}


@dataclass(frozen=True)
class PositioningData:
    """Deviations x[i, j] (target i, run j) for each direction, in the input unit."""

    targets: np.ndarray   # (m,)
    up: np.ndarray        # (m, n) deviations approaching in the + direction
    down: np.ndarray      # (m, n) deviations approaching in the - direction
    unit: str = ""

    @property
    def runs(self) -> int:
        return self.up.shape[1]


def _direction(value, lineno, name):
    v = str(value).strip().lower()
    if v in UP:
        return "up"
    if v in DOWN:
        return "down"
    raise InvalidInputError(f"{name} line {lineno}: direction {value!r} is not one of +, -, up, down")


def from_frame(df: pd.DataFrame, name: str = "data", lines=None) -> PositioningData:
    """Validate a long table (columns target, direction, run, and actual or deviation)."""
    cols = {c.lower().strip(): c for c in df.columns}
    for need in ("target", "direction", "run"):
        if need not in cols:
            raise InvalidInputError(f"{name}: missing column {need!r} (need target, direction, run, and actual or deviation)")
    if "deviation" not in cols and "actual" not in cols:
        raise InvalidInputError(f"{name}: needs a column 'actual' (measured position) or 'deviation'")
    lines = lines if lines is not None else np.arange(len(df)) + 2
    numeric = {}
    for key in ("target", "run", "deviation" if "deviation" in cols else "actual"):
        col = pd.to_numeric(df[cols[key]], errors="coerce")
        bad = np.flatnonzero(~np.isfinite(col.to_numpy(dtype=float)))
        if bad.size:
            raise InvalidInputError(f"{name} line {lines[bad[0]]}: {key} {df[cols[key]].iloc[bad[0]]!r} is not a finite number")
        numeric[key] = col.to_numpy(dtype=float)
    dev = numeric["deviation"] if "deviation" in numeric else numeric["actual"] - numeric["target"]
    dirs = [_direction(v, lines[k], name) for k, v in enumerate(df[cols["direction"]])]
    table = pd.DataFrame({"target": numeric["target"], "direction": dirs, "run": numeric["run"], "dev": dev})
    dup = table.duplicated(["target", "direction", "run"])
    if dup.any():
        k = int(np.flatnonzero(dup.to_numpy())[0])
        raise InvalidInputError(f"{name} line {lines[k]}: target {table.target[k]:g}, direction {table.direction[k]}, "
                                f"run {table.run[k]:g} appears twice")
    targets = np.sort(table["target"].unique())
    if targets.size < 2:
        raise InvalidInputError(f"{name}: needs at least two target positions, got {targets.size}")
    runs = None
    arrays = {}
    for d in ("up", "down"):
        sub = table[table["direction"] == d]
        if sub.empty:
            raise InvalidInputError(f"{name}: no measurements in the {d} direction (ISO 230-2 approaches every target both ways)")
        piv = sub.pivot(index="target", columns="run", values="dev").reindex(targets)
        for t, row in piv.iterrows():
            count = int(row.notna().sum())
            if count < 2:
                raise InvalidInputError(f"{name}: target {t:g} has {count} run(s) in the {d} direction; at least two are needed")
        if piv.isna().any().any():
            t = piv.index[piv.isna().any(axis=1)][0]
            raise InvalidInputError(f"{name}: unequal coverage: target {t:g} misses run(s) "
                                    f"{[int(r) if float(r).is_integer() else r for r in piv.columns[piv.loc[t].isna()]]} in the {d} direction")
        if runs is not None and piv.shape[1] != runs:
            raise InvalidInputError(f"{name}: unequal coverage: {runs} runs up but {piv.shape[1]} runs down")
        runs = piv.shape[1]
        arrays[d] = piv.to_numpy(dtype=float)
    return PositioningData(targets=targets, up=arrays["up"], down=arrays["down"])


def read_csv(path) -> PositioningData:
    """Read a positioning CSV (comma, semicolon or whitespace separated, '#' comments)."""
    df, lines = read_table(path)
    if df.isna().any().any():
        k = int(np.flatnonzero(df.isna().any(axis=1).to_numpy())[0])
        raise InvalidInputError(f"{path} line {lines[k]}: missing field(s)")
    return from_frame(df, str(path), lines=np.array(lines))


def validate(data, method_id="") -> PositioningData:
    """The registry's validator for the positioning family."""
    if isinstance(data, PositioningData):
        return data
    if isinstance(data, pd.DataFrame):
        return from_frame(data, method_id or "data")
    raise InvalidInputError(f"{method_id}: positioning methods take PositioningData or a DataFrame with columns "
                            f"target, direction, run, actual/deviation (got {type(data).__name__})")
