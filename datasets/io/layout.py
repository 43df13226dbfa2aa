"""What the first lines of a delimited file say about it (:func:`sniff` -> :class:`Layout`): separator,
decimal mark, header and units row, comment style, from at most :data:`datasets.io.delimiters.SNIFF_LINES` lines;
and the ``--skip-rows`` advice when an instrument's preamble (test conditions written above the table) stands
above the first row of numbers (:func:`preamble_hint`, :func:`skip_rows_hint`)."""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field

import numpy as np

from datasets.io.delimiters import COMMENT_PREFIXES, SNIFF_LINES, _separator, _split
from datasets.io.headers import _names_above, _units_row, _with_units, parse_name
from datasets.io.numbers import (_COMMA_GROUPED, _COMMA_NUMBER, DataFileError, NumberFormatError, _is_number,
                                 decimal_marks, number_problem)
from datasets.io.textfile import _open_text, iter_lines, note_encoding


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
    sample: list = field(default_factory=list)    # (line number, line) of the first data lines read by sniff
    units_line: int = 0             # 1-based line of a units row under the header (0: none)
    skip_rows: int = 0              # the lines --skip-rows skipped (never refused as markup when read again)

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
                if key in lowered:
                    out.append(lowered.index(key))
                    continue
                keys = [parse_name(h)[0] for h in self.header] if self.header else []
                want = parse_name(str(n))[0]
                if want not in keys:
                    have = ", ".join(self.header) if self.header else "no header"
                    raise DataFileError(f"{self.name}: no column {n!r} (columns: {have}); use --columns")
                out.append(keys.index(want))
        return out

    def preamble_hint(self) -> str:
        """:func:`skip_rows_hint` of this file (for a refusal of its header made where this module is not imported:
        ``datasets.io.headers``, which it imports)."""
        return skip_rows_hint(self)

    def fields(self) -> list[tuple[str, str | None]]:
        """(key, unit) of each header name (:func:`parse_name`); [] without a header."""
        return [parse_name(h) for h in self.header] if self.header else []


def one_column(name, header: str | None) -> str:
    """The refusal of a file of one column of numbers (the radial deviations alone, as roundness and ballbar software
    export them equally spaced over the revolution): each point needs two numbers."""
    what = f" ({header})" if header else ""
    return (f"{name}: one column of numbers{what}: fitbench needs two per point (x, y, or angle + radial deviation); "
            "if they are radial deviations equally spaced over a revolution, add an angle column (i x 360/N deg for "
            "the i-th of N, from 0) and name both, e.g. 'Angle [deg];Deviation [um]'")


def sniff(path, skip_rows: int = 0) -> Layout:
    """Read at most the first ``SNIFF_LINES`` lines: separator, decimal comma, header, comment style."""
    name = os.fspath(path)
    if skip_rows < 0:
        raise DataFileError(f"{name}: --skip-rows must be >= 0, got {skip_rows}")
    fh = _open_text(name, skip_rows=skip_rows)
    note_encoding(name)
    body, preamble, comment = [], [], "#"
    try:
        with fh:
            for lineno, raw in iter_lines(fh, name):
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
    sep, decimal_comma = _separator([ln for _, ln in body])
    head = _split(first, sep)
    numeric = all(_is_number(t.replace(",", ".") if decimal_comma else t) for t in head)
    if not numeric:   # numbers some written as no reader reads them (1 045,9; an en dash): no header, named
        odd = [t for t in head if not _is_number(t.replace(",", ".") if decimal_comma else t)]
        why = [number_problem(t, decimal_comma) for t in odd]
        if all(why):
            raise NumberFormatError(f"{name} line {body[0][0]}: {why[0]}")
    if numeric:
        decimal_comma = _marks(name, body, sep, decimal_comma)
        return Layout(name, sep, decimal_comma, None, 0, body[0][0], len(head), comment, preamble, body,
                      skip_rows=skip_rows)
    if _units_row(head) is not None:
        above = _names_above(skip_rows)
        raise DataFileError(f"{name} line {body[0][0]}: the header {first!r} names units, not columns; put the "
                            f"units into the names (X [µm];Y [µm]){above}")
    if _numeric_fields(first) is not None and len(body) > 1 and _numeric_fields(body[1][1]) is not None:
        # numbers and a label ('CW;1,250;2,2597') above more of them: data where the header should be
        what = ((f"if --skip-rows {skip_rows} skipped the header line, give fewer; else " if skip_rows else "")
                + "add a header line naming the columns (e.g. direction;angle [deg];radial deviation [um])")
        raise DataFileError(f"{name} line {body[0][0]}: {first!r} is a row of data where the header should be; {what}")
    units_line = 0
    if len(body) > 1 and (units := _units_row(_split(body[1][1], sep))) is not None:
        head, units_line = _with_units(name, head, units, body[1][0]), body[1][0]
        body = [body[0]] + body[2:]
    if len(body) < 2:
        raise DataFileError(f"{name}: a header but no data lines")
    widths = {len(_split(ln, sep)) for _, ln in body[1:]}
    named = len(head) - next((k for k, h in enumerate(reversed(head)) if h), len(head))  # 'X;Y;': two names
    if max(widths) < named:           # every row shorter than the header: said before any column is looked up
        if max(widths) == 1 and sep is None and parse_name(first)[1] is not None:
            # one name with its unit ('Deviation [µm]', split at its space) over one column of numbers
            raise DataFileError(one_column(name, repr(first.strip())))
        lineno, ln = body[1]
        k = len(_split(ln, sep))
        hint = preamble_hint(name, body[0][0], skip_rows=skip_rows)
        raise DataFileError(f"{name} line {lineno}: {k} field{'s' if k != 1 else ''} where the header (line "
                            f"{body[0][0]}) has {len(head)}: {ln!r}{hint}")
    if (longer := longer_rows(name, head, named, body, sep, comment, skip_rows)) is not None:
        raise DataFileError(longer)
    decimal_comma = _marks(name, body[1:], sep, decimal_comma)
    return Layout(name, sep, decimal_comma, head, body[0][0], body[1][0], len(head), comment, preamble, body[1:],
                  units_line, skip_rows)


def longer_rows(name, head: list, named: int, body: list, sep, comment: str, skip_rows: int = 0) -> str | None:
    """The refusal of data rows with more fields than the header names (``body``: the header's (line, text), then
    the first data lines'), or None. Read from their first fields, a point number before x, y was read as x and
    the x as y (a circle of R 99.5 mm for one of 50 mm), and ``170,80,000`` (decimal commas in a comma-separated
    file) as x 170, y 80, its third field dropped. Fields after the named ones that are all empty (a separator
    at the end of each data line) are not refused; nor is an inline comment, nor a line that is no row of data
    (a header below a preamble line taken for the header, which the readers name)."""
    where = None
    widths = []
    for lineno, ln in body[1:]:
        toks = _split(ln.split(comment, 1)[0].strip(), sep)
        longer = len(toks) > named and any(toks[named:]) and _numeric_fields(ln) is not None   # a row of data
        widths.append(len(toks) if longer else named)
        if longer and where is None:
            where = (lineno, ln, len(toks))
    if where is None:
        return None
    lineno, ln, k = where
    header_line = body[0][0]
    names = ", ".join(repr(h) for h in head[:named])
    hint = preamble_hint(name, header_line, skip_rows=skip_rows) if _numeric_fields(body[1][1]) is None else ""
    if hint:          # the "header" is an instrument's preamble line above the table (no numbers below it)
        return f"{name} line {lineno}: {k} fields where the header (line {header_line}) has {named}: {ln!r}{hint}"
    every = len(set(widths)) == 1
    what = (f"every data line has {k} fields (line {lineno}: {ln!r})" if every
            else f"line {lineno} has {k} fields: {ln!r}")
    comma = ""
    if sep == "," and not any("." in t for _, t in body[1:]):
        comma = ("; if the numbers are written with decimal commas, the commas between the fields split them: "
                 "export with ';' or tabs between the fields")
    return (f"{name}: the header (line {header_line}) names {named} column{'s' * (named != 1)} ({names}) but "
            f"{what}; fitbench does not guess which fields the names belong to: name every column in the header, or give "
            f"--skip-rows {header_line} and --columns I J (fields counted from 0; --unit if they are not in mm) to "
            f"read the fields without the header{comma}")


def _marks(name, body, sep, decimal_comma: bool) -> bool:
    """The decimal mark of the data lines ``body`` (:func:`decimal_marks`; rows of at least two numbers, a
    label allowed, :func:`_numeric_fields`), else the separator's guess ``decimal_comma``."""
    rows = []
    for lineno, ln in body:
        toks = _split(ln, sep)
        words = [t for t in toks
                 if t and not (_is_number(t) or _COMMA_NUMBER.fullmatch(t) or _COMMA_GROUPED.fullmatch(t))]
        if len(toks) - len(words) >= 2 and (not words or (len(words) == 1 and _ROW_LABEL.fullmatch(words[0]))):
            rows.append((lineno, toks))
    got = decimal_marks(name, rows)
    return decimal_comma if got is None else got


#: a label a data row may carry beside its numbers (a direction or run column: CW, ccw, +, up, run1, G02)
_ROW_LABEL = re.compile(r"[A-Za-z0-9+\-_]{1,16}")


def _numeric_fields(line: str) -> tuple[str | None, int] | None:
    """(separator, number of fields) when ``line`` is a data row under some separator: at least two numbers,
    and at most one other field, a label such as a direction or run (``CW;0,250;1,9019``)."""
    for sep in (";", "\t", ",", None):
        toks = _split(line, sep)
        words = [t for t in toks if not _is_number(t.replace(",", ".") if sep != "," else t)]
        if len(toks) - len(words) >= 2 and (not words or (len(words) == 1 and _ROW_LABEL.fullmatch(words[0]))):
            return sep, len(toks)
    return None


def skip_rows_hint(layout: Layout, before: int | None = None) -> str:
    """'; or, if ... is a preamble, give --skip-rows N' naming the first row of numbers (and keeping the header
    line just above it when it has as many fields), or '' when no such row is in the first lines."""
    return preamble_hint(layout.name, layout.header_line, before, skip_rows=layout.skip_rows)


def preamble_hint(name, header_line: int = 1, before: int | None = None, skip_rows: int = 0) -> str:
    """:func:`skip_rows_hint` for the file ``name`` whose header was taken from line ``header_line``: the hint
    when the first data row (:func:`_numeric_fields`; a direction or run label allowed) lies below the line
    after that header (and after line ``before``, the line an error names), else ''."""
    previous = None
    name = os.fspath(name)
    try:
        with _open_text(name, skip_rows=skip_rows) as fh:
            for lineno, raw in iter_lines(fh, name):
                ln = raw.strip()
                if lineno < header_line or not ln or ln.startswith(COMMENT_PREFIXES):
                    continue
                got = _numeric_fields(ln)
                if got is not None:
                    n = lineno - 1
                    if previous is not None and previous[0] == lineno - 1 and _units_row(_split(previous[1], got[0])):
                        n = lineno - 3                  # keep the header and the units row under it (read as units)
                    elif previous is not None and previous[0] == lineno - 1 and len(_split(previous[1], got[0])) == got[1]:
                        n = lineno - 2                                  # keep the header line above the numbers
                    if n < header_line or (before is not None and lineno <= before):
                        return ""
                    return (f"; if {'line 1 is' if n == 1 else f'lines 1-{n} are'} an instrument's preamble, give "
                            f"--skip-rows {n} (the first row of numbers is line {lineno})")
                previous = (lineno, ln)
                if lineno > SNIFF_LINES + header_line:
                    return ""
    except (DataFileError, UnicodeDecodeError, OSError):
        return ""
    return ""
