"""Multilateration lengths (:func:`read_multilateration`): a measurements table (station, x, y,
z, length; optionally the tool offset xp, yp, zp) and an optional stations table (station, x, y, z, dead-path L),
as :class:`methods.multilateration.MultilaterationData`; lengths in mm from each column's header unit
(``x [mm]``, ``length [m]``), else ``--unit``, else mm."""
from __future__ import annotations

import numpy as np

from datasets.io._pandas import pd
from datasets.io.headers import LENGTH_UNITS, parse_name, unit_refusal
from datasets.io.numbers import DataFileError
from datasets.io.tables import _numeric_column, read_table
from methods.units import canonical, to_mm


def _multilateration_table(path, need: tuple[str, ...], optional: tuple[str, ...] = (), skip_rows: int = 0,
                           unit: str | None = None):
    """(stations, {column: values in mm}, line numbers, {column: unit}) of a multilateration table. Header names
    are read like every reader's (:func:`parse_name`: ``x [mm]``, ``length [m]``, ``L (mm)``); a column's unit
    is its header's, else ``unit`` (--unit), else mm; a header unit contradicting ``unit`` is an error."""
    df, line_of = read_table(path, keep_default_na=False, skip_rows=skip_rows,
                             no_data_hint=f"need a header {','.join(need)} and one row per measurement")
    names, units = [], {}
    for c in df.columns:
        key, u = parse_name(c)
        key = "L" if key == "l" else key
        names.append(key)
        if u is not None and key in need[1:] + optional:
            if u not in LENGTH_UNITS.values():
                raise unit_refusal(path, c, u)
            if unit is not None and canonical(unit) != u:
                raise DataFileError(f"{path}: the header says column {str(c).strip()!r} is in {u} but --unit says "
                                    f"{canonical(unit)}; drop --unit or correct the header")
            units[key] = u
    df.columns = names
    missing = [c for c in need if c not in df.columns]
    if missing:
        raise DataFileError(f"{path}: missing column(s) {', '.join(missing)}; the header must name {', '.join(need)}"
                            " (units in brackets allowed: x [mm])")
    empty = (df[list(need)].isna() | (df[list(need)].apply(lambda c: c.str.strip()) == "")).any(axis=1).to_numpy()
    if empty.any():
        k = int(np.flatnonzero(empty)[0])
        raise DataFileError(f"{path} line {line_of[k]}: missing field(s)")
    line_of = np.array(line_of)
    numeric = {}
    present = [c for c in optional if c in df.columns]
    if present and len(present) != len(optional):
        raise DataFileError(f"{path}: give all of {', '.join(optional)} or none (found {', '.join(present)})")
    default = canonical(unit) if unit is not None else "mm"
    for c in list(need[1:]) + present:
        units.setdefault(c, default)
        numeric[c] = to_mm(_numeric_column(df[c], c, path, line_of), units[c])
    return df["station"].astype(str).str.strip().to_numpy(), numeric, line_of, units


def read_multilateration(path, stations_path=None, *, unit: str | None = None, skip_rows: int = 0,
                         with_units: bool = False):
    """Multilateration lengths: a measurements table (station, x, y, z, length; optionally xp, yp, zp) and,
    optionally, a stations table (station, x, y, z, L), as :class:`methods.multilateration.MultilaterationData`
    (``from_frame``). Lengths in mm from each column's header unit (``x [mm]``, ``length [m]``), else ``unit``
    (the files' length unit, --unit), else mm. ``with_units``: also return {column: unit} of the measurements."""
    from methods.multilateration import from_frame
    st, num, lines, units = _multilateration_table(path, ("station", "x", "y", "z", "length"),
                                                   optional=("xp", "yp", "zp"), skip_rows=skip_rows, unit=unit)
    df = pd.DataFrame({"station": st, **num})
    data = from_frame(df, str(path), lines=lines)
    if stations_path is not None:
        sst, snum, slines, _ = _multilateration_table(stations_path, ("station", "x", "y", "z", "L"),
                                                      skip_rows=skip_rows, unit=unit)
        pos = {}
        for r, s in enumerate(sst):
            if s in pos:
                raise DataFileError(f"{stations_path} line {slines[r]}: station {s} appears twice")
            pos[s] = [snum["x"][r], snum["y"][r], snum["z"][r], snum["L"][r]]
        absent = [s for s in data.stations if s not in pos]
        if absent:
            raise DataFileError(f"{stations_path}: no position for station(s) {', '.join(absent)} of {path}")
        data = data.with_stations([pos[s] for s in data.stations])
    return (data, units) if with_units else data
