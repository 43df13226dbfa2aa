"""The fields of a table's lines: comment lines (:data:`COMMENT_PREFIXES`: ``#``, ``%``, ``//``), the
separator (semicolon, tab, comma or whitespace) and the decimal comma guessed from the first data lines
(:func:`_separator`: a header-less ``1,5<TAB>2,25`` is two numbers), double-quoted fields as spreadsheets export
them (:func:`_split`: ``"1,5"`` may hold the separator)."""
from __future__ import annotations

import csv
import re

from datasets.io.numbers import _OTHER_GROUPED, _is_number


COMMENT_PREFIXES = ("#", "%", "//")
SNIFF_LINES = 200


def _separator(lines: list[str]) -> tuple[str | None, bool]:
    """(separator, decimal comma) of a table from its first data lines: semicolon, tab, comma or whitespace
    (None). A comma between digits inside tab- or whitespace-separated fields is a decimal comma, so a
    header-less ``1,5<TAB>2,25`` is two numbers, not three fields."""
    quoted = [ln for ln in lines[:50] if '"' in ln]
    lines = [_unquoted(ln) for ln in lines]
    first = lines[0]
    dec = re.compile(r"[+-]?[0-9]*,[0-9]+(?:[eE][+-]?[0-9]+)?")
    if ";" in first:
        sep = ";"
    elif "," in first:
        sep = ","
        for cand in ("\t", None):
            fields = _split(first, cand)
            if len(fields) >= 2 and (cand is None or "\t" in first) and \
                    all(dec.fullmatch(f) or _is_number(f) or _OTHER_GROUPED.fullmatch(f) for f in fields) and \
                    any(dec.fullmatch(f) or _OTHER_GROUPED.fullmatch(f) for f in fields):
                sep = cand
                break
    elif "\t" in first:
        sep = "\t"
    else:
        sep = None
    if sep == "\t" and any(" " in ln.replace("\t", "") and "\t" not in ln for ln in lines[1:]):
        sep = None  # tabs and spaces mixed: whitespace
    decimal_comma = sep in (";", "\t", None) and any(re.search(r"[0-9],[0-9]", ln) for ln in lines[:50])
    if sep == "," and any(re.search(r'"\s*[+-]?[0-9]*,[0-9]+(?:[eE][+-]?[0-9]+)?\s*"', ln) for ln in quoted):
        decimal_comma = True   # "0,000","5,5035": quoted decimal commas in a comma-separated file
    return sep, decimal_comma


#: what separates the fields of a whitespace table: spaces and tabs, as for pandas' C parser (``str.split()`` would
#: also split at a no-break space, U+00A0 or U+202F, which French exports write as digit grouping: '1 045,9')
_FIELD_SPACE = re.compile(r"[ \t]+")


def _split(line: str, sep: str | None) -> list[str]:
    """The fields of ``line``; a field in double quotes (``"1,5"``, as spreadsheets export) is read without its
    quotes and may hold the separator. Whitespace (``sep`` None) is spaces and tabs (:data:`_FIELD_SPACE`)."""
    if '"' not in line:
        return [t.strip() for t in (line.split(sep) if sep else _FIELD_SPACE.split(line.strip()))]
    if sep is None:
        return [t.strip().strip('"').strip() for t in _FIELD_SPACE.split(line.strip())]
    return [t.strip() for t in next(csv.reader([line], delimiter=sep, skipinitialspace=True))]


def _unquoted(line: str) -> str:
    """``line`` with each double-quoted field's content replaced by ``0``: the separators it shows are real."""
    return re.sub(r'"[^"]*"', "0", line)
