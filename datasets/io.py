"""Reader for users' point files: header optional; comma, semicolon, tab or whitespace separated;
``#`` and ``%`` comment lines; a semicolon file may use decimal commas. Malformed input is refused
with the file name and line number (a :class:`DataFileError`, one kind of :class:`InvalidInputError`)."""
from __future__ import annotations

import io
import os

import numpy as np
import pandas as pd

from methods import InvalidInputError
from methods._validation import read_text_file

COMMENT_PREFIXES = ("#", "%")


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


def read_points(path, columns: tuple[str, str] = ("x", "y")) -> np.ndarray:
    """Read an (N, 2) float array from a text file.

    With a header, the columns named ``columns`` (case-insensitive) are used, else the first two;
    without a header the file must have exactly two columns. Every data line must have the same
    number of fields and every used field must be a finite number.
    """
    name = os.fspath(path)
    text = read_text_file(name, error=DataFileError, missing_hint="give a path or a data set name from 'datasets.list()'")

    lines = [(i + 1, ln.strip()) for i, ln in enumerate(text.splitlines())]
    body = [(i, ln) for i, ln in lines if ln and not ln.startswith(COMMENT_PREFIXES)]
    if not body:
        raise DataFileError(f"{name}: no data lines (only blank or comment lines)")
    first = body[0][1]
    sep = ";" if ";" in first else "," if "," in first else "\t" if "\t" in first else None
    decimal_comma = sep == ";" and any("," in ln for _, ln in body[:50])
    head = _split(first, sep)
    has_header = not all(_is_number(t.replace(",", ".") if decimal_comma else t) for t in head)
    if has_header:
        lowered = [h.lower() for h in head]
        want = [c.lower() for c in columns]
        idx = [lowered.index(c) for c in want] if all(c in lowered for c in want) else [0, 1]
        if len(head) < 2:
            raise DataFileError(f"{name} line {body[0][0]}: header {first!r} has fewer than two columns")
        rows = body[1:]
    else:
        if len(head) != 2:
            raise DataFileError(f"{name} line {body[0][0]}: {len(head)} columns and no header; "
                                "add a header line naming the x and y columns")
        idx = [0, 1]
        rows = body
    if not rows:
        raise DataFileError(f"{name}: a header but no data lines")
    ncol = len(head)

    # Fast path: pandas' C parser on the data lines; any problem is located line by line below.
    data = "\n".join(ln for _, ln in rows)
    try:
        frame = pd.read_csv(io.StringIO(data), sep=r"\s+" if sep is None else sep, header=None,
                            decimal="," if decimal_comma else ".", dtype=float, engine="c" if sep else "python")
        ok = frame.shape[1] == ncol and np.isfinite(frame.to_numpy()[:, idx]).all()
    except (ValueError, pd.errors.ParserError):
        ok = False
    if ok:
        return np.ascontiguousarray(frame.to_numpy()[:, idx], dtype=np.float64)
    for lineno, ln in rows:
        toks = _split(ln, sep)
        if len(toks) != ncol:
            raise DataFileError(f"{name} line {lineno}: {len(toks)} fields where the first line has {ncol}: {ln!r}")
        for j in idx:
            tok = toks[j].replace(",", ".") if decimal_comma else toks[j]
            if not _is_number(tok):
                raise DataFileError(f"{name} line {lineno}: {toks[j]!r} is not a number")
            if not np.isfinite(float(tok)):
                raise DataFileError(f"{name} line {lineno}: {toks[j]!r} is not a finite number; remove or repair the point")
    raise DataFileError(f"{name}: could not be parsed (unexpected format); use one x,y pair per line")


