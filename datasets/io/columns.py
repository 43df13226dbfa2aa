"""Numeric columns of a sniffed file as float64 arrays (:func:`read_columns`).

A small file (:data:`SMALL_FILE_BYTES`) is read without pandas by Python's float after the grammar check
(:func:`_read_small`); a larger one by pandas' C parser straight from the file with a float64 dtype and only the
columns used (peak memory within 3x the returned array), again through a stream writing U+2212 as '-' when it holds
one. The line-by-line diagnosis (:func:`_diagnose`: file name, line number, what is wrong) runs only after the fast
parser failed; digit grouping is checked over every line of a large file of decimal commas (:func:`_check_grouping`)."""
from __future__ import annotations

import contextlib
import os
import re

import numpy as np

from datasets.io._pandas import pd
from datasets.io.delimiters import COMMENT_PREFIXES, _split
from datasets.io.layout import Layout, _numeric_fields, skip_rows_hint
from datasets.io.numbers import (_COMMA_GROUPED, _COMMA_NUMBER, DataFileError, NumberFormatError, _AsciiMinus,
                                 _field_number, _is_number, _number, decimal_marks, number_problem)
from datasets.io.textfile import (_open_text, check_line_lengths, file_encoding, iter_lines, read_lines,
                                  refuse_cut_last_line, text_end, unterminated_last_line)


def _diagnose(layout: Layout, idx, skip_rows: int):
    """Locate the first bad line (runs only after the fast parser failed)."""
    name = layout.name
    text = read_lines(name, skip_rows=layout.skip_rows)
    seps = "".join(c for c in (layout.sep or "") if not c.isspace())
    gap = None   # the first blank, separator-only or comment line after the last data line
    for lineno, ln in enumerate(text, start=1):
        ln = ln.strip()
        if lineno < layout.first_data_line:
            continue
        if not ln or ln.startswith(COMMENT_PREFIXES):
            gap = gap or lineno
            continue
        if "\x00" in ln:
            raise DataFileError(f"{name} line {lineno}: holds NUL bytes, so it is not a text table; if it is UTF-16 or "
                                "UTF-32 text, save it as UTF-8 (or with a byte-order mark)")
        toks = _split(ln, layout.sep)
        if seps and not ln.strip(seps):          # ',' or ';;': a spreadsheet's empty row
            raise DataFileError(f"{name} line {lineno}: holds only separators ({ln!r}), no values: "
                                f"{_after_table(text, lineno, separators=True)}")
        if len(toks) != layout.ncol:
            where = f"the header (line {layout.header_line})" if layout.header else "the first line"
            what = skip_rows_hint(layout, before=lineno)
            if not what and len(toks) > layout.ncol:   # never read from its first fields
                what = ("; correct the line, or delete it" if not layout.header else
                        "; correct the line, or delete it (if such lines hold a column more, name it in the header)")
            raise DataFileError(f"{name} line {lineno}: {len(toks)} field{'s' if len(toks) != 1 else ''} where {where} "
                                f"has {layout.ncol}: {ln!r}{what}")
        for j in idx:
            tok = toks[j].replace(",", ".") if layout.decimal_comma else toks[j]
            if not _is_number(tok) or (layout.decimal_comma and "." in toks[j]):
                why = number_problem(toks[j], layout.decimal_comma)
                if why:
                    raise NumberFormatError(f"{name} line {lineno}: {why}")
                hint = skip_rows_hint(layout, before=lineno) or _header_below(layout, lineno, ln, toks)
                if not hint and not toks[j]:
                    column = repr(layout.header[j]) if layout.header else f"column {j}"
                    raise DataFileError(f"{name} line {lineno}: missing field: {column} is empty: fill in the value, "
                                        "or delete the line")
                if not hint:
                    after = _after_table(text, lineno) if gap else ""
                    hint = (f": {after}" if after else
                            ": correct the value, or delete the line (a totals or summary line: delete it, or "
                            "prefix it with #)")
                raise DataFileError(f"{name} line {lineno}: {toks[j]!r} is not a number{hint}")
            if not np.isfinite(_number(tok)):
                raise DataFileError(f"{name} line {lineno}: {toks[j]!r} is not a finite number; remove or repair the point")
        gap = None
    raise DataFileError(f"{name}: could not be parsed (unexpected format); use one row of numbers per line")


def _after_table(text: list, lineno: int, separators: bool = False) -> str:
    """What to do with line ``lineno`` of ``text`` (the file's lines), not a data row, below a blank line or a line
    of separators (``separators``: it is one): when no row of numbers follows (a summary after the points: 'Max
    deviation,0.0034', Excel's 'Count,240'), delete the lines or comment them out; when one does, the file holds
    a second table (under its own header) or block of points, and each is to be read on its own."""
    rest = [(k, ln.strip()) for k, ln in enumerate(text[lineno:], start=lineno + 1)
            if ln.strip() and not ln.strip().startswith(COMMENT_PREFIXES)]
    numbers = next((k for k, ln in rest if (got := _numeric_fields(ln)) is not None and got[1] >= 2), None)
    if numbers is not None:
        if separators:
            return (f"delete the line; if the rows from line {numbers} are another profile, save each profile in a "
                    "file of its own")
        return (f"rows of numbers follow again from line {numbers}: the file holds a second table; save each table "
                f"in a file of its own (or delete the lines not to be read)")
    last = rest[-1][0] if rest else lineno
    if last == lineno:
        return f"line {lineno}, below the points, is not a point (a summary?): delete it, or prefix it with #"
    return f"lines {lineno}-{last}, below the points, are not points (a summary?): delete them, or prefix them with #"


def _header_below(layout: Layout, lineno: int, line: str, toks: list) -> str:
    """The --skip-rows hint for a file without a header whose line ``lineno``, near the top, is a row of names
    (``50;3600`` above ``Winkel [°];Abweichung [µm]``: an instrument's numeric preamble taken for data), else ''."""
    if layout.header is not None or lineno > PREAMBLE_LINES or not all(t.strip() for t in toks) or \
            any(_is_number(t.replace(",", ".")) for t in toks):
        return ""
    n = lineno - 1
    return (f"; if {'line 1 is' if n == 1 else f'lines 1-{n} are'} an instrument's preamble above the header "
            f"{line!r}, give --skip-rows {n}")


#: the first lines of a file where a row of names under rows of numbers is taken for a header below a preamble
PREAMBLE_LINES = 20


def _check_last_line(layout: Layout, idx) -> None:
    """:func:`refuse_cut_last_line` for a file read by :func:`read_columns` (the reference: the sniffed data rows)."""
    last = unterminated_last_line(layout.name, layout.skip_rows)
    if last is None:
        return
    toks = _split(last[1].strip(), layout.sep)
    rows = [_split(ln, layout.sep) for n, ln in layout.sample if n != last[0]]
    refuse_cut_last_line(layout.name, (last[0], toks), [r for r in rows if len(r) == layout.ncol], idx)


#: files up to this size are parsed without pandas (whose import costs ~0.3 s: fast start-up)
SMALL_FILE_BYTES = 1 << 16


def _read_small(layout: Layout, usecols: list[int]) -> dict | None:
    """The float columns ``usecols`` of a small, plain numeric file, read with Python's float (correctly
    rounded) after the grammar check (:data:`NUMBER`); None when the file is large or unusual (an inline
    comment, a short row), and the pandas reader below decides (and explains). A token outside the
    grammar is explained by the same diagnosis as in a large file."""
    try:
        if os.path.getsize(layout.name) > SMALL_FILE_BYTES:
            return None
    except OSError:
        return None
    rows, fields = [], []
    for lineno, raw in enumerate(read_lines(layout.name, skip_rows=layout.skip_rows), start=1):
        ln = raw.strip()
        if lineno < layout.first_data_line or not ln or ln.startswith(layout.comment):
            continue
        if layout.comment in ln:
            return None
        tokens = _split(ln, layout.sep)
        if len(tokens) != layout.ncol:
            return None
        try:
            rows.append([_field_number(tokens[k], layout.decimal_comma) for k in usecols])
        except ValueError:
            _diagnose(layout, usecols, 0)
        if layout.decimal_comma:
            fields.append((lineno, [tokens[k] for k in usecols]))
    if not rows:
        return None
    if fields:
        decimal_marks(layout.name, fields)   # every line, not only the sniffed ones: '2,908' beside a later '25'
    table = np.array(rows, dtype=np.float64)
    return {k: table[:, j].copy() for j, k in enumerate(usecols)}


def read_columns(layout: Layout, idx: list[int], *, skip_rows: int = 0, strings: tuple[int, ...] = ()) -> dict:
    """The columns ``idx`` as float64 arrays (and ``strings`` as object arrays), straight from the file."""
    usecols = sorted(set(idx) | set(strings))
    small = None if strings else _read_small(layout, usecols)
    if small is not None:
        if not all(np.isfinite(small[k]).all() for k in idx):
            _diagnose(layout, idx, skip_rows)
        _check_last_line(layout, idx)
        return small
    check_line_lengths(layout.name, layout.skip_rows)
    dtype = {k: (object if k in strings else np.float64) for k in usecols}
    dos_eof = text_end(layout.name) is not None

    def parse(usecols=usecols, *, decimal="," if layout.decimal_comma else ".", thousands=None, minus=False):
        """The columns ``usecols`` by pandas' C parser (``minus``: from a stream writing U+2212 as '-')."""
        try:
            with contextlib.ExitStack() as stack:
                source = (_AsciiMinus(stack.enter_context(_open_text(layout.name, skip_rows=layout.skip_rows)))
                          if minus or dos_eof else layout.name)   # the text before a DOS end-of-file mark
                frame = pd.read_csv(source, sep=r"\s+" if layout.sep is None else layout.sep, header=None,
                                    skiprows=layout.first_data_line - 1, dtype={k: dtype[k] for k in usecols},
                                    usecols=None if len(usecols) == layout.ncol else usecols, decimal=decimal,
                                    thousands=thousands, comment=layout.comment, skip_blank_lines=True, engine="c",
                                    encoding=file_encoding(layout.name), keep_default_na=True)
            cols = {k: frame[k].to_numpy() for k in usecols}
            del frame
            return cols, all(np.isfinite(cols[k]).all() for k in idx if k in cols)
        except (ValueError, KeyError, pd.errors.ParserError, UnicodeDecodeError):
            return None, False   # KeyError: every row shorter than the header

    minus = False
    cols, ok = parse()
    if not ok and _holds_unicode_minus(layout.name, layout.skip_rows):   # parsed again, its minus signs in ASCII
        minus = True
        cols, ok = parse(minus=True)
    if not ok:
        _diagnose(layout, idx, skip_rows)
    if not all(len(cols[k]) for k in usecols):
        raise DataFileError(f"{layout.name}: a header but no data lines")
    if layout.decimal_comma:
        _check_grouping(layout, idx, cols, lambda columns: parse(columns, decimal=".", thousands=",", minus=minus))
    _check_last_line(layout, idx)
    return cols


def _grouping_suspects(layout: Layout, idx) -> list[int]:
    """The columns of ``idx`` whose comma numbers in the sniffed lines all look like digit grouping (``2,908``) or
    which hold none there: only in those can a later line make the file one :func:`decimal_marks` refuses."""
    rows = [_split(ln, layout.sep) for _, ln in layout.sample]
    return [k for k in idx
            if all(_COMMA_GROUPED.fullmatch(r[k]) for r in rows if k < len(r) and _COMMA_NUMBER.fullmatch(r[k]))]


def _check_grouping(layout: Layout, idx, cols: dict, parse_grouped) -> None:
    """:func:`decimal_marks` over every line of a large file of decimal commas (:func:`sniff` saw its first
    :data:`SNIFF_LINES`; a column of ``2,908`` there and ``25`` further down was read as 2.908 and 25), decided
    without a Python loop over the lines: the columns it could refuse (:func:`_grouping_suspects`) are parsed a
    second time by the C parser with ',' as the thousands separator, giving t beside the decimal-comma value d. A
    field without a comma has t = d; ``d,ddd`` (k digits after the comma) has t = 1000 d in [1000, 10^6). A column
    with a comma field, every one of them of that kind, and an integer from 1 to 999 with t = d is what the rule
    refuses (or, for contrived fields such as ``2,908e0``, may): the lines are then checked one by one, by the same
    function as a small file's, which refuses it naming the lines."""
    suspects = _grouping_suspects(layout, idx)
    if not suspects:
        return
    grouped_cols, ok = parse_grouped(suspects)
    maybe = not ok   # a field the second parse cannot read (',5'): the lines decide
    for k in suspects if ok else ():
        d, t = cols[k], grouped_cols[k]
        with np.errstate(invalid="ignore", over="ignore"):
            comma = t != d
            grouped = (np.abs(t) >= 1000) & (np.abs(t) < 1e6) & (t == np.rint(t)) & (np.abs(1000 * d - t) <= 1e-9 * np.abs(t))
            small = ~comma & (d == np.rint(d)) & (np.abs(d) >= 1) & (np.abs(d) <= 999)
        if comma.any() and small.any() and not (comma & ~grouped).any():
            maybe = True
            break
    if maybe:
        decimal_marks(layout.name, _data_fields(layout, idx))


def _data_fields(layout: Layout, columns) -> list:
    """(line number, fields ``columns``) of every data line of ``layout``'s file (an inline comment cut off)."""
    out = []
    for lineno, raw in enumerate(read_lines(layout.name, skip_rows=layout.skip_rows), start=1):
        ln = raw.split(layout.comment, 1)[0].strip()
        if lineno < layout.first_data_line or not ln:
            continue
        toks = _split(ln, layout.sep)
        if len(toks) == layout.ncol:
            out.append((lineno, [toks[k] for k in columns]))
    return out


def data_blocks(layout: Layout, gaps: list | None = None) -> list[tuple[int, int]]:
    """(first, last) line of each block of data lines of ``layout``'s file, blocks being separated by blank lines,
    lines holding only separators (``,``) or comment lines (``# second diameter``): CMM and form-tester exports list
    several features one after another that way, each under its own label or after a blank line. Separators before
    the first data line or after the last make no block. ``gaps``, if given, receives what separated the blocks
    (:func:`_gap_kind`: 'blank', 'separators', or the first comment line as ``(line, text)``). A file without such a
    line between two data lines is one block, found by a regular-expression scan of 4 Mi character blocks; else one
    pass over the lines, nothing kept but the blocks."""
    if not _has_gap_line(layout.name, layout.skip_rows, layout.sep):
        return [(layout.first_data_line, -1)]
    blocks, start, last, gap = [], None, None, []
    seps = "".join(c for c in (layout.sep or "") if not c.isspace())
    with _open_text(layout.name, skip_rows=layout.skip_rows) as fh:
        for lineno, raw in iter_lines(fh, layout.name):
            if lineno < layout.first_data_line:
                continue
            ln = raw.strip()
            if not ln.strip(seps) or ln.startswith(COMMENT_PREFIXES) or ln.startswith(layout.comment):
                if start is not None:
                    gap.append(_gap_kind(lineno, ln, seps))
                continue
            if gap:
                if not _NUMBER_START.match(ln):  # an instrument's summary after the points ('RONt [µm];4,0813'): no
                    break                        # block of points (the reader names the line that is not a number)
                blocks.append((start, last))
                if gaps is not None:
                    gaps.append(gap)
                start, gap = None, []
            if start is None:
                start = lineno
            last = lineno
    if start is not None:
        blocks.append((start, last))
    return blocks


#: how a line of numbers starts (a sign, a digit, a decimal point or comma before a digit, inf or nan)
_NUMBER_START = re.compile(r"[+\-]?(?:\d|[.,]\d|inf|nan)", re.IGNORECASE)


def _gap_kind(lineno: int, line: str, seps: str):
    """What the line ``line`` (stripped) between two blocks of data is: 'blank', 'separators' or (line, text) of a
    comment."""
    return "blank" if not line else "separators" if not line.strip(seps) else (lineno, line)


_COMMENT_LINE = r"[ \t]*(?:#|%|//)[^\n]*\n"
_DATA_START = r"[ \t\r\f\v]*[^\s#%/]"


def _gap_pattern(sep: str | None) -> re.Pattern:
    """A data line's start, then blank lines, lines of separators only or comment lines, then another data line's
    start (any line not blank nor a comment: a header line too, which :func:`data_blocks` passes over)."""
    seps = re.escape("".join(c for c in (sep or "") if not c.isspace()))
    blank = rf"[ \t\r\f\v{seps}]*\n"
    data = rf"[ \t\r\f\v]*[^\s#%/{seps}]" if seps else _DATA_START
    return re.compile(rf"\n{data}[^\n]*\n(?:{blank}|{_COMMENT_LINE})+{data}")


def _has_gap_line(path, skip_rows: int = 0, sep: str | None = None) -> bool:
    """Whether the text of ``path`` holds a blank, separator-only or comment line between two lines that are neither
    (read in blocks of 4 Mi characters, each searched with the last 64 Ki characters of the one before)."""
    pattern, tail = _gap_pattern(sep), "\n"
    with _open_text(path, skip_rows=skip_rows) as fh:
        while block := fh.read(1 << 22):
            text = tail + block
            if pattern.search(text):
                return True
            cut = text.find("\n", max(len(text) - (1 << 16), 0))
            tail = text[cut:] if cut >= 0 else text
    return False


def _holds_unicode_minus(path, skip_rows: int = 0) -> bool:
    """Whether the text of ``path`` holds a Unicode minus sign (U+2212), read in blocks of 4 Mi characters."""
    with _open_text(path, skip_rows=skip_rows) as fh:
        while block := fh.read(1 << 22):
            if "\u2212" in block:
                return True
    return False
