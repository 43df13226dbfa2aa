"""Positioning measurements (ISO 230-2): readers and the validated container.

Layouts read (``read_csv``):

* long format, one measurement per row: ``target, direction, run, deviation`` (or ``actual``), the
  layout of ISO 230-2's own data tables (a value per target, approach direction and run);
* wide format, one column per run as laser-interferometer software exports it: ``target`` then
  ``run 1 +``, ``run 1 -``, ... (also ``run1_up/run1_down``, ``Run 1 Forward/Reverse``, ``1↑/1↓``), or
  ``target, direction, run 1, run 2, ...`` with a row per target and direction. This follows the
  tabular exports of Renishaw LaserXL/CARTO (a column of deviations per run and direction beside the
  target positions, errors often in µm) as shown in public calibration reports; the exact column titles
  of each software version are not publicly specified, hence the tolerant matching (confidence: medium
  for the layout, low for the exact titles). Run columns without any direction (``target, run 1, run 2``)
  are a unidirectional test approached in the + direction; a long table may hold one direction only:
  then only the unidirectional figures (A, E, R of that direction) are evaluated.

Units: ``unit`` for the targets (and ``actual``), ``deviation_unit`` for the deviations (default:
``unit``); everything is returned in mm. Deviations implausible for the declared unit (beyond 0.1 % of
the travel and 0.1 mm, or all below 10 nm) give a warning naming the likely unit.
"""
from __future__ import annotations

from dataclasses import dataclass

import re

import numpy as np

from methods._errors import InvalidInputError
from methods._validation import read_table
from methods.units import canonical, to_mm, warn_implausible
from methods._lazy import lazy_module

pd = lazy_module("pandas")


MAX_ABS_DEVIATION_MM = 1e6     # larger deviations are not measurements (and overflow the statistics)
TARGET_NAMES = ("target", "position", "target position", "target [mm]", "target (mm)", "target position (mm)",
                "target position [mm]", "position [mm]", "position (mm)", "nominal", "soll", "sollposition")
_RUN = re.compile(r"^\s*(?:run|lauf|messung|r)?\s*[_#.]?\s*(\d+)\s*[_\s(\[]*"
                  r"(\+|-|up|down|u|d|fwd|rev|forward|reverse|pos|neg|↑|↓|hin|rück|rueck)?\s*[)\]]?\s*(?:\[.*\]|\(.*\))?\s*$",
                  re.IGNORECASE)

UP = {"+", "up", "u", "positive", "pos", "↑"}
DOWN = {"-", "down", "d", "negative", "neg", "↓"}


@dataclass(frozen=True)
class PositioningData:
    """Deviations x[i, j] (target i, run j) for each direction, in the input unit."""

    targets: np.ndarray   # (m,)
    up: np.ndarray | None     # (m, n) deviations approaching in the + direction (None: unidirectional test, - only)
    down: np.ndarray | None   # (m, n) deviations approaching in the - direction (None: unidirectional test, + only)
    unit: str = ""

    @property
    def runs(self) -> int:
        return (self.up if self.up is not None else self.down).shape[1]

    @property
    def directions(self) -> tuple:
        """The approach directions measured: ('up', 'down') for a bidirectional test."""
        return tuple(d for d in ("up", "down") if getattr(self, d) is not None)


def _direction(value, lineno, name):
    v = str(value).strip().lower()
    if v in UP:
        return "up"
    if v in DOWN:
        return "down"
    raise InvalidInputError(f"{name} line {lineno}: direction {value!r} is not one of +, -, up, down")


def from_frame(df: pd.DataFrame, name: str = "data", lines=None, *, unit: str = "mm",
               deviation_unit: str | None = None) -> PositioningData:
    """Validate a long table (columns target, direction, run, and actual or deviation); lengths to mm."""
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
    dev_unit = deviation_unit or unit
    numeric["target"] = to_mm(numeric["target"], unit)
    if "deviation" in numeric:
        dev = to_mm(numeric["deviation"], dev_unit)
    else:
        dev = to_mm(numeric["actual"], unit) - numeric["target"]
        dev_unit = unit
    big = np.flatnonzero(np.abs(dev) > MAX_ABS_DEVIATION_MM)
    if big.size:
        raise InvalidInputError(f"{name} line {lines[big[0]]}: a deviation of {dev[big[0]]:.3g} mm is not a measurement "
                                f"(larger than {MAX_ABS_DEVIATION_MM:g} mm); check the file and --unit")
    travel = float(np.ptp(numeric["target"])) if len(dev) else 0.0
    peak = float(np.max(np.abs(dev))) if len(dev) else 0.0
    if travel > 0 and not warn_implausible("positioning deviations", peak, max(1e-3 * travel, 0.1), dev_unit,
                                           typical_mm=1e-5 * travel):
        if 0 < peak < 1e-5:
            import warnings
            warnings.warn(f"positioning deviations of at most {peak * 1e6:.3g} nm (read as {canonical(dev_unit)}) are "
                          "implausibly small; is the file in mm? (--unit mm)", UserWarning, stacklevel=2)
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
    arrays = {"up": None, "down": None}
    present = [d for d in ("up", "down") if (table["direction"] == d).any()]
    for d in present:
        sub = table[table["direction"] == d]
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
    return PositioningData(targets=targets, up=arrays["up"], down=arrays["down"], unit="mm")


def _wide_to_long(df: pd.DataFrame, name: str, lines) -> tuple[pd.DataFrame, np.ndarray] | None:
    """A wide export (one column per run) as the long table; None when ``df`` is not wide."""
    cols = [str(c).strip() for c in df.columns]
    low = [c.lower() for c in cols]
    t = next((low.index(n) for n in TARGET_NAMES if n in low), None)
    if t is None or "run" in low:
        return None
    d_col = low.index("direction") if "direction" in low else None
    runs = {}
    for k, c in enumerate(cols):
        if k in (t, d_col):
            continue
        m = _RUN.match(c)
        if not m:
            raise InvalidInputError(f"{name}: column {c!r} is neither the target, a direction nor a run "
                                    "(wide layout: target, run 1 +, run 1 -, ... or target, direction, run 1, run 2, ...)")
        runs[k] = (int(m.group(1)), m.group(2))
    if not runs:
        return None
    rows = []
    for k, (run, tag) in runs.items():
        if d_col is not None:
            if tag:
                raise InvalidInputError(f"{name}: column {cols[k]!r} names a direction and the file has a direction column")
            direction = df.iloc[:, d_col].to_numpy()
        else:
            # no direction anywhere: a unidirectional test approached in the + direction
            direction = np.full(len(df), "+" if tag is None or tag.lower() in ("+", "up", "u", "fwd", "forward", "pos",
                                                                                "↑", "hin") else "-")
        rows.append(pd.DataFrame({"target": df.iloc[:, t].to_numpy(), "direction": direction, "run": run,
                                  "deviation": df.iloc[:, k].to_numpy(), "_line": lines}))
    long = pd.concat(rows, ignore_index=True)
    return long.drop(columns="_line"), long["_line"].to_numpy()


def read_csv(path, *, unit: str = "mm", deviation_unit: str | None = None, skip_rows: int = 0) -> PositioningData:
    """Read a positioning file, long or wide layout (see the module docstring); comma, semicolon, tab or
    whitespace separated, decimal commas in semicolon/tab files, '#' comments, ``skip_rows`` preamble
    lines. Lengths converted to mm from ``unit`` (targets) and ``deviation_unit`` (deviations)."""
    df, lines = read_table(path, skip_rows=skip_rows)
    if df.isna().any().any():
        k = int(np.flatnonzero(df.isna().any(axis=1).to_numpy())[0])
        raise InvalidInputError(f"{path} line {lines[k]}: missing field(s)")
    lines = np.array(lines)
    wide = _wide_to_long(df, str(path), lines)
    if wide is not None:
        df, lines = wide
    return from_frame(df, str(path), lines=lines, unit=unit, deviation_unit=deviation_unit)


def validate(data, method_id="") -> PositioningData:
    """The registry's validator for the positioning family."""
    if isinstance(data, PositioningData):
        return data
    if isinstance(data, pd.DataFrame):
        return from_frame(data, method_id or "data")
    raise InvalidInputError(f"{method_id}: positioning methods take PositioningData or a DataFrame with columns "
                            f"target, direction, run, actual/deviation (got {type(data).__name__})")
