"""Pitch-error compensation tables from a positioning test, and writers for controllers.

The table holds, at equally spaced positions from the first target (``interval`` mm apart, default the
target spacing), the mean bidirectional deviation x(P) (the mean of the ↑ and ↓ curves: from the GLS
polynomials, ``source='model'``, or linearly interpolated between the mean deviations at the targets,
``source='mean'``), the ↑ and ↓ deviations, and the compensation value c(P) = -x(P) (what the
controller adds to the commanded position so that the axis reaches it). The mean reversal value B is
not in the table: controllers take it as a separate backlash parameter; it is written in the header.
**Check the sign convention of the controller with a verification run after loading a table.**

Writers (``WRITERS``):

A unidirectional test gives the table of its one direction (the other column is empty, B unknown).

* ``csv``: generic CSV, one row per position, lengths in mm (``position_mm, deviation_mm,
  deviation_up_mm, deviation_down_mm, compensation_mm``).
* ``siemens-eec``: SINUMERIK interpolatory compensation (LEC/EEC) as an MPF/INI part program setting the
  system variables ``$AA_ENC_COMP[0, i, AXIS]`` (compensation value of point i, mm),
  ``$AA_ENC_COMP_STEP`` (spacing, mm), ``$AA_ENC_COMP_MIN``/``_MAX`` (first and last position, mm) and
  ``$AA_ENC_COMP_IS_MODULO``, between ``%_N_AX_EEC_INI`` / ``CHANDATA(1)`` and ``M17``. Source: the
  SINUMERIK Function Manual Extended Functions, K3 Compensations, sec. 4.4.2.3 (example of compensation
  values for axis X1; edition 03/2013, 6FC5397-1BP40-3BA1), read on a public mirror of the manual.
  Confidence: high for the variable names and file layout; the number of points must not exceed the
  axis' MD38000 $MA_MM_ENC_COMP_MAX_POINTS (the header says how many are needed).
* ``fanuc-pitch``: FANUC pitch-error compensation data in the parameter-tape format: one line
  ``N<10000 + point number> P<value>`` per compensation point, the values *incremental* (the change of the
  compensation over the interval ending at that point) in detection units (default 0.001 mm), with the
  parameters to set written as comments: 3620 (point number of the reference position), 3621/3622
  (smallest/largest point number), 3623 (magnification), 3624 (interval). Sources: FANUC Series 0i-PB
  parameter manual B-63980EN/01 sec. 4 (parameters 3620-3624 and the incremental example), FANUC
  technical report A-77810E (bidirectional pitch-error compensation, parameters 3605#0, 3620-3627),
  cnc.wiki "Fanuc pitch error compensation" (input as incremental values seen from the negative
  direction, the 128-point hint). Confidence: high for the parameter numbers and the incremental
  convention; medium for the ``N10000 + n`` numbering of the tape (it depends on the series and on the
  axis' block of point numbers: check 3620-3622 of the axis). Values beyond ±127 detection units per
  interval (older series accept ±7 x magnification) get a warning.
"""
from __future__ import annotations

import warnings

import numpy as np

from methods import InvalidInputError
from methods.positioning.model import evaluate_band


def compensation_table(res, data, *, interval: float | None = None, source: str = "model") -> pd.DataFrame:
    """The table (see the module docstring); ``res`` a positioning.gls_polynomial result, ``data`` its input."""
    import pandas as pd  # loaded when a table is made (the fitbench command stays light)
    P = np.asarray(data.targets, float)
    if interval is None:
        interval = float(np.min(np.diff(P)))
    if not (np.isfinite(interval) and interval > 0):
        raise InvalidInputError(f"--interval must be a positive length in mm, got {interval!r}")
    n = int(np.floor((P[-1] - P[0]) / interval + 1e-9))
    if n < 1:
        raise InvalidInputError(f"--interval {interval:g} mm is longer than the travel measured ({P[-1] - P[0]:g} mm)")
    if n + 1 > 100_000:
        raise InvalidInputError(f"--interval {interval:g} mm gives {n + 1} points; choose a coarser interval")
    pos = P[0] + interval * np.arange(n + 1)
    dirs = data.directions
    curves = {}
    if source == "model":
        if not res.polynomial:
            raise InvalidInputError("--compensation-from model needs the GLS polynomial (positioning.gls_polynomial)")
        for d in dirs:
            curves[d] = evaluate_band(res.polynomial[d], pos)[0]
    elif source == "mean":
        for d in dirs:
            curves[d] = np.interp(pos, P, res.per_target[f"mean_{d}"])
    else:
        raise InvalidInputError(f"--compensation-from must be 'model' or 'mean', got {source!r}")
    up = curves.get("up", np.full_like(pos, np.nan))
    down = curves.get("down", np.full_like(pos, np.nan))
    mean = np.mean([curves[d] for d in dirs], axis=0)
    table = pd.DataFrame({"position_mm": pos, "deviation_mm": mean, "deviation_up_mm": up,
                          "deviation_down_mm": down, "compensation_mm": -mean})
    table.attrs.update(interval_mm=float(interval), source=source,
                       backlash_mm=float(np.mean(up - down)) if len(dirs) == 2 else float("nan"))
    return table


def _header(table, comment: str) -> list[str]:
    uni = not np.isfinite(table.attrs.get("backlash_mm", float("nan")))
    return [f"{comment} fitbench pitch-error compensation: c(P) = -({'deviation of the one direction measured' if uni else 'mean bidirectional deviation'}), "
            f"from the {table.attrs.get('source', '?')}",
            f"{comment} {len(table)} points, {table.position_mm.iloc[0]:g} to {table.position_mm.iloc[-1]:g} mm every "
            f"{table.attrs.get('interval_mm', float('nan')):g} mm; mean reversal value B = " +
            (f"{table.attrs['backlash_mm'] * 1e3:.2f} µm (set as backlash separately)" if not uni else
             "unknown (unidirectional test)"),
            f"{comment} check the controller's sign convention with a verification run"]


def write_csv(table: pd.DataFrame, axis: str = "X") -> str:
    lines = _header(table, "#")
    return "\n".join(lines) + "\n" + table.to_csv(index=False, float_format="%.6f", lineterminator="\n")


def write_siemens_eec(table: pd.DataFrame, axis: str = "X1") -> str:
    step = table.attrs["interval_mm"]
    out = ["%_N_AX_EEC_INI", *_header(table, ";"),
           f"; MD38000 $MA_MM_ENC_COMP_MAX_POINTS of {axis} must be >= {len(table)}", "CHANDATA(1)"]
    for i, c in enumerate(table.compensation_mm.to_numpy()):
        out.append(f"$AA_ENC_COMP[0,{i},{axis}]={c:.6f}")
    out += [f"$AA_ENC_COMP_STEP[0,{axis}]={step:.6f}", f"$AA_ENC_COMP_MIN[0,{axis}]={table.position_mm.iloc[0]:.6f}",
            f"$AA_ENC_COMP_MAX[0,{axis}]={table.position_mm.iloc[-1]:.6f}", f"$AA_ENC_COMP_IS_MODULO[0,{axis}]=0", "M17"]
    return "\n".join(out) + "\n"


def write_fanuc_pitch(table: pd.DataFrame, axis: str = "X", detection_unit_mm: float = 0.001,
                      reference_number: int = 0, magnification: int = 1) -> str:
    counts = np.rint(table.compensation_mm.to_numpy() / (detection_unit_mm * magnification)).astype(np.int64)
    inc = np.diff(counts, prepend=counts[0])       # incremental; 0 at the reference (first) point
    if np.any(np.abs(inc) > 127):
        warnings.warn(f"fanuc-pitch: increments up to {np.abs(inc).max()} detection units per interval; check the "
                      "controller's range (older series: +-7 x magnification) or use a larger magnification (3623)",
                      UserWarning, stacklevel=2)
    interval_units = table.attrs["interval_mm"] / detection_unit_mm
    last = reference_number + len(table) - 1
    out = ["%", f"(FITBENCH PITCH ERROR COMPENSATION, AXIS {axis.upper()}, INCREMENTAL VALUES IN DETECTION UNITS OF "
                f"{detection_unit_mm:g} MM)",
           *("(" + h[2:].replace("µm", "UM").replace("(", "").replace(")", "").upper().encode("ascii", "replace").decode()
             .strip() + ")" for h in _header(table, "#")),
           f"(SET 3620 = {reference_number} REFERENCE POINT AT {table.position_mm.iloc[0]:g} MM, 3621 = {reference_number}, "
           f"3622 = {last}, 3623 = {magnification}, 3624 = {interval_units:g})"]
    for k, v in enumerate(inc):
        out.append(f"N{10000 + reference_number + k} P{int(v)}")
    out.append("%")
    return "\n".join(out) + "\n"


WRITERS = {"csv": write_csv, "siemens-eec": write_siemens_eec, "fanuc-pitch": write_fanuc_pitch}


def write_tables(res, data, requests, *, interval=None, source="model", axis="X1", write) -> pd.DataFrame:
    """Build the table once and write it in every requested ``(format, path)`` with ``write(path, text)``;
    every format is checked before any file is written. Returns the table."""
    for fmt, _ in requests:
        if fmt not in WRITERS:
            raise InvalidInputError(f"--compensation {fmt}: unknown format; use one of {', '.join(WRITERS)}")
    table = compensation_table(res, data, interval=interval, source=source)
    texts = [(path, WRITERS[fmt](table, axis=axis)) for fmt, path in requests]
    for path, text in texts:
        write(path, text)
    return table
