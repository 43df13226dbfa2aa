"""Multilateration measurements: one length per (station, nominal point), and optionally known stations
(files are read by :func:`datasets.io.read_multilateration`).

Measurements CSV: ``station, x, y, z, length`` (nominal point, measured length P_i(k) in mm, eq. 5), and
optionally ``xp, yp, zp``: the tool (reflector) offset of that point, needed to identify the geometric errors
(the axis position is the nominal point minus the offset).
Stations CSV: ``station, x, y, z, L`` (position and dead-path offset L_k). Stations keep their order of
first appearance, points the order of first appearance of their nominal (x, y, z).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from methods._errors import InvalidInputError
from methods._lazy import lazy_module

pd = lazy_module("pandas")


@dataclass(frozen=True)
class MultilaterationData:
    """``lengths[i, k]`` = P_i(k) of nominal point ``points[i]`` seen from station ``stations[k]`` (NaN: not
    measured); ``known_stations`` (K, 4) = [x, y, z, L] per station when given."""

    stations: tuple
    points: np.ndarray            # (N, 3) nominal
    lengths: np.ndarray           # (N, K)
    known_stations: np.ndarray | None = None
    offsets: np.ndarray | None = None     # (N, 3) tool offsets when given

    @property
    def mask(self) -> np.ndarray:
        return np.isfinite(self.lengths)

    def to_frame(self) -> pd.DataFrame:
        i, k = np.nonzero(self.mask)
        order = np.lexsort((i, k))
        i, k = i[order], k[order]
        df = pd.DataFrame({"station": np.asarray(self.stations, dtype=object)[k], "x": self.points[i, 0],
                           "y": self.points[i, 1], "z": self.points[i, 2], "length": self.lengths[i, k]})
        if self.offsets is not None:
            for c, name in enumerate(("xp", "yp", "zp")):
                df[name] = self.offsets[i, c]
        return df

    def stations_frame(self) -> pd.DataFrame:
        s = self.known_stations
        return pd.DataFrame({"station": list(self.stations), "x": s[:, 0], "y": s[:, 1], "z": s[:, 2], "L": s[:, 3]})

    def with_stations(self, stations) -> "MultilaterationData":
        return MultilaterationData(self.stations, self.points, self.lengths, _check_stations(stations, len(self.stations)),
                                   self.offsets)


def _check_stations(stations, k):
    if stations is None:
        return None
    s = np.asarray(stations, float)
    if s.shape != (k, 4):
        raise InvalidInputError(f"known stations must be a ({k}, 4) array [x, y, z, L], got shape {s.shape}")
    if not np.all(np.isfinite(s)):
        raise InvalidInputError("known stations contain NaN or infinite values")
    return s


def from_frame(df: pd.DataFrame, name: str = "data", lines=None, known_stations=None) -> MultilaterationData:
    """Long table (station, x, y, z, length) -> :class:`MultilaterationData`."""
    cols = {str(c).strip().lower(): c for c in df.columns}
    missing = [c for c in ("station", "x", "y", "z", "length") if c not in cols]
    if missing:
        raise InvalidInputError(f"{name}: missing column(s) {', '.join(missing)} (need station, x, y, z, length)")
    lines = np.arange(len(df)) + 2 if lines is None else np.asarray(lines)
    st = df[cols["station"]].astype(str).str.strip().to_numpy()
    xyz = np.column_stack([pd.to_numeric(df[cols[c]], errors="coerce").to_numpy(float) for c in "xyz"])
    length = pd.to_numeric(df[cols["length"]], errors="coerce").to_numpy(float)
    bad = np.flatnonzero(~(np.all(np.isfinite(xyz), axis=1) & np.isfinite(length)))
    if bad.size:
        raise InvalidInputError(f"{name} line {lines[bad[0]]}: x, y, z and length must be finite numbers")
    stations, s_idx = np.unique(st, return_index=True)
    stations = tuple(st[np.sort(s_idx)])
    k_of = {s: k for k, s in enumerate(stations)}
    kk = np.array([k_of[s] for s in st])
    _, first, inverse = np.unique(xyz, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    order = np.argsort(first)                         # unique points in order of first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    ii = rank[inverse]
    points = xyz[np.sort(first)]
    lengths = np.full((points.shape[0], len(stations)), np.nan)
    dup = pd.Series(list(zip(ii, kk))).duplicated().to_numpy()
    if dup.any():
        r = int(np.flatnonzero(dup)[0])
        raise InvalidInputError(f"{name} line {lines[r]}: station {st[r]} measured point ({xyz[r, 0]:g}, {xyz[r, 1]:g}, "
                                f"{xyz[r, 2]:g}) twice; keep one length per station and point (or average them)")
    lengths[ii, kk] = length
    offsets = None
    if all(c in cols for c in ("xp", "yp", "zp")):
        off = np.column_stack([pd.to_numeric(df[cols[c]], errors="coerce").to_numpy(float) for c in ("xp", "yp", "zp")])
        bad = np.flatnonzero(~np.all(np.isfinite(off), axis=1))
        if bad.size:
            raise InvalidInputError(f"{name} line {lines[bad[0]]}: xp, yp, zp must be finite numbers")
        offsets = np.full(points.shape, np.nan)
        offsets[ii] = off
        clash = np.flatnonzero(np.any(offsets[ii] != off, axis=1))
        if clash.size:
            r = int(clash[0])
            raise InvalidInputError(f"{name} line {lines[r]}: point ({xyz[r, 0]:g}, {xyz[r, 1]:g}, {xyz[r, 2]:g}) appears "
                                    f"with two different tool offsets")
    return MultilaterationData(stations, points, lengths, _check_stations(known_stations, len(stations)), offsets)


def validate(data, method_id: str = "") -> MultilaterationData:
    """The registry's validator: structure, enough lengths, no degenerate geometry."""
    if isinstance(data, pd.DataFrame):
        data = from_frame(data, method_id or "data")
    if not isinstance(data, MultilaterationData):
        raise InvalidInputError(f"{method_id}: multilateration methods take MultilaterationData or a DataFrame with "
                                f"columns station, x, y, z, length (got {type(data).__name__})")
    n, k = data.lengths.shape
    mask = data.mask
    if data.known_stations is None:
        per_station = mask.sum(axis=0)
        few = np.flatnonzero(per_station < 5)
        if few.size:
            raise InvalidInputError(f"{method_id}: station {data.stations[few[0]]} measured {per_station[few[0]]} point(s); "
                                    f"locating a station and its dead path needs at least 5 non-coplanar points")
        for kk in range(k):
            P = data.points[mask[:, kk]]
            s = np.linalg.svd(P - P.mean(axis=0), compute_uv=False)
            if s[2] <= 1e-9 * s[0]:
                raise InvalidInputError(f"{method_id}: the points measured from station {data.stations[kk]} are coplanar "
                                        f"or collinear; the station cannot be located (measure points in 3-D)")
    per_point = mask.sum(axis=1)
    need = 4 if method_id.split(".")[-1].startswith("case_b") else 3
    few = np.flatnonzero(per_point < need)
    if few.size:
        p = data.points[few[0]]
        raise InvalidInputError(f"{method_id}: point ({p[0]:g}, {p[1]:g}, {p[2]:g}) has {per_point[few[0]]} length(s); "
                                f"this method needs at least {need} stations per point")
    return data
