"""ISO 230-2 positioning tables (:func:`read_positioning`) as
:class:`methods.positioning.PositioningData` in mm: the long layout (target, direction, run, deviation or actual,
as ISO 230-2's own data tables) and the wide exports of laser-interferometer software (one column per run and
direction beside the targets, as Renishaw LaserXL/CARTO tabular exports show it: ``Run 1 +``, ``run1_up``,
``Lauf 2``, ``Run 1 Forward``/``Reverse`` in the run order, :func:`_wide_to_long`); units from the header, else
``--unit`` and ``--deviation-unit``."""
from __future__ import annotations

import re
import warnings

import numpy as np

from datasets.io._pandas import pd
from datasets.io.headers import (ANGLE_UNITS, CONVERT, LENGTH_UNITS, mixed_units, parse_name, unit_refusal,
                                 unit_words)
from datasets.io.layout import preamble_hint
from datasets.io.numbers import DataFileError, NumberFormatError
from datasets.io.tables import _numeric_column, read_table
from methods import InvalidInputError
from methods.units import canonical


TARGET_NAMES = ("target", "position", "target position", "target [mm]", "target (mm)", "target position (mm)",
                "target position [mm]", "position [mm]", "position (mm)", "nominal", "nominal position", "commanded",
                "commanded position", "soll", "sollposition", "ziel", "zielposition")
#: other names of the long table's columns in real exports (matched like every header name, :func:`parse_name`:
#: case, spaces and the unit ignored): ``Actual position [mm]``, ``Error (µm)`` (laser software's word), ``Dir``
ROLE_NAMES = {"actual": ("actual", "actual position", "measured position", "measured", "ist", "istposition"),
              "deviation": ("deviation", "error", "positional deviation", "position error", "positioning error",
                            "abweichung", "fehler"),
              "direction": ("direction", "dir", "richtung"),
              "run": ("run", "run no", "run number", "lauf")}
#: the roles of a long table's columns ``read_positioning(columns=...)`` (``--column ROLE=COLUMN``) may assign
COLUMN_ROLES = ("target", "direction", "run", "actual", "deviation")
ROLE_WORDS = {"target": "the target positions", "direction": "the approach directions", "run": "the run numbers",
              "actual": "the actual (measured) positions", "deviation": "the positioning deviations"}
#: the unit words a run column may give after 'in' (DIN 1313: ``Run 1 + in µm``; any other word is no unit)
_IN_UNITS = "|".join(sorted({re.escape(w) for u in unit_words() for w in (u, u.replace("µ", "μ"))}, key=len,
                            reverse=True))
RUN_COLUMN = re.compile(r"^\s*(?:run|lauf|messung|r)?\s*[_#.]?\s*(\d+)\s*[_\s(\[]*"
                  r"(\+|-|up|down|dn|u|d|increasing|decreasing|inc|dec|positive|negative|pos|neg|↑|↓|fwd|rev|bwd|"
                  r"forward|reverse|backward|return|hin|rückwärts|rueckwaerts|vorwärts|vorwaerts|rück|rueck|zurück|"
                  r"zurueck)?\s*[)\]]?\s*(?:\[.*\]|\(.*\)|/\s*[^/\s]+|in\s+(?:" + _IN_UNITS + r"))?\s*$",
                  re.IGNORECASE)


#: header names (their :func:`parse_name` key) of a wide export's point-number column (``Point``, ``Target No.``,
#: ``Target number``, ``Nr.``): laser software numbers its targets beside them; not read when it counts them
POINT_NUMBER_KEYS = frozenset({
    "point", "pointno", "pointnr", "pointnumber", "pointindex", "pt", "ptno", "targetno", "targetnr", "targetnumber",
    "targetindex", "positionno", "positionnr", "positionnumber", "posno", "posnr", "no", "nr", "number", "index",
    "idx", "#", "punkt", "punktnr", "messpunkt", "zielpunkt", "zielnr", "step"})
#: units of the environment columns an export writes beside the runs (temperature, pressure, humidity): not lengths
ENVIRONMENT_UNITS = frozenset({"°c", "°f", "degc", "degf", "k", "pa", "hpa", "kpa", "mbar", "bar", "mmhg", "inhg",
                               "psi", "torr", "%", "%rh", "% rh", "rh", "% r.h.", "%r.h."})
#: words in a column's name (its :func:`parse_name` key) that say it holds an environment reading, not a run
ENVIRONMENT_WORDS = ("temp", "pressure", "humid", "druck", "feuchte")

#: run columns without directions whose odd and even runs differ by more than this Welch t-test on the runs' means
#: over the targets allows (two-sided p) are two approach directions, not one
ALTERNATING_P = 1e-3
#: ``run_directions``: the approach direction of every run, or of the odd and the even runs (ISO 230-2 ↑ = +)
RUN_DIRECTIONS = {"up": "+", "down": "-", "up,down": "+-", "down,up": "-+"}


class ColumnNote(UserWarning):
    """Which column the reader took for a role (``--column``), and which columns it did not read: printed as a
    note by ``fitbench positioning``."""


def _header_names(columns) -> list[str]:
    """The header's names as written: pandas renames a repeated name ``X`` to ``X.1``, ``X.2``, ... and names a
    header cell left empty ``Unnamed: N`` (N its 0-based position): that is '' here, as the file writes it
    (messages name such a column by its position, :func:`_column_words`)."""
    names = [str(c) for c in columns]
    out = []
    for k, c in enumerate(names):
        m = re.fullmatch(r"(.*)\.(\d+)", c)
        out.append("" if re.fullmatch(r"Unnamed: \d+", c) else m.group(1) if m and m.group(1) in names else c)
    return out


def _spreadsheet_letters(k: int) -> str:
    """The spreadsheet name of the 0-based column ``k``: A, B, ..., Z, AA, AB, ..."""
    out = ""
    k += 1
    while k:
        k, r = divmod(k - 1, 26)
        out = chr(ord("A") + r) + out
    return out


def _column_words(names: list[str], k: int, columns=None) -> str:
    """A column of the user's file for a message: ``column 3 'Run 1 - (µm)'`` or, for a header cell left empty,
    ``column 10 (K in a spreadsheet; no name in the header)``, never pandas' ``Unnamed: 10``. ``columns``: the
    frame's columns when some of the file's were dropped (pandas' name holds the file's position)."""
    if names[k].strip():
        return f"column {k} {names[k]!r}"
    m = re.fullmatch(r"Unnamed: (\d+)", str(columns[k])) if columns is not None else None
    k = int(m.group(1)) if m else k
    return f"column {k} ({_spreadsheet_letters(k)} in a spreadsheet; no name in the header)"


def _column_index(names: list[str], role: str, given, path) -> int:
    """The 0-based index of the column ``given`` for ``role`` (``--column ROLE=COLUMN``): a header name (as written,
    or case, spaces and unit ignored, :func:`parse_name`) or a 0-based number; a name two columns share is refused
    asking for the number."""
    text = str(given).strip()
    low = [n.strip().lower() for n in names]
    if isinstance(given, (int, np.integer)) or (text.isdigit() and text.lower() not in low):
        k = int(text)
        if not 0 <= k < len(names):
            raise DataFileError(f"{path}: --column {role}={text}: there is no column {k} (the file has {len(names)} "
                                "columns, numbered from 0)")
        return k
    hits = [k for k, n in enumerate(low) if n and n == text.lower()]
    if not hits:
        want = parse_name(text)[0]
        hits = [k for k, n in enumerate(names) if parse_name(n)[0] == want]
    if not hits:
        raise DataFileError(f"{path}: --column {role}={text}: no column {text!r} (columns: "
                            f"{', '.join(repr(n) if n.strip() else _column_words(names, k) for k, n in enumerate(names))})")
    if len(hits) > 1:
        raise DataFileError(f"{path}: --column {role}={text}: columns {' and '.join(map(str, hits))} (numbered from 0) "
                            f"are both named {names[hits[0]]!r}: give --column {role}={hits[0]} or "
                            f"--column {role}={hits[1]}")
    return hits[0]


def _role_name(name: str) -> str | None:
    """The role a positioning table's column ``name`` names (:data:`TARGET_NAMES`, :data:`ROLE_NAMES`), or None."""
    key = parse_name(name)[0]
    role = next((r for r, names in ROLE_NAMES.items() if key in {parse_name(n)[0] for n in names}), None)
    return role or ("target" if key in {parse_name(n)[0] for n in TARGET_NAMES} else None)


def _assign_roles(names: list[str], path, columns: dict | None) -> tuple[dict[int, str], list[str]]:
    """{column index: role} of a positioning table's header ``names`` and the notes on the choice: each role
    (target, direction, run, actual, deviation) goes to the column ``columns`` names for it, else to the one column
    whose name is one of the role's (:data:`TARGET_NAMES`, :data:`ROLE_NAMES`). Two columns with a name for one
    role (``Error (µm)`` and ``Deviation (µm)``: a straightness channel beside the linear one, a repeated name under a
    two-row group header) are refused naming both: fitbench does not guess which one holds the positioning
    deviations."""
    candidates: dict[str, list[int]] = {}
    for k, n in enumerate(names):
        role = _role_name(n)
        if role is not None:
            candidates.setdefault(role, []).append(k)
    chosen: dict[str, int] = {}
    for role, given in (columns or {}).items():
        if role not in COLUMN_ROLES:
            raise InvalidInputError(f"--column {role}={given}: unknown role {role!r}; use one of "
                                    f"{', '.join(COLUMN_ROLES)} (e.g. --column \"deviation=Deviation (µm)\")")
        k = _column_index(names, role, given, path)
        other = next((r for r, j in chosen.items() if j == k), None)
        if other is not None:
            raise DataFileError(f"{path}: --column gives column {names[k]!r} for both {other} and {role}: "
                                "name one column for each")
        chosen[role] = k
    for role, k in chosen.items():
        named = _role_name(names[k])
        if named is not None and named != role and named not in chosen:
            raise DataFileError(f"{path}: --column {role}={columns[role]} names {names[k]!r}, the {named} column: give "
                                f"the {role} column (its header name or 0-based number)")
    roles, notes = {k: role for role, k in chosen.items()}, []
    for role, k in chosen.items():
        rest = [j for j in candidates.get(role, ()) if j not in roles]
        notes.append(f"{ROLE_WORDS[role]} read from {_column_words(names, k)}, as --column {role}={columns[role]} says"
                     + (f"; not read: {', '.join(f'column {j} {names[j]!r}' for j in rest)}" if rest else ""))
    for role, ks in candidates.items():
        rest = [k for k in ks if k not in roles]
        if role in chosen:
            continue
        if len(rest) > 1:
            same = len({names[k].strip().lower() for k in rest}) == 1
            which = (f"columns {' and '.join(map(str, rest[:2]))} (numbered from 0) are both named {names[rest[0]]!r}"
                     if same else f"the columns {' and '.join(repr(names[k]) for k in rest[:2])} both have a name of "
                     f"the {role} column")
            how = (f"--column {role}={rest[0]} or --column {role}={rest[1]}" if same else
                   f"--column \"{role}={names[rest[0]]}\" or --column \"{role}={names[rest[1]]}\"")
            raise DataFileError(f"{path}: {which}{f' (and {len(rest) - 2} more)' if len(rest) > 2 else ''}; fitbench "
                                f"does not guess which one holds {ROLE_WORDS[role]} (the other may be another channel, "
                                f"e.g. straightness): give {how}, or delete or rename the other column")
        if rest:
            roles[rest[0]] = role
    return roles, notes


def alternating_runs(values: np.ndarray) -> tuple[float, float, float] | None:
    """(mean odd - even difference, Welch t, two-sided p) of the runs' means over the targets, ``values`` (targets,
    runs) in run order: a bidirectional test exported without direction labels alternates its two directions
    (odd runs one way, even runs the other), whose means differ by the reversal value B at every target. Run means
    (not single deviations) carry the run-to-run drift into the test's scatter, so a drifting unidirectional test
    does not pass for two directions. None with fewer than two runs in a group."""
    if values.shape[1] < 4:
        return None
    from scipy import stats
    run_means = values.mean(axis=0)
    odd, even = run_means[0::2], run_means[1::2]
    t, p = stats.ttest_ind(odd, even, equal_var=False)
    return float(odd.mean() - even.mean()), float(t), float(p)


def _not_a_run(df: pd.DataFrame, k: int, name: str, t: int, d_col: int | None = None) -> str | None:
    """Why the wide export's column ``k`` (header ``name``, not a run's) is clearly not a run, or None: a point
    number (:data:`POINT_NUMBER_KEYS`, no unit) whose values count the targets (column ``t``): 1, 2, ..., n or 0, 1,
    ..., n-1 (either way) over the rows, over the distinct targets with one number per target, or over each
    direction's rows (a direction column ``d_col`` lists each target twice); or an environment reading (an :data:`ENVIRONMENT_UNITS` unit, or an :data:`ENVIRONMENT_WORDS` name without a
    length or angle unit). A point-number name over other values is refused: the column may hold something else."""
    from datasets.io.numbers import NUMBER
    key, unit = parse_name(name)
    if unit is not None and unit.replace(" ", "") in {u.replace(" ", "") for u in ENVIRONMENT_UNITS}:
        return "environment"
    if unit is None or (unit not in LENGTH_UNITS.values() and unit not in ANGLE_UNITS.values()
                        and unit not in CONVERT["angle"]):
        if any(w in key for w in ENVIRONMENT_WORDS):
            return "environment"
    if key in POINT_NUMBER_KEYS and unit is None:
        cells = df.iloc[:, k].fillna("").astype(str).str.strip()
        targets = df.iloc[:, t].fillna("").astype(str).str.strip()
        n_targets = targets.nunique()
        if cells.map(lambda v: NUMBER.fullmatch(v) is not None).all():
            values = cells.astype(float).to_numpy()
            pairs = pd.DataFrame({"p": values, "t": targets.to_numpy()})
            one_to_one = (pairs.groupby("p")["t"].nunique() == 1).all() and (pairs.groupby("t")["p"].nunique() == 1).all()
            groups = [values, pd.unique(values) if one_to_one else None]
            if d_col is not None:
                way = df.iloc[:, d_col].fillna("").astype(str).str.strip().to_numpy()
                groups += [values[way == w] for w in pd.unique(way)]

            def counts(v) -> bool:
                return v is not None and v.size > 0 and any(
                    np.array_equal(v, c) or np.array_equal(v, c[::-1]) for c in (np.arange(v.size), 1 + np.arange(v.size)))
            if counts(groups[0]) or counts(groups[1]) or (len(groups) > 2 and all(counts(g) for g in groups[2:])):
                return "point numbers"
        shown = ", ".join(cells.iloc[:4]) + (", ..." if len(cells) > 4 else "")
        raise DataFileError(f"{name!r} has a point number's name, but its values ({shown}) do not count the "
                            f"{n_targets} targets (1, 2, ..., {n_targets} or from 0): delete the column if it holds "
                            "no deviations, or name it as a run ('Run 3 + (µm)') if it does")
    return None


def _wide_to_long(df: pd.DataFrame, name: str, lines, run_directions: str | None = None, to_um: float = 1e3,
                  notes: list | None = None) -> tuple[pd.DataFrame, np.ndarray, bool] | None:
    """A wide export (one column per run) as the long table and whether the file gave the directions; None when
    ``df`` is not wide. Columns that are clearly not runs (:func:`_not_a_run`: a point-number column counting the
    targets, temperature, pressure or humidity) are not read, and ``notes`` names them (``not read: column 0
    'Point'``); any other column that is not a run's is refused, since it may be a run whose name has a typo. Run columns without any direction are read by ``run_directions`` ('+', '-', or '+-' / '-+':
    odd runs in the first direction, even runs in the other), else as one direction that is not given, unless the
    odd and even runs differ as two directions do (:func:`alternating_runs`): that is refused naming the option.
    ``to_um``: µm per unit of the deviations (for the message)."""
    pattern = RUN_DIRECTIONS.get(run_directions, run_directions)
    cols = [c.strip() for c in _header_names(df.columns)]     # as the header writes them (not pandas' 'X.1')
    low = [c.lower() for c in cols]
    t = next((low.index(n) for n in TARGET_NAMES if n in low), None)
    if t is None or "run" in low or "deviation" in low or "actual" in low:   # a long table (with or without runs)
        return None
    d_col = low.index("direction") if "direction" in low else None
    runs, seen, skipped = {}, {}, []
    for k, c in enumerate(cols):
        if k in (t, d_col):
            continue
        if not c:
            raise DataFileError(f"{name}: {_column_words(cols, k, df.columns)} holds values: name it in the header as the other run "
                                "columns are named ('Run N +' or 'Run N -' and the unit, e.g. 'Run 5 - (µm)'), or "
                                "delete the column")
        if c in seen:
            raise DataFileError(f"{name}: the column {c!r} appears twice (columns {seen[c]} and {k}, numbered from 0): "
                                "rename the one that is another run, or delete it")
        seen[c] = k
        m = RUN_COLUMN.match(c)
        if not m:
            try:
                why = _not_a_run(df, k, c, t, d_col)
            except DataFileError as exc:
                raise DataFileError(f"{name}: column {k} {exc}") from None
            if why is not None:
                skipped.append(k)
                continue
            raise DataFileError(f"{name}: column {c!r} is neither the target, a direction nor a run "
                                "(wide layout: target, run 1 +, run 1 -, ... or target, direction, run 1, run 2, ...; "
                                "the words read after a run's number: +/-, up/down (dn), ↑/↓, pos/neg, "
                                "increasing/decreasing as the axis direction, forward/reverse (fwd/rev/bwd, backward, "
                                "return, hin/rück/zurück, vorwärts/rückwärts) as the run order): name it as a run "
                                "('Run 3 + (µm)') if it holds a run's deviations, else delete the column (a point "
                                "number counting the targets and temperature, pressure or humidity columns are not "
                                "read)")
        runs[k] = (int(m.group(1)), m.group(2))
    if not runs:
        return None
    if skipped and notes is not None:
        notes.append(f"not read: {', '.join(_column_words(cols, k, df.columns) for k in skipped)}")
    # 'Forward'/'Reverse' ('Hin'/'Rück') are the laser software's run order, not the axis direction (ISO 230-2: ↑ is
    # an approach in the + direction): the forward runs pass the targets in the order the file lists them
    from methods.positioning.data import RUN_ORDER_TAGS, UP, RunOrderNote
    order = {k: RUN_ORDER_TAGS[tag.lower()] for k, (_, tag) in runs.items() if tag and tag.lower() in RUN_ORDER_TAGS}
    forward = None
    if order and d_col is None:
        targets = _numeric_column(df.iloc[:, t], "target", name, lines)
        step = np.diff(targets)
        forward = "+" if step.size and np.all(step > 0) else "-" if step.size and np.all(step < 0) else None
        named = "/".join(repr(cols[next(k for k, v in order.items() if v == w)]) for w in ("forward", "reverse")
                         if w in order.values())
        if forward is None:
            text = (f"{name}: columns {named} ... name the run order (the laser software's forward and reverse runs), "
                    "not the axis direction, and the targets are neither increasing nor decreasing in the file, so "
                    "which way the forward runs moved is unknown: give --forward-direction + or - (or name the "
                    "directions in the headers: Run 1 +, Run 1 -)")
        else:
            text = (f"columns {named} ... name the run order, not the axis direction; the targets are listed "
                    f"{'increasing' if forward == '+' else 'decreasing'} ({targets[0] + 0.0:g} to {targets[-1] + 0.0:g} in the file's "
                    f"unit), so the forward runs are read as approaches in the {'+ (↑)' if forward == '+' else '− (↓)'} direction and "
                    f"the reverse runs as {'− (↓)' if forward == '+' else '+ (↑)'} (--forward-direction "
                    f"{'-' if forward == '+' else '+'} if the forward runs moved the other way)")
        warnings.warn(RunOrderNote(text, forward), stacklevel=4)
    other = {"+": "-", "-": "+"}
    unlabelled = d_col is None and all(tag is None for _, tag in runs.values())
    if run_directions is not None and not unlabelled:
        raise DataFileError(f"{name}: --run-directions is for run columns without directions; this file names its "
                            "directions (in the column names or a direction column): drop the option")
    given = not unlabelled or run_directions is not None
    if unlabelled and run_directions is None:
        order_k = sorted(runs, key=lambda k: runs[k][0])
        values = np.column_stack([_numeric_column(df.iloc[:, k], cols[k], name, lines) for k in order_k])
        alt = alternating_runs(values)
        if alt is not None and alt[2] < ALTERNATING_P:
            raise DataFileError(
                f"{name}: the {len(runs)} run columns name no approach direction, and the odd runs differ from the "
                f"even runs by {alt[0] * to_um:+.3g} µm on average (Welch t = {alt[1]:.3g} over the runs' means, "
                f"p = {alt[2]:.2g}), as the two directions of a bidirectional test do: give --run-directions up,down "
                "(odd runs approached in +, even runs in -) or down,up, or --run-directions up / down if all runs "
                "approached one way (or name the columns Run N + / Run N -)")
    seq = {k: i for i, k in enumerate(sorted(runs, key=lambda k: runs[k][0]))}
    rows = []
    for k, (run, tag) in runs.items():
        if d_col is not None:
            if tag:
                raise DataFileError(f"{name}: column {cols[k]!r} names a direction and the file has a direction column")
            direction = df.iloc[:, d_col].to_numpy()
        elif k in order:
            # ambiguous order: + provisionally, the note says so (fitbench positioning refuses it without
            # --forward-direction)
            fwd = forward or "+"
            direction = np.full(len(df), fwd if order[k] == "forward" else other[fwd])
        elif unlabelled:
            # no direction anywhere: as --run-directions says (odd/even runs in the order of their numbers), else one
            # direction, not given (held as '+', labelled 'direction not given')
            signs = pattern or "+"
            direction = np.full(len(df), signs[seq[k] % len(signs)])
        else:
            direction = np.full(len(df), "+" if tag is None or tag.lower() in UP else "-")
        rows.append(pd.DataFrame({"target": df.iloc[:, t].to_numpy(), "direction": direction, "run": run,
                                  "deviation": df.iloc[:, k].to_numpy(), "_line": lines}))
    long = pd.concat(rows, ignore_index=True)
    return long.drop(columns="_line"), long["_line"].to_numpy(), given



def preamble_axis(path, skip_rows: int) -> tuple[str, int, str] | None:
    """(axis name, line number, the line) of a preamble line ``Axis;Z`` (``Axis: Z``, ``Achse<TAB>Z``) among the
    ``skip_rows`` lines above the table, as laser software writes the test's identity there; None if there is none."""
    if skip_rows <= 0:
        return None
    from itertools import islice
    from datasets.io.textfile import _open_text, iter_lines
    name = str(path)
    with _open_text(name, "", skip_rows) as fh:
        for lineno, line in islice(iter_lines(fh, name), skip_rows):
            m = re.fullmatch(r"\s*(?:axis|achse|axe|asse)\s*(?:name)?\s*[;:,\t=]\s*\"?([^;,\t\"]+?)\"?\s*[;,\t]*\s*",
                             line.lstrip("\ufeff").rstrip("\r\n"), re.IGNORECASE)
            if m:
                return m.group(1), lineno, line.strip().lstrip("\ufeff")
    return None


def _header_unit(found: dict, given: str | None, option: str, name) -> str | None:
    """The one unit the header gives columns ``found`` ({column: unit}), checked against the option's value."""
    units = set(found.values())
    if len(units) > 1:
        if units <= set(LENGTH_UNITS.values()):
            raise mixed_units(name, found)
        raise DataFileError(f"{name}: the columns {', '.join(found)} are in different units "
                            f"({', '.join(sorted(units))}); convert them to one unit")
    header = units.pop() if units else None
    if header is not None and (header in ANGLE_UNITS.values() or header in CONVERT["angle"]):
        col = next(iter(found))
        what = ("targets in an angle unit: a rotary axis" if option == "--unit" else
                "deviations in an angle unit: a rotary axis, or the pitch or yaw of a linear one")
        raise DataFileError(f"{name}: column {col!r} holds {what}; rotary axes and angular deviations are not "
                            "supported: fitbench evaluates the positioning of linear axes (ISO 230-2, targets and "
                            "deviations in nm, µm, mm, m or in)")
    if header is not None and header not in LENGTH_UNITS.values():
        raise unit_refusal(name, next(iter(found)), header)
    if header is not None and given is not None and canonical(given) != header:
        raise DataFileError(f"{name}: the header says column {next(iter(found))!r} is in {header} but {option} says "
                            f"{canonical(given)}; drop {option} or correct the header")
    return header or (canonical(given) if given is not None else None)


def read_positioning(path, *, unit: str | None = None, deviation_unit: str | None = None, skip_rows: int = 0,
                     with_units: bool = False, run_directions: str | None = None, columns: dict | None = None):
    """An ISO 230-2 positioning file, long or wide layout (:mod:`methods.positioning.data` describes them), as
    :class:`methods.positioning.PositioningData`. Header names are read like every reader's (:func:`parse_name`:
    ``Target (mm)``, ``Deviation [µm]``, ``Run 1 + (um)``); lengths are converted to mm from the header's units,
    else ``unit`` (targets, actual positions; default mm) and ``deviation_unit`` (deviations; default the
    targets' unit); a header unit contradicting them is an error. ``with_units``: also return the two units, the
    deviations' None when a deviation column's unit is stated neither in the header nor by ``deviation_unit`` (it
    is then read in ``unit``: a guess no controller table may be written from).
    ``run_directions`` ('up', 'down', 'up,down', 'down,up'): the approach directions of run columns that name none
    (odd runs first); without it such runs are one direction, not given, or refused when they alternate (:func:`_wide_to_long`).
    ``columns`` ({role: header name or 0-based number}, roles :data:`COLUMN_ROLES`): the column to read for a role,
    needed when two columns have a name for it (:func:`_assign_roles`); which was read is said as a
    :class:`ColumnNote` warning."""
    if run_directions is not None and run_directions not in RUN_DIRECTIONS:
        raise InvalidInputError(f"--run-directions {run_directions!r}: use one of {', '.join(RUN_DIRECTIONS)}")
    try:
        return _read_positioning(path, unit=unit, deviation_unit=deviation_unit, skip_rows=skip_rows,
                                 with_units=with_units, run_directions=run_directions, columns=columns)
    except InvalidInputError as exc:
        _add_preamble_hint(exc, path, skip_rows)
        raise


def _add_preamble_hint(exc: InvalidInputError, path, skip_rows: int) -> None:
    """Append :func:`preamble_hint` to the message of ``exc`` (a file read without --skip-rows whose data
    rows start below a preamble: its first line was taken as the header)."""
    if skip_rows == 0 and len(exc.args) == 1 and "--skip-rows" not in str(exc.args[0]) and \
            not isinstance(exc, NumberFormatError) and not getattr(exc, "no_preamble_hint", False):
        hint = preamble_hint(path)
        if hint:
            exc.args = (f"{exc.args[0]}{hint}",)


def _spaced_names(df, lines, path, skip_rows: int):
    """A table aligned with spaces whose header names contain spaces (``Target (mm)    Run 1 + (µm) ...``) splits
    its header into more fields than its rows have: the header is split again at runs of two or more spaces (or
    tabs), and taken when that gives exactly the rows' field count; otherwise it is refused in one line saying so
    (it was 'line 2: missing field(s); if line 1 is an instrument's preamble, give --skip-rows 1')."""
    filled = ~(df.isna() | df.apply(lambda c: c.astype(str).str.strip() == "")).to_numpy()
    if not len(df) or filled.all():
        return df
    counts = filled.sum(axis=1)
    m = int(counts[0])
    n = len(counts) if np.all(counts == m) else int(np.argmin(counts == m))  # the table's rows: those before the
    if n < len(counts) and (2 * n < len(counts) or not np.all(counts[n:] < m)):  # first of another length, shorter
        return df                                                 # ones below them (a trailer), not longer (a preamble)
    if not (filled[:n, :m].all() and m < df.shape[1]):
        return df
    from datasets.io.delimiters import COMMENT_PREFIXES
    from datasets.io.textfile import read_lines
    text = read_lines(path, "", skip_rows)
    k = next((i for i in range(skip_rows, lines[0] - 1) if text[i].strip()
              and not text[i].lstrip().startswith(COMMENT_PREFIXES)), None)
    if k is None or re.search(r"[,;|\t]", text[k].strip()):        # not a table separated by spaces
        return df
    names = re.split(r"\t|\s{2,}", text[k].strip())
    if len(names) == len(text[k].split()):          # no name with a space in it: not this case
        return df
    if len(names) != m:
        err = DataFileError(f"{path} line {k + 1}: the header splits at spaces into {df.shape[1]} names but the rows "
                            f"have {m} fields: its names contain spaces; separate the columns with tabs or ';', or "
                            "use names without spaces")
        err.no_preamble_hint = True
        raise err
    out = df.iloc[:, :m].copy()
    out.columns = names
    return out


def _trailer(df, lines, empty, path, skip_rows: int = 0):
    """The table without the lines laser software writes after it (``Environment compensation: automatic``, ``End
    of data``): rows from the first incomplete one on are dropped, with a warning naming them, when a blank line
    separates them from the table and none of them is a complete row; otherwise the first incomplete row is refused
    in one line quoting it and saying what to do."""
    from datasets.io.numbers import NUMBER
    from datasets.io.textfile import read_lines
    k = int(np.flatnonzero(empty)[0])
    first = df.iloc[:, 0].fillna("").astype(str).str.strip()
    if first.iloc[k] and NUMBER.fullmatch(first.iloc[k]):           # a data row with a field missing
        names, row = _header_names(df.columns), df.iloc[k]
        shown = [repr(n) if n.strip() else _column_words(names, j) for j, n in enumerate(names)]
        blank = [shown[j] for j in range(df.shape[1]) if isinstance(row.iloc[j], str) and not row.iloc[j].strip()]
        short = [shown[j] for j in range(df.shape[1]) if not isinstance(row.iloc[j], str)]   # the line ends early
        if blank:
            raise DataFileError(f"{path} line {lines[k]}: missing field(s): {' and '.join(blank[:2])}"
                                f"{f' (and {len(blank) - 2} more)' if len(blank) > 2 else ''} "
                                f"{'is' if len(blank) == 1 else 'are'} empty: fill in the value, or delete the line "
                                "(or the column)")
        raise DataFileError(f"{path} line {lines[k]}: missing field(s): {df.shape[1] - len(short)} where the header "
                            f"has {df.shape[1]} (no {', '.join(short[:2])}"
                            f"{', ...' if len(short) > 2 else ''})")
    text = read_lines(path, "", skip_rows)
    quoted = text[lines[k] - 1].strip()[:60]
    after_blank = k > 0 and any(not text[i].strip() for i in range(lines[k - 1], lines[k] - 1))
    numeric = first.iloc[k:].map(lambda v: bool(v) and NUMBER.fullmatch(v) is not None).to_numpy(dtype=bool)
    if after_blank and empty[k:].all() and not numeric.any():
        shown = ", ".join(repr(text[n - 1].strip()[:40]) for n in lines[k:k + 3]) + (", ..." if len(lines) - k > 3 else "")
        where = (f"line {lines[k]} after the blank line below the table is not a data row and was" if lines[k] == lines[-1]
                 else f"lines {lines[k]}-{lines[-1]} after the blank line below the table are not data rows and were")
        warnings.warn(f"{path}: {where} not read ({shown})", UserWarning, stacklevel=4)
        return df.iloc[:k].reset_index(drop=True), list(lines[:k])
    raise DataFileError(f"{path} line {lines[k]}: {quoted!r} is not a data row (fields missing): delete the lines "
                        "after the table, or prefix them with #")


#: the first cell of a row of statistics an export writes below the table (``Mean;0.1;...``, ``Max``, ``Sigma``)
STATISTICS_ROW = re.compile(r"(mean|average|avg|max|maximum|min|minimum|sum|total|std|stdev|stddev|std\.?\s*dev|"
                            r"standard deviation|sigma|σ|range|median|rms|mittelwert|mittel|summe|spannweite|"
                            r"standardabweichung)\b.*", re.IGNORECASE)


def _second_table_or_totals(df, names: list[str], lines, path, skip_rows: int) -> None:
    """Refuse, in its own terms, a row that repeats the header (a second table: another axis or test written below
    the first, usually after a blank line) or a row of statistics (``Mean;0.1;...``: a totals row), each a complete
    row the number check would only call 'not a finite number'; the message says what to do."""
    named = [j for j, n in enumerate(names) if n.strip()]
    if not len(df) or not named:
        return

    def column(j):
        return df.iloc[:, j].fillna("").astype(str).str.strip()
    first = column(0)
    header = (column(named[0]) == names[named[0]].strip()).to_numpy().copy()
    for j in named[1:] if header.any() else ():
        header &= (column(j) == names[j].strip()).to_numpy()
    stats = first.str.fullmatch(STATISTICS_ROW.pattern, case=False).to_numpy(dtype=bool)
    hit = np.flatnonzero(header | stats)
    if not hit.size:
        return
    from datasets.io.textfile import read_lines
    k = int(hit[0])
    text = read_lines(path, "", skip_rows)
    quoted = text[lines[k] - 1].strip()
    quoted = quoted if len(quoted) <= 60 else quoted[:57] + "..."
    if header[k]:
        blank = k > 0 and any(not text[i].strip() for i in range(lines[k - 1], lines[k] - 1))
        raise DataFileError(f"{path} line {lines[k]}: {quoted!r} repeats the header: a second table"
                            f"{' after a blank line' if blank else ''} (lines {lines[k]}-{lines[-1]}; another axis or "
                            "test?); fitbench reads one table per file: put each table in a file of its own, or delete "
                            f"the lines from {lines[k]} on (or prefix them with #)")
    raise DataFileError(f"{path} line {lines[k]}: {quoted!r} is a row of statistics ({first.iloc[k]!r}), not a "
                        "target's row: fitbench computes the figures from the runs; delete the line (and any others "
                        "below the table), or prefix it with #")


def _trailing_separators(df, lines, path):
    """The table without the empty last column a separator after the last field of every line, header included,
    gives (Excel's ``;`` at the end of each line when the sheet has an empty column to the right; ``; `` with a
    space after it): an unnamed (or blank-named) last column whose every cell is empty. Rows that all have one field more than the header (pandas then takes their
    first field for the row index, shifting every column) are refused in one line saying so."""
    if not (isinstance(df.index, pd.RangeIndex) and df.index.start == 0 and df.index.step == 1):
        n = df.shape[1]
        ends = df.iloc[:, -1].fillna("").astype(str).str.strip().eq("").all()
        raise DataFileError(f"{path}: the header has {n} names but every data line has {n + 1} fields (from line "
                            f"{lines[0]})" + (": each data line ends with a separator and the header does not; delete "
                            "the separators after the last values, or end the header with one too" if ends else
                            ": name every column in the header"))
    while df.shape[1] > 1 and not _header_names(df.columns)[-1].strip() and \
            df.iloc[:, -1].fillna("").astype(str).str.strip().eq("").all():
        df = df.iloc[:, :-1]
    return df


def _target_names() -> str:
    """The names read as the target column, for a message (``Target, Position, Nominal, ...``)."""
    seen = {}
    for n in TARGET_NAMES:
        name = re.sub(r"\s*[(\[].*$", "", n).strip()
        seen.setdefault(parse_name(name)[0], name[:1].upper() + name[1:])
    return ", ".join(seen.values())


def _no_target(path, names: list[str], roles: dict, wide: bool) -> str:
    """The refusal of a table without a target column, in the terms of its layout: a wide export (a column per run,
    no run column) names its first column; a long table its own columns."""
    runs = [n for k, n in enumerate(names) if k not in roles and RUN_COLUMN.match(n)]
    if wide or ("run" not in roles.values() and runs):
        j = next((k for k, n in enumerate(names) if k not in roles and not RUN_COLUMN.match(n)), None)
        first = None if j is None else names[j]
        which = (f"its first column {first!r} is not a name fitbench reads as the target ({_target_names()})"
                 if first else f"its {_column_words(names, j)} is not named as the target ({_target_names()})"
                 if first is not None else f"the columns are all run columns ({runs[0]!r}, ...)")
        how = (f"rename it 'Target (mm)' or give --column \"target={first}\"" if first else
               f"name it 'Target (mm)' or give --column target={j}" if first is not None else
               "add the target column first, named 'Target (mm)'")
        return f"{path}: no target column in this wide export (the targets, then one column per run): {which}; {how}"
    return (f"{path}: no target column (a long table has target, direction, run, and actual or deviation; the target "
            f"column is read under the names {_target_names()}): rename it, or give --column target=NAME")


def _target_jitter(targets: np.ndarray, unit: str) -> str | None:
    """'the targets 0, -0.001, 0.001 mm lie within 0.002 mm of each other' when distinct target values lie closer
    together than 0.1 % of the travel (no ISO 230-2 test spaces its targets so: a machine readout's last digit
    written as the target), else None."""
    values = np.unique(targets[np.isfinite(targets)])
    if values.size < 3:
        return None
    travel = float(values[-1] - values[0])
    close = np.flatnonzero(np.diff(values) < 1e-3 * travel)
    if not close.size:
        return None
    k = int(close[0])
    group = [values[k]]
    while k < values.size - 1 and values[k + 1] - values[k] < 1e-3 * travel:
        group.append(values[k + 1])
        k += 1
    spread = group[-1] - group[0]
    shown = ", ".join(f"{v + 0.0:g}" for v in group[:4]) + (", ..." if len(group) > 4 else "")
    return f"the targets {shown} {canonical(unit)} lie within {spread:.3g} {canonical(unit)} of each other"


#: words in a column's name (its :func:`parse_name` key) that say it holds a position or a positional deviation
POSITION_WORDS = ("deviation", "error", "abweichung", "fehler", "actual", "measured", "position", "target", "soll",
                  "nominal")


def _unread_columns(df, names, roles, unread, path, columns, notes: list) -> None:
    """A long table's numeric columns that no role took: one with a length unit and a position or deviation word in
    its name (``Deviation Z (µm)`` beside ``Deviation (µm)``: another channel of a 6-DoF laser) is refused unless
    ``--column`` chose the columns read, since fitbench does not guess which channel holds the positioning
    deviations; the others (``Straightness Y (µm)``, ``Pitch (µrad)``, ``Temperature (°C)``) are named in a note."""
    from datasets.io.numbers import NUMBER
    taken = set(roles) | {k for k, c in enumerate(df.columns) if c in unread}
    other = []
    for k, n in enumerate(names):
        if k in taken:
            continue
        cells = df.iloc[:, k].fillna("").astype(str).str.strip()
        if len(cells) and cells.map(lambda v: NUMBER.fullmatch(v) is not None).all():
            other.append(k)
    if not other:
        return
    key_unit = {k: parse_name(names[k]) for k in other}
    suspect = [k for k in other if key_unit[k][1] in LENGTH_UNITS.values()
               and any(w in key_unit[k][0] for w in POSITION_WORDS)]
    if suspect and not columns:
        dev = next((j for j, r in roles.items() if r in ("deviation", "actual")), None)
        read = f"besides {names[dev]!r} " if dev is not None else ""
        role = roles.get(dev, "deviation")
        raise DataFileError(f"{path}: {read}the table has the length column(s) "
                            f"{', '.join(repr(names[k]) for k in suspect)}, and fitbench does not guess which one holds "
                            f"the positioning deviations (another channel?): give --column \"{role}=NAME\" naming the "
                            "column to read (or its 0-based number), or delete the others")
    notes.append(f"not read: {', '.join(_column_words(names, k) for k in other)}")


def _equal_row_counts(targets: np.ndarray, directions, path, lines) -> None:
    """A long table without a run column counts its runs by rows: a target with fewer (or more) rows in a direction
    than the other targets is refused in those terms, naming its lines (a point missing or written twice), not as
    the run its missing row would have been numbered (it said 'target 97.3 misses run(s) [5]' for a file without
    runs when the target's 3rd point was missing)."""
    frame = pd.DataFrame({"t": targets, "d": "" if directions is None else directions, "line": lines})
    counts = frame.groupby(["d", "t"], sort=False).size()
    for d in frame["d"].unique():
        sub = counts.loc[d]
        tally = sub.value_counts()
        usual = int(tally[tally == tally.max()].index.max())          # the count most targets have
        odd = sub[sub != usual]
        if not len(odd):
            continue
        t, n = float(odd.index[0]), int(odd.iloc[0])
        where = frame["line"][(frame["t"] == t) & (frame["d"] == d)].tolist()
        shown = ", ".join(map(str, where[:12])) + (", ..." if len(where) > 12 else "")
        way = f" with direction {d!r}" if directions is not None else ""
        raise DataFileError(f"{path}: target {t + 0.0:g} has {n} row{'s' * (n != 1)}{way} (line{'s' * (n != 1)} "
                            f"{shown}) and the other targets {usual}: the table has no run column, so its runs are "
                            f"counted by rows, and a point is {'missing' if n < usual else 'written more than once'} "
                            f"there; {'add it' if n < usual else 'delete the extra row'} (or add a Run column)")


def _long_runs_and_directions(df, path, lines, run_directions, notes: list, to_um: float) -> bool:
    """Complete a long table in place: without a run column (laser software's capture order: target, direction,
    deviation per point, the runs one after the other) the k-th row of each target and direction is run k, said
    in ``notes``; without a direction column the runs are one direction, not given, or as ``run_directions`` says
    (odd and even runs in the order of their numbers), and refused when the odd and even runs differ as two
    directions do (:func:`alternating_runs`), as a wide export's unlabelled run columns are. Returns whether the
    directions were given."""
    cols = {str(c).lower().strip(): c for c in df.columns}
    if "target" not in cols:
        return True
    has_direction = "direction" in cols
    if "run" not in cols:
        targets = _numeric_column(df[cols["target"]], "target", path, lines)
        keys = [targets] + ([df[cols["direction"]].astype(str).str.strip().str.lower().to_numpy()] if has_direction
                            else [])
        df["run"] = pd.DataFrame({f"k{i}": k for i, k in enumerate(keys)}).groupby(
            [f"k{i}" for i in range(len(keys))], sort=False).cumcount().to_numpy() + 1
        _equal_row_counts(targets, keys[1] if has_direction else None, path, lines)
        notes.append(f"the table has no run column: the k-th row of each target{' and direction' * has_direction} "
                     "is read as run k, in the order of the file (as laser software lists the runs one after the "
                     "other)")
        cols["run"] = "run"
    if has_direction:
        return True
    run = _numeric_column(df[cols["run"]], "run", path, lines)
    targets = _numeric_column(df[cols["target"]], "target", path, lines)
    twice = pd.DataFrame({"t": targets, "r": run}).duplicated(keep=False).to_numpy()
    if twice.any():
        first, second = np.flatnonzero(twice & (targets == targets[twice][0]) & (run == run[twice][0]))[:2]
        raise DataFileError(f"{path}: missing column 'direction': target {targets[first] + 0.0:g} has run "
                            f"{run[first]:g} twice (lines {lines[first]} and {lines[second]}), two approach directions? "
                            "name the direction column 'Direction' (+ or - on every row)")
    order = {r: i for i, r in enumerate(np.unique(run))}
    if run_directions is not None:
        pattern = RUN_DIRECTIONS.get(run_directions, run_directions)
        df["direction"] = [pattern[order[r] % len(pattern)] for r in run]
        return True
    dev_col = cols.get("deviation") or cols.get("actual")
    if dev_col is not None:
        values = _numeric_column(df[dev_col], "deviation", path, lines)
        if dev_col == cols.get("actual"):
            values = values - targets
        table = pd.DataFrame({"t": targets, "r": run, "v": values}).pivot_table(index="t", columns="r", values="v")
        alt = alternating_runs(table.to_numpy()) if not table.isna().any().any() else None
        if alt is not None and alt[2] < ALTERNATING_P:
            raise DataFileError(
                f"{path}: the table has no direction column, and its {table.shape[1]} runs' odd runs differ from the "
                f"even runs by {alt[0] * to_um:+.3g} µm on average (Welch t = {alt[1]:.3g} over the runs' means, "
                f"p = {alt[2]:.2g}), as the two directions of a bidirectional test do: give --run-directions up,down "
                "(odd runs approached in +, even runs in -) or down,up, or --run-directions up / down if all runs "
                "approached one way (or add a Direction column with + or - on every row)")
    df["direction"] = "+"            # one direction, not given (labelled so by from_frame's direction_given)
    return False


def _read_positioning(path, *, unit, deviation_unit, skip_rows, with_units, run_directions=None, columns=None):
    from methods.positioning import from_frame

    # 'nan' and 'inf' stay text here and are refused as not finite by _numeric_column, like every reader
    df, lines = read_table(path, skip_rows=skip_rows, keep_default_na=False)
    df = _trailing_separators(df, lines, path)
    df = _spaced_names(df, lines, path, skip_rows)
    empty = (df.isna() | df.apply(lambda c: c.astype(str).str.strip() == "")).any(axis=1).to_numpy()
    if empty.any():
        df, lines = _trailer(df, lines, empty, path, skip_rows)
    lines = np.array(lines)
    names = _header_names(df.columns)
    _second_table_or_totals(df, names, lines, path, skip_rows)
    roles, column_notes = _assign_roles(names, path, columns)
    # columns named for a role that --column gave another column: not read
    unread = [df.columns[k] for k, n in enumerate(names) if k not in roles and _role_name(n) is not None]
    renamed, lengths, deviations = {}, {}, {}
    for k, c in enumerate(df.columns):
        _, u = parse_name(names[k])
        role = roles.get(k)
        if role is not None:
            renamed[c] = role
        if u is not None and role in ("target", "actual"):
            lengths[names[k]] = u
        elif u is not None and (role == "deviation" or (role is None and c not in unread and RUN_COLUMN.match(names[k]))):
            deviations[names[k]] = u
    unit = _header_unit(lengths, unit, "--unit", path) or "mm"
    stated = _header_unit(deviations, deviation_unit, "--deviation-unit", path)
    deviation_unit = stated or unit
    raw, df = df, df.drop(columns=unread).rename(columns=renamed)
    long_only = [r for r in (columns or {}) if r not in ("target", "direction")]
    run_columns = [n for k, n in enumerate(names) if k not in roles and _role_name(n) is None and RUN_COLUMN.match(n)]
    if long_only and run_columns:
        raise DataFileError(f"{path}: --column {long_only[0]}={columns[long_only[0]]} names a column of a long table "
                            f"(target, direction, run, deviation or actual), and this file has run columns "
                            f"({run_columns[0]!r}, ...: a wide export, read without --column): drop the option")
    from methods.units import to_mm
    wide = _wide_to_long(df, str(path), lines, run_directions, to_um=float(to_mm(1.0, deviation_unit)) * 1e3,
                         notes=column_notes)
    given = True
    if wide is not None:
        df, lines, given = wide
    elif run_directions is not None and "direction" in roles.values():
        raise DataFileError(f"{path}: --run-directions is for run columns without directions; this is a long table "
                            "with a direction column: drop the option")
    else:
        given = _long_runs_and_directions(df, path, lines, run_directions, column_notes,
                                          to_um=float(to_mm(1.0, deviation_unit)) * 1e3)
    if wide is None:
        _unread_columns(raw, names, roles, unread, path, columns, column_notes)
    if wide is None and {"actual", "deviation"} <= set(roles.values()) and "actual" not in (columns or {}):
        k = {r: j for j, r in roles.items()}
        column_notes.append(f"the deviations read from column {names[k['deviation']]!r}; the column "
                            f"{names[k['actual']]!r} (actual positions) not read (--column actual=... reads it instead)")
    for note in column_notes:
        warnings.warn(ColumnNote(note), stacklevel=3)
    cols = {str(c).lower().strip(): c for c in df.columns}
    for key in ("target", "run", "deviation", "actual"):
        if key in cols:
            df[cols[key]] = _numeric_column(df[cols[key]], key, path, lines)
    if "target" not in cols:
        raise DataFileError(_no_target(path, names, roles, wide is not None))
    try:
        data = from_frame(df, str(path), lines=lines, unit=unit, deviation_unit=deviation_unit, direction_given=given)
    except InvalidInputError as exc:
        jitter = _target_jitter(df[cols["target"]].to_numpy(dtype=float), unit)
        if jitter is None:
            raise
        reason = str(exc)[len(f"{path}: "):] if str(exc).startswith(f"{path}: ") else str(exc)
        raise DataFileError(f"{path}: {jitter} and are read as different targets ({reason}); if they are one target "
                            "with the machine's readout jitter, round the target column to the targets commanded"
                            ) from None
    # deviations from actual positions are in the positions' unit; a deviation column's unit is stated or not
    stated = stated if "deviation" in cols else unit
    return (data, unit, stated) if with_units else data
