"""Readers for users' files: points (any two columns), circular-test runs (x, y or angle + radial
deviation, one or both directions in one file). Header optional; comma, semicolon, tab or whitespace
separated; ``#`` and ``%`` comment lines; a semicolon file may use decimal commas; ``skip_rows`` drops a
preamble (instrument software writes test conditions above the table). Every reader takes the file's
length unit (``unit``, default mm) and returns millimetres.

The numbers are parsed by pandas' C parser straight from the file with a float64 dtype and only the
columns used (issue 16 item 20: peak memory within 3x the returned array; measured in
/work/notes/frontdoor.md). Malformed input is refused with the file name and line number (a
:class:`DataFileError`, one kind of :class:`InvalidInputError`); the line-by-line diagnosis runs only
after the fast parser failed.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field

import numpy as np

from methods import InvalidInputError
from methods._lazy import lazy_module
from methods._validation import read_text_file
from methods.units import canonical, to_mm

pd = lazy_module("pandas")

COMMENT_PREFIXES = ("#", "%", "//")
SNIFF_LINES = 200
PLANES = {"xy": ("x", "y"), "yz": ("y", "z"), "zx": ("z", "x"), "xz": ("x", "z"), "yx": ("y", "x"), "zy": ("z", "y")}


class DataFileError(InvalidInputError):
    """A points file that cannot be read; the message names the file and line."""


def _is_number(token: str) -> bool:
    try:
        float(token)
        return True
    except ValueError:
        return False


def _split(line: str, sep: str | None) -> list[str]:
    return [t.strip() for t in (line.split(sep) if sep else line.split())]


@dataclass
class Layout:
    """What the first lines of a delimited file say about it."""

    name: str
    sep: str | None                 # None: whitespace
    decimal_comma: bool
    header: list | None             # column names (as written) or None
    header_line: int                # 1-based line of the header (0: none)
    first_data_line: int            # 1-based line of the first data row
    ncol: int
    comment: str                    # the comment character the C parser skips
    preamble: list = field(default_factory=list)  # non-comment lines skipped with skip_rows

    def index(self, names, default=(0, 1)) -> list[int]:
        """Column indices of ``names`` (case-insensitive header names or 0-based integers)."""
        if names is None:
            return list(default)
        out = []
        lowered = [h.strip().lower() for h in self.header] if self.header else []
        for n in names:
            if isinstance(n, (int, np.integer)) or (isinstance(n, str) and n.strip().isdigit() and n.strip().lower() not in lowered):
                k = int(n)
                if not 0 <= k < self.ncol:
                    raise DataFileError(f"{self.name}: column {k} does not exist (the file has {self.ncol} columns, 0-based)")
                out.append(k)
            else:
                key = str(n).strip().lower()
                if key not in lowered:
                    have = ", ".join(self.header) if self.header else "no header"
                    raise DataFileError(f"{self.name}: no column {n!r} (columns: {have}); use --columns")
                out.append(lowered.index(key))
        return out


def sniff(path, skip_rows: int = 0) -> Layout:
    """Read at most the first ``SNIFF_LINES`` lines: separator, decimal comma, header, comment style."""
    name = os.fspath(path)
    if skip_rows < 0:
        raise DataFileError(f"{name}: --skip-rows must be >= 0, got {skip_rows}")
    try:
        fh = open(name, encoding="utf-8-sig")
    except FileNotFoundError:
        raise DataFileError(f"{name}: no such file (give a path or a data set name from 'datasets.list()')") from None
    except OSError as exc:
        raise DataFileError(f"{name}: cannot be read as text ({exc})") from None
    body, preamble, comment = [], [], "#"
    try:
        with fh:
            for lineno, raw in enumerate(fh, start=1):
                ln = raw.strip()
                if lineno <= skip_rows:
                    preamble.append(ln)
                    continue
                if not ln:
                    continue
                if ln.startswith(COMMENT_PREFIXES):
                    if ln.startswith("%"):
                        comment = "%"
                    continue
                body.append((lineno, ln))
                if len(body) >= SNIFF_LINES:
                    break
    except (UnicodeDecodeError, OSError) as exc:
        raise DataFileError(f"{name}: cannot be read as text ({exc})") from None
    if not body:
        raise DataFileError(f"{name}: no data lines (only blank or comment lines)")
    first = body[0][1]
    sep = ";" if ";" in first else "," if "," in first else "\t" if "\t" in first else None
    if sep == "\t" and any(" " in ln.replace("\t", "") and "\t" not in ln for _, ln in body[1:]):
        sep = None  # tabs and spaces mixed: whitespace
    decimal_comma = sep in (";", "\t", None) and any(re.search(r"\d,\d", ln) for _, ln in body[:50])
    head = _split(first, sep)
    numeric = all(_is_number(t.replace(",", ".") if decimal_comma else t) for t in head)
    if numeric:
        return Layout(name, sep, decimal_comma, None, 0, body[0][0], len(head), comment, preamble)
    if len(body) < 2:
        raise DataFileError(f"{name}: a header but no data lines")
    return Layout(name, sep, decimal_comma, head, body[0][0], body[1][0], len(head), comment, preamble)


def _diagnose(layout: Layout, idx, skip_rows: int):
    """Locate the first bad line (runs only after the fast parser failed)."""
    name = layout.name
    text = read_text_file(name, error=DataFileError)
    for lineno, ln in enumerate(text.splitlines(), start=1):
        ln = ln.strip()
        if lineno < layout.first_data_line or not ln or ln.startswith(COMMENT_PREFIXES):
            continue
        toks = _split(ln, layout.sep)
        if len(toks) != layout.ncol:
            raise DataFileError(f"{name} line {lineno}: {len(toks)} fields where the first line has {layout.ncol}: {ln!r}")
        for j in idx:
            tok = toks[j].replace(",", ".") if layout.decimal_comma else toks[j]
            if not _is_number(tok):
                raise DataFileError(f"{name} line {lineno}: {toks[j]!r} is not a number")
            if not np.isfinite(float(tok)):
                raise DataFileError(f"{name} line {lineno}: {toks[j]!r} is not a finite number; remove or repair the point")
    raise DataFileError(f"{name}: could not be parsed (unexpected format); use one row of numbers per line")


#: files up to this size are parsed without pandas (whose import costs ~0.3 s, issue 20: fast start-up)
SMALL_FILE_BYTES = 1 << 16


def _read_small(layout: Layout, usecols: list[int]) -> dict | None:
    """The float columns ``usecols`` of a small, plain numeric file, read with Python's float (correctly
    rounded); None when the file is large or anything is unusual (an inline comment, a short row, a token
    that is not a number), and the pandas reader below decides (and explains)."""
    try:
        if os.path.getsize(layout.name) > SMALL_FILE_BYTES:
            return None
        with open(layout.name, encoding="utf-8-sig") as fh:
            text = fh.read()
    except (OSError, UnicodeDecodeError):
        return None
    rows = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        ln = raw.strip()
        if lineno < layout.first_data_line or not ln or ln.startswith(layout.comment):
            continue
        if layout.comment in ln:
            return None
        tokens = _split(ln, layout.sep)
        if len(tokens) != layout.ncol:
            return None
        try:
            rows.append([float(tokens[k].replace(",", ".") if layout.decimal_comma else tokens[k]) for k in usecols])
        except ValueError:
            return None
    if not rows:
        return None
    table = np.array(rows, dtype=np.float64)
    return {k: table[:, j].copy() for j, k in enumerate(usecols)}


def read_columns(layout: Layout, idx: list[int], *, skip_rows: int = 0, strings: tuple[int, ...] = ()) -> dict:
    """The columns ``idx`` as float64 arrays (and ``strings`` as object arrays), straight from the file."""
    usecols = sorted(set(idx) | set(strings))
    small = None if strings else _read_small(layout, usecols)
    if small is not None:
        if not all(np.isfinite(small[k]).all() for k in idx):
            _diagnose(layout, idx, skip_rows)
        return small
    dtype = {k: (object if k in strings else np.float64) for k in usecols}
    try:
        frame = pd.read_csv(layout.name, sep=r"\s+" if layout.sep is None else layout.sep, header=None,
                            skiprows=layout.first_data_line - 1, dtype=dtype,
                            usecols=None if len(usecols) == layout.ncol else usecols,
                            decimal="," if layout.decimal_comma else ".", comment=layout.comment,
                            skip_blank_lines=True, engine="c",
                            encoding="utf-8-sig", keep_default_na=True)
        cols = {k: frame[k].to_numpy() for k in usecols}
        del frame
        ok = all(np.isfinite(cols[k]).all() for k in idx)
    except (ValueError, pd.errors.ParserError, UnicodeDecodeError):
        ok = False
    if not ok:
        _diagnose(layout, idx, skip_rows)
    if not all(len(cols[k]) for k in usecols):
        raise DataFileError(f"{layout.name}: a header but no data lines")
    return cols


def read_points(path, columns=("x", "y"), *, plane: str | None = None, unit: str = "mm", skip_rows: int = 0) -> np.ndarray:
    """Read an (N, 2) float array (mm) from a text file.

    ``columns``: two header names (case-insensitive) or 0-based indices; ``plane`` ('xy', 'yz', 'zx')
    picks the named columns of that plane. Without a header the file must have exactly two columns
    (or ``columns`` as indices); with a header lacking the names, the first two columns are used only
    when the file has exactly two, else the error lists the columns. ``unit``: the file's length unit."""
    layout = sniff(path, skip_rows)
    if plane is not None:
        if plane.lower() not in PLANES:
            raise DataFileError(f"unknown plane {plane!r}; use one of {', '.join(PLANES)}")
        columns = PLANES[plane.lower()]
        idx = layout.index(columns)
    elif layout.header is None:
        explicit = columns is not None and all(isinstance(c, (int, np.integer)) or str(c).strip().isdigit() for c in columns)
        if explicit:
            idx = layout.index(columns)
        elif layout.ncol != 2:
            raise DataFileError(f"{layout.name} line {layout.first_data_line}: {layout.ncol} columns and no header; "
                                "add a header line naming the x and y columns (or --columns 0 1)")
        else:
            idx = [0, 1]
    else:
        if len(layout.header) < 2:
            raise DataFileError(f"{layout.name} line {layout.header_line}: header has fewer than two columns")
        lowered = [h.strip().lower() for h in layout.header]
        wanted = columns or ("x", "y")
        if all(isinstance(c, str) and c.strip().lower() in lowered for c in wanted) or \
                any(isinstance(c, (int, np.integer)) for c in wanted) or columns not in (None, ("x", "y")):
            idx = layout.index(wanted)
        elif layout.ncol == 2:
            idx = [0, 1]
        else:
            raise DataFileError(f"{layout.name}: which two columns? the header has {', '.join(layout.header)}; "
                                "give --columns NAME NAME or --plane xy|yz|zx")
    if len(idx) != 2 or idx[0] == idx[1]:
        raise DataFileError(f"{layout.name}: give two different columns, got {columns!r}")
    cols = read_columns(layout, idx, skip_rows=skip_rows)
    out = np.empty((len(cols[idx[0]]), 2), dtype=np.float64)
    out[:, 0], out[:, 1] = cols[idx[0]], cols[idx[1]]
    if unit != "mm":
        out *= to_mm(1.0, unit)
    return out


# ------------------------------------------------------------------ circular-test runs
ANGLE_NAMES = ("angle", "theta", "angle_deg", "angle_rad", "angle [deg]", "angle [rad]", "angle (deg)", "angle (rad)",
               "angle[deg]", "angle[rad]", "angle/deg", "angle/°", "angle [°]", "angle (°)", "winkel")
DEVIATION_NAMES = ("deviation", "radial_deviation", "radial deviation", "dr", "error", "radial_error",
                   "deviation [um]", "deviation [µm]", "deviation (um)", "deviation (µm)", "deviation [mm]", "abweichung")
DIRECTION_NAMES = ("direction", "dir", "run", "pass", "richtung")
CW_WORDS = {"cw", "g02", "g2", "clockwise", "-", "-1"}
CCW_WORDS = {"ccw", "g03", "g3", "counterclockwise", "counter-clockwise", "anticlockwise", "+", "+1", "1"}


def _find(header_lower, names):
    for n in names:
        if n in header_lower:
            return header_lower.index(n)
    return None


def _angle_unit_from_header(name: str) -> str | None:
    n = name.lower()
    if "rad" in n:
        return "rad"
    if "deg" in n or "°" in n:
        return "deg"
    return None


@dataclass
class CircularRuns:
    """The runs read from one file: a list of (label, (N, 2) points in mm, in the file's order)."""

    runs: list
    source: str
    kind: str          # 'xy' or 'polar'
    unit: str
    notes: list = field(default_factory=list)


def read_runs(path, *, columns=None, plane=None, unit: str = "mm", skip_rows: int = 0, angle_unit: str | None = None,
              nominal_radius: float | None = None, nominal_center=(0.0, 0.0)) -> CircularRuns:
    """One circular-test file: x, y columns (any two: ``columns`` or ``plane``), or angle + radial
    deviation (header names such as ``angle [deg]`` and ``deviation [µm]``; converted to x, y about
    ``nominal_center`` with ``nominal_radius``, both in mm), holding one run or both directions (a
    ``direction`` or ``run`` column; rows of each run in the order measured).

    The angle + deviation layout follows what ballbar software lists as its data (sample angle and
    radial deviation per point, e.g. the Renishaw Ballbar 20 "data" view and its text export); we found
    no public specification of those exports, so the column names accepted are ours (confidence: low
    for byte-for-byte compatibility, high for the content)."""
    layout = sniff(path, skip_rows)
    name = layout.name
    lowered = [h.strip().lower() for h in layout.header] if layout.header else []
    a_col = _find(lowered, ANGLE_NAMES) if lowered else None
    d_col = _find(lowered, DEVIATION_NAMES) if lowered else None
    r_col = _find(lowered, DIRECTION_NAMES) if lowered else None
    polar = a_col is not None and d_col is not None and columns is None and plane is None
    if polar:
        idx = [a_col, d_col]
        au = angle_unit or _angle_unit_from_header(layout.header[a_col])
        if au is None:
            raise DataFileError(f"{name}: is the angle column {layout.header[a_col]!r} in degrees or radians? "
                                "name it 'angle [deg]' / 'angle [rad]' or give --angle-unit deg|rad")
        if au not in ("deg", "rad"):
            raise DataFileError(f"--angle-unit must be deg or rad, got {au!r}")
        if nominal_radius is None:
            raise DataFileError(f"{name}: an angle + radial-deviation file needs --nominal-radius to place the points")
    else:
        if r_col is not None:
            # x, y + direction: find the coordinate columns among the others
            if plane is not None:
                cols_xy = PLANES.get(plane.lower())
                if cols_xy is None:
                    raise DataFileError(f"unknown plane {plane!r}; use one of {', '.join(PLANES)}")
                idx = layout.index(cols_xy)
            elif columns is not None:
                idx = layout.index(columns)
            else:
                idx = layout.index(("x", "y")) if "x" in lowered and "y" in lowered else \
                    [k for k in range(layout.ncol) if k != r_col][:2]
        else:
            pts = read_points(path, columns if columns is not None else ("x", "y"), plane=plane, unit=unit,
                              skip_rows=skip_rows)
            return CircularRuns([("file", pts)], name, "xy", canonical(unit))
    strings = (r_col,) if r_col is not None else ()
    cols = read_columns(layout, idx, skip_rows=skip_rows, strings=strings)
    f = to_mm(1.0, unit)
    if polar:
        ang = cols[idx[0]] if au == "rad" else np.radians(cols[idx[0]])
        r = float(nominal_radius) + cols[idx[1]] * f
        cx, cy = (float(v) for v in nominal_center)
        pts = np.column_stack([cx + r * np.cos(ang), cy + r * np.sin(ang)])
    else:
        pts = np.column_stack([cols[idx[0]] * f, cols[idx[1]] * f])
    if r_col is None:
        return CircularRuns([("file", pts)], name, "polar" if polar else "xy", canonical(unit))
    labels = pd.Series(cols[r_col]).astype(str).str.strip()
    runs = []
    for lab in pd.unique(labels):
        mask = (labels == lab).to_numpy()
        low = lab.lower()
        tag = "cw" if low in CW_WORDS else "ccw" if low in CCW_WORDS else lab
        runs.append((tag, pts[mask]))
    if len(runs) > 2:
        raise DataFileError(f"{name}: {len(runs)} runs in the direction/run column ({', '.join(l for l, _ in runs)}); "
                            "a circular test has two (CW and CCW)")
    return CircularRuns(runs, name, "polar" if polar else "xy", canonical(unit),
                        notes=[f"{len(runs)} run(s) read from the column {layout.header[r_col]!r}"])
