"""Tables with named columns (:func:`read_table`), the base of the positioning and multilateration readers:
a header, separator and decimal mark decided like :func:`datasets.io.layout.sniff`'s, a units row under the header,
decimal commas turned into points, read as strings by pandas with the file's line number of each row; a column
as float64 by the readers' one grammar (:func:`_numeric_column`)."""
from __future__ import annotations

import numpy as np

from datasets.io._pandas import pd
from datasets.io.delimiters import COMMENT_PREFIXES, SNIFF_LINES, _separator, _split
from datasets.io.headers import _names_above, _units_row, _with_units
from datasets.io.numbers import _NON_FINITE, NUMBER, DataFileError, NumberFormatError, decimal_marks, number_problem
from datasets.io.textfile import note_encoding, read_lines, refuse_cut_last_line, unterminated_last_line


def read_table(path, *, no_data_hint: str = "", keep_default_na: bool = True, skip_rows: int = 0):
    """A delimited text table with a header (separator and decimal comma as :func:`sniff` decides; blank and
    comment lines skipped; ``skip_rows`` preamble lines dropped; decimal commas turned into points) as a
    DataFrame of strings, with the file's line number of each data row. Errors are one line."""
    import io

    if skip_rows < 0:
        raise DataFileError(f"--skip-rows must be >= 0, got {skip_rows}")
    kept, lines = [], []
    all_lines = read_lines(path, "", skip_rows)
    note_encoding(path)
    for k, line in enumerate(all_lines, start=1):
        if k > skip_rows and line.strip() and not line.lstrip().startswith(COMMENT_PREFIXES):
            kept.append(line)
            lines.append(k)
    if len(kept) < 2:
        raise DataFileError(f"{path}: no data lines{f' ({no_data_hint})' if no_data_hint else ''}")
    sep, decimal_comma = _separator([ln.strip() for ln in kept])
    if sep is None:   # the parser below splits at any Unicode space: '1 000' grouped with U+00A0/U+202F is named
        for k, line in zip(lines, kept):
            if "\u00a0" in line or "\u202f" in line:
                why = next(filter(None, (number_problem(t) for t in _split(line, None)
                                         if "\u00a0" in t or "\u202f" in t)), None)
                if why:
                    raise NumberFormatError(f"{path} line {k}: {why}")
    header = _split(kept[0].strip(), sep)
    if _units_row(header) is not None:
        raise DataFileError(f"{path} line {lines[0]}: the header {kept[0].strip()!r} names units, not columns; put "
                            "the units into the names (Target [mm], Run 1 + [µm])"
                            + _names_above(skip_rows))
    try:
        df = pd.read_csv(io.StringIO("\n".join(kept)), sep=r"\s+" if sep is None else sep, engine="python", dtype=str,
                         keep_default_na=keep_default_na)
    except pd.errors.ParserError as exc:
        raise DataFileError(_parser_error(path, exc, lines)) from None
    units = _units_row(df.iloc[0].fillna("").astype(str).tolist()) if len(df) else None
    if units is not None:                     # a units row under the header: into the names, as NAME [UNIT]
        df.columns = _with_units(path, [str(c) for c in df.columns], units, lines[1])
        df, lines = df.iloc[1:].reset_index(drop=True), lines[:1] + lines[2:]
        if not len(df):
            raise DataFileError(f"{path}: no data lines{f' ({no_data_hint})' if no_data_hint else ''}")
    cells = df.fillna("").astype(str).apply(lambda c: c.str.strip()).values.tolist()
    marks = decimal_marks(path, zip(lines[1:], cells))
    decimal_comma = decimal_comma if marks is None else marks
    last = unterminated_last_line(path, skip_rows)
    if last is not None and last[0] == lines[-1]:
        refuse_cut_last_line(path, (last[0], cells[-1]), cells[:-1][:SNIFF_LINES], range(len(df.columns)))
    if decimal_comma:
        df = df.apply(lambda col: col.str.replace(r"^\s*([+-]?[0-9]*),([0-9]+(?:[eE][+-]?[0-9]+)?)\s*$", r"\1.\2",
                                                  regex=True)
                      if pd.api.types.is_string_dtype(col) or col.dtype == object else col)
    return df, lines[1:]


def _parser_error(path, exc, lines) -> str:
    """pandas' ParserError in the file's own terms: its 'line L' counts the lines pandas was given (blank, comment
    and skipped lines left out), so it is translated to the file's line (``lines``: the file's line number of each
    line given); pandas' guesses about quoting are left out."""
    import re
    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    m = re.match(r"Expected (\d+) fields? in line (\d+), saw (\d+)", text)
    if m and 1 <= int(m.group(2)) <= len(lines):
        want, at, got = int(m.group(1)), lines[int(m.group(2)) - 1], int(m.group(3))
        return f"{path} line {at}: {got} field{'s' * (got != 1)} where the header (line {lines[0]}) has {want}"
    text = re.sub(r"\s*Error could possibly be due to.*$", "", text)
    text = re.sub(r"\s*(?:in|at|on) line \d+|\s*line \d+", "", text).rstrip(" .,;")   # not the file's line numbers
    return f"{path}: malformed table ({text})"


def _numeric_column(col, what: str, name, lines) -> np.ndarray:
    """A column of strings as float64 by the readers' one grammar (:data:`NUMBER`); the first token outside
    it, or not finite, is refused with its line."""
    text = col.astype(str).str.strip()
    ok = text.str.fullmatch(NUMBER.pattern).to_numpy(dtype=bool)
    values = np.full(len(text), np.nan)
    values[ok] = text[ok].astype(float).to_numpy()
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        k = int(bad[0])
        tok = str(col.iloc[k]).strip()
        if tok.lower() in _NON_FINITE:
            raise DataFileError(f"{name} line {lines[k]}: {what} {tok!r} is not a finite number; remove or repair the point")
        why = number_problem(tok)
        if why:
            raise NumberFormatError(f"{name} line {lines[k]}: {what} {why}")
        raise DataFileError(f"{name} line {lines[k]}: {what} {col.iloc[k]!r} is not a finite number")
    return values
