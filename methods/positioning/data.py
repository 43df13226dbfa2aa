"""Positioning measurements (ISO 230-2): the validated container and its table form (:func:`from_frame`).
Files are read by :func:`datasets.io.read_positioning`, which accepts these layouts:

* long format, one measurement per row: ``target, direction, run, deviation`` (or ``actual``), the
  layout of ISO 230-2's own data tables (a value per target, approach direction and run);
* wide format, one column per run as laser-interferometer software exports it: ``target`` then
  ``run 1 +``, ``run 1 -``, ... (also ``run1_up/run1_down``, ``1↑/1↓``, and ``Run 1 Forward/Reverse`` or
  ``Hin/Rück``, the run order, mapped to ↑/↓ by the order of the targets in the file: :class:`RunOrderNote`), or
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

import re
from dataclasses import dataclass, replace

import numpy as np

from methods._errors import InvalidInputError
from methods.units import UnitWarning, canonical, to_mm, warn_implausible
from methods._lazy import lazy_module

pd = lazy_module("pandas")


MAX_ABS_DEVIATION_MM = 1e6     # larger deviations are not measurements (and overflow the statistics)
#: the words read as the + (↑) and - (↓) approach directions, in the order a message lists them
UP_WORDS = ("+", "up", "u", "pos", "positive", "inc", "increasing", "↑")
DOWN_WORDS = ("-", "down", "dn", "d", "neg", "negative", "dec", "decreasing", "↓")
UP, DOWN = set(UP_WORDS), set(DOWN_WORDS)


#: column words of wide laser exports that name the run order (the first and second run of a pair), not the axis
#: direction: what a forward run is depends on where the test started
RUN_ORDER_TAGS = {"fwd": "forward", "forward": "forward", "hin": "forward",
                  "rev": "reverse", "reverse": "reverse", "bwd": "reverse", "backward": "reverse", "rück": "reverse",
                  "rueck": "reverse", "zurück": "reverse", "zurueck": "reverse", "return": "reverse",
                  "vorwärts": "forward", "vorwaerts": "forward", "rückwärts": "reverse", "rueckwaerts": "reverse"}


class RunOrderNote(UserWarning):
    """How a wide export's Forward/Reverse (Hin/Rück) runs were mapped to the ISO 230-2 directions ↑/↓ (by the
    order of the targets in the file); ``forward`` is '+', '-' or None (order ambiguous, read as '+')."""

    def __init__(self, message: str, forward: str | None = None):
        super().__init__(message)
        self.forward = forward


def swap_directions(data: "PositioningData") -> "PositioningData":
    """The test with its ↑ and ↓ runs exchanged (a run-order mapping corrected by the user)."""
    return replace(data, up=data.down, down=data.up)


@dataclass(frozen=True)
class PositioningData:
    """Deviations x[i, j] (target i, run j) for each direction, in the input unit. ``direction_given`` False: a
    unidirectional test whose file names no approach direction (held in ``up``, labelled 'direction not given').
    ``runs_numbered_alike`` False: the file numbers its up and down runs differently (e.g. odd runs up, even runs
    down), so ``up[:, j]`` and ``down[:, j]`` are the j-th run of each direction in the order of their numbers."""

    targets: np.ndarray   # (m,)
    up: np.ndarray | None     # (m, n) deviations approaching in the + direction (None: unidirectional test, - only)
    down: np.ndarray | None   # (m, n) deviations approaching in the - direction (None: unidirectional test, + only)
    unit: str = ""
    direction_given: bool = True
    #: the temperature correction applied (:func:`thermal_correction`), None: the deviations as measured
    thermal: dict | None = None
    #: the up and down runs carry the same run numbers (column j of each is run j)
    runs_numbered_alike: bool = True

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
    if v in RUN_ORDER_TAGS:   # the laser software's run order (docs/positioning.md), which way the axis moved unknown
        raise InvalidInputError(f"{name} line {lineno}: direction {value!r} names the run order, not the axis direction: "
                                "write + or - (the direction the axis moved to the targets in that run)")
    numbered = (" (a number does not say which way the axis moved: the software that wrote the file says which of its "
                "numbers is the + direction)") if re.fullmatch(r"[+-]?\d+", v) else ""
    raise InvalidInputError(f"{name} line {lineno}: direction {value!r} is not a direction fitbench reads{numbered}: "
                            f"write + for the runs that approached the targets in the + direction (also read: "
                            f"{', '.join(UP_WORDS[1:])}) and - for those in the - direction "
                            f"({', '.join(DOWN_WORDS[1:])}); case is ignored")


def from_frame(df: pd.DataFrame, name: str = "data", lines=None, *, unit: str = "mm",
               deviation_unit: str | None = None, direction_given: bool = True) -> PositioningData:
    """Validate a long table (columns target, direction, run, and actual or deviation); lengths to mm.
    ``direction_given`` False: the direction column was not in the file (a unidirectional test read as '+')."""
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
    # deviations read from their own column have their own unit (--deviation-unit); the targets' unit (--unit)
    # would also rescale the travel
    option = "--deviation-unit" if "deviation" in numeric else "--unit"
    if travel > 0 and not warn_implausible("positioning deviations", peak, max(1e-3 * travel, 0.1), dev_unit,
                                           typical_mm=1e-5 * travel, option=option):
        if 0 < peak < 1e-5:
            import warnings
            warnings.warn(f"positioning deviations of at most {peak * 1e6:.3g} nm (read as {canonical(dev_unit)}) are "
                          f"implausibly small; are they in mm? ({option} mm)", UnitWarning, stacklevel=2)
    dirs = [_direction(v, lines[k], name) for k, v in enumerate(df[cols["direction"]])]
    table = pd.DataFrame({"target": numeric["target"], "direction": dirs, "run": numeric["run"], "dev": dev})
    dup = table.duplicated(["target", "direction", "run"])
    if dup.any():
        k = int(np.flatnonzero(dup.to_numpy())[0])
        raise InvalidInputError(f"{name} line {lines[k]}: target {table.target[k]:g}, direction {table.direction[k]}, "
                                f"run {table.run[k]:g} appears twice")
    targets = np.sort(table["target"].unique()) + 0.0      # -0.0 (a target written -0,0000) is 0
    if targets.size < 2:
        raise InvalidInputError(f"{name}: needs at least two target positions, got {targets.size}")
    runs = None
    arrays = {"up": None, "down": None}
    numbers = []
    present = [d for d in ("up", "down") if (table["direction"] == d).any()]
    for d in present:
        sub = table[table["direction"] == d]
        piv = sub.pivot(index="target", columns="run", values="dev").reindex(targets)
        for t, row in piv.iterrows():
            count = int(row.notna().sum())
            # one run per direction is ISO 230-2's procedure for axes over 2000 mm (E, M, B; no s, R, A)
            if count < 2 and not (count == 1 and piv.shape[1] == 1):
                raise InvalidInputError(f"{name}: target {t:g} has {count} run(s) in the {d} direction; at least two "
                                        "are needed (or one run at every target, ISO 230-2's test of axes over 2000 mm)")
        if piv.isna().any().any():
            t = piv.index[piv.isna().any(axis=1)][0]
            raise InvalidInputError(f"{name}: unequal coverage: target {t:g} misses run(s) "
                                    f"{[int(r) if float(r).is_integer() else r for r in piv.columns[piv.loc[t].isna()]]} in the {d} direction")
        if runs is not None and piv.shape[1] != runs:
            raise InvalidInputError(f"{name}: unequal coverage: {runs} runs up but {piv.shape[1]} runs down")
        runs = piv.shape[1]
        arrays[d] = piv.to_numpy(dtype=float)
        numbers.append(tuple(piv.columns))
    return PositioningData(targets=targets, up=arrays["up"], down=arrays["down"], unit="mm",
                           direction_given=direction_given or arrays["down"] is not None,
                           runs_numbered_alike=len(set(numbers)) <= 1)


def thermal_correction(data: PositioningData, material_temperature_c: float,
                       expansion_coefficient_um_per_m_k: float) -> PositioningData:
    """The nominal differential expansion (NDE) correction of ISO 230-2:2014 for a test whose axis (scale or
    workpiece) was at ``material_temperature_c`` instead of the reference temperature 20 °C (ISO 1): a length
    P measured at T stands for P (1 + alpha (T - 20)) at 20 °C, so each deviation loses alpha (T - 20) P,
    P the target position as given (mm) and alpha the expansion coefficient (µm/(m·K) = 1e-6 / K). A pure
    thermal slope alpha (T - 20) P is removed exactly. The result's ``thermal`` says what was done:
    material_temperature_c, expansion_coefficient_um_per_m_k, correction_um_per_m (-alpha (T - 20)) and
    correction_at_ends_mm ((first target, its correction), (last target, its correction)), so what is made from it
    (a controller table) can say so."""
    slope = float(expansion_coefficient_um_per_m_k) * 1e-6 * (float(material_temperature_c) - 20.0)
    P = np.asarray(data.targets, dtype=float)
    shift = slope * P[:, None]
    done = {"material_temperature_c": float(material_temperature_c),
            "expansion_coefficient_um_per_m_k": float(expansion_coefficient_um_per_m_k),
            "correction_um_per_m": -slope * 1e6,
            "correction_at_ends_mm": ((float(P[0]), float(-slope * P[0]) + 0.0), (float(P[-1]), float(-slope * P[-1]) + 0.0))}
    return replace(data, up=None if data.up is None else data.up - shift,
                   down=None if data.down is None else data.down - shift, thermal=done)


def validate(data, method_id="") -> PositioningData:
    """The registry's validator for the positioning family."""
    if isinstance(data, PositioningData):
        return data
    if isinstance(data, pd.DataFrame):
        return from_frame(data, method_id or "data")
    raise InvalidInputError(f"{method_id}: positioning methods take PositioningData or a DataFrame with columns "
                            f"target, direction, run, actual/deviation (got {type(data).__name__})")
