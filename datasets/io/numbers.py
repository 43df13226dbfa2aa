"""The one number grammar of every reader and the readers' two exceptions.

:data:`NUMBER` (optional sign, digits with an optional decimal point, optional exponent; ``nan``/``inf`` read and
refused later as not finite; Python's ``float('117_677670')`` would accept what a person reads as two numbers); the
Unicode minus sign U+2212, as spreadsheets and instrument software export negative numbers, read as '-'
(:func:`ascii_minus`); dashes that only look like one (:data:`DASHES`) and digit grouping (``1,000``, ``1.045,9``,
``1 045,9``, ``1'045.9``) refused by name (:func:`number_problem`); one decimal mark per file
(:func:`decimal_marks`: ``1,000`` beside ``3.7308``, as Excel's "Text (Tab delimited)" writes numbers as displayed,
is refused, never read as a decimal comma). :class:`DataFileError` is the one kind of
:class:`methods.InvalidInputError` every reader raises; :class:`NumberFormatError` says what to export instead."""
from __future__ import annotations

import re

from methods import InvalidInputError


#: the one number grammar of every reader (ASCII digits; no '_' separators, no hexadecimal, no 'd' exponent)
NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NON_FINITE = {"nan", "+nan", "-nan", "inf", "+inf", "-inf", "infinity", "+infinity", "-infinity"}


class DataFileError(InvalidInputError):
    """A points file that cannot be read; the message names the file and line."""


class NumberFormatError(DataFileError):
    """A field whose shape says why it is not a number (digit grouping, a Unicode minus, two decimal marks):
    the message says what to export instead, and no preamble hint (--skip-rows) is added to it."""


def _is_number(token: str) -> bool:
    """``token`` is a number of the readers' grammar (:data:`NUMBER`, or a nan/inf word refused later as not finite)."""
    return NUMBER.fullmatch(token) is not None or token.lower() in _NON_FINITE


def _number(token: str) -> float:
    """``float(token)`` for a token of the grammar, else ValueError."""
    if not _is_number(token):
        raise ValueError(token)
    return float(token)


#: a number written with a decimal comma (``1,5``, ``-0,25e-3``)
_COMMA_NUMBER = re.compile(r"[+-]?[0-9]*,[0-9]+(?:[eE][+-]?[0-9]+)?")
#: a number with ',' digit grouping, as English locales display it (``1,000``, ``12,345.5``, ``1,234,567``)
_COMMA_GROUPED = re.compile(r"[+-]?[1-9][0-9]{0,2}(?:,[0-9]{3})+(?:\.[0-9]*)?")
#: a number with '.', space, no-break space (U+00A0), narrow no-break space (U+202F), thin space (U+2009) or
#: apostrophe grouping (German, French, Swiss locales: ``1.045,9``, ``1 045,9``, ``1'045.9``)
_OTHER_GROUPED = re.compile("[+-]?[1-9][0-9]{0,2}(?P<g>[. \u00a0\u202f\u2009'\u2019])[0-9]{3}(?:(?P=g)[0-9]{3})*"
                            "(?:[.,][0-9]*)?")
_GROUP_NAMES = {",": "','", ".": "'.'", " ": "a space", "\u00a0": "a no-break space (U+00A0)",
                "\u202f": "a narrow no-break space (U+202F)", "\u2009": "a thin space (U+2009)", "'": "an apostrophe",
                "\u2019": "an apostrophe (U+2019)"}
#: integers an export with digit grouping writes without a separator (below 1000), zero excluded
_SMALL_INTEGER = re.compile(r"[+-]?0*[1-9][0-9]{0,2}")

#: the Unicode minus sign (U+2212) before a number, as spreadsheets and instrument software export negative numbers
_UNICODE_MINUS = re.compile("\u2212(?=[0-9.,])")
#: dashes that look like a minus sign but are punctuation: refused by name (:func:`number_problem`), never read
DASHES = {"\u2010": "a hyphen '\u2010' (U+2010)", "\u2011": "a non-breaking hyphen '\u2011' (U+2011)",
          "\u2012": "a figure dash '\u2012' (U+2012)", "\u2013": "an en dash '\u2013' (U+2013)",
          "\u2014": "an em dash '\u2014' (U+2014)", "\ufe63": "a small hyphen-minus '\ufe63' (U+FE63)",
          "\uff0d": "a fullwidth hyphen-minus '\uff0d' (U+FF0D)"}


def ascii_minus(text: str) -> str:
    """``text`` with each Unicode minus sign (U+2212) before a digit, '.' or ',' written as the ASCII '-': every
    reader reads it as a minus sign (a header's ``x \u2212 x0`` is left as it is)."""
    return _UNICODE_MINUS.sub("-", text) if "\u2212" in text else text


class _AsciiMinus:
    """A text file whose reads give :func:`ascii_minus` of its text (for pandas' C parser, which reads ASCII
    signs only); a read ending in U+2212 takes the next character too (the digit after it decides)."""

    def __init__(self, fh):
        self._fh = fh

    def read(self, size: int = -1) -> str:
        text = self._fh.read(size)
        while text.endswith("\u2212") and size is not None and size > 0:
            more = self._fh.read(1)
            if not more:
                break
            text += more
        return ascii_minus(text)

    def __iter__(self):
        return (ascii_minus(line) for line in self._fh)


def number_problem(token: str, decimal_comma: bool = False) -> str | None:
    """Why ``token``, outside the grammar (:data:`NUMBER`), is not read as a number, when its shape says it:
    digit grouping (a thousands separator: ``1,000``, ``1.045,9``, ``1 045,9``, ``1'045.9``), a dash that is not
    a minus sign (:data:`DASHES`: an en dash ``\u20130,5``), or a decimal point in a file of decimal commas. None when
    the shape says nothing. (The Unicode minus sign U+2212 is read as '-': :func:`ascii_minus`.)"""
    t = ascii_minus(str(token).strip())
    if t[:1] in DASHES and (_is_number("-" + t[1:]) or _COMMA_NUMBER.fullmatch("-" + t[1:])):
        return (f"{token!r} starts with {DASHES[t[:1]]}, not a minus sign; fitbench reads '-' and the Unicode minus "
                "'\u2212' (U+2212) as minus, never a dash (a dash also marks ranges and empty cells); export without "
                "typographic dashes (or replace it by '-')")
    m = _COMMA_GROUPED.fullmatch(t)
    g = "," if m else None
    if not m:
        m = _OTHER_GROUPED.fullmatch(t)
        g = m.group("g") if m else None
    if m and not (g == "." and _is_number(t)):
        return (f"{token!r} looks like a number with a thousands separator ({_GROUP_NAMES[g]}); export without "
                "digit grouping")
    if decimal_comma and _is_number(t) and "." in t:
        return (f"{token!r} has a decimal point where the file's numbers have decimal commas; a file uses one "
                "decimal mark: export it again with one")
    return None


def decimal_marks(name, rows) -> bool | None:
    """The decimal mark of a file's numbers, from its data fields ``rows`` ((line number, tokens) pairs): True
    for decimal commas, False for decimal points, None when no field has either.

    One mark per file. A field with a comma between digits is a decimal comma (``1500,0000``) unless the file
    also writes decimal points (``3.7308``): no export mixes the two marks, so then the comma is digit grouping
    (``1,000`` beside ``3.7308``: Excel's "Text (Tab delimited)" writes numbers as displayed) and the file is
    refused, naming the line and the field. Without decimal points, a column whose comma fields all look like
    grouping (one to three digits, not starting with 0, then groups of exactly three: ``2,908``, ``-1,140``)
    and which also holds integers from 1 to 999 without a comma (``25``, ``-80``) is refused as ambiguous:
    a grouped export writes numbers below 1000 that way, a fixed-decimals export would write ``25,000``.
    A column whose every field is ``d,ddd`` is read as decimal commas (nothing in the file can tell).
    Checked on every line of every file: a small file (:data:`SMALL_FILE_BYTES`), a positioning or multilateration
    table line by line; a larger file on its first :data:`SNIFF_LINES` data lines, then (its parser refusing any
    field with the other mark) on all of them without a Python loop over the lines (:func:`_check_grouping`)."""
    first_comma = first_point = None
    columns: dict = {}   # column -> [all comma fields grouping-shaped, first comma field, first small integer]
    for lineno, toks in rows:
        for j, t in enumerate(toks):
            if "," in t and _COMMA_GROUPED.fullmatch(t) and ("." in t or t.count(",") > 1):
                raise NumberFormatError(f"{name} line {lineno}: {number_problem(t)}")
            if _COMMA_NUMBER.fullmatch(t):
                first_comma = first_comma or (lineno, t)
                col = columns.setdefault(j, [True, None, None])
                col[1] = col[1] or (lineno, t)
                col[0] = col[0] and _COMMA_GROUPED.fullmatch(t) is not None
            elif NUMBER.fullmatch(t):
                if "." in t:
                    first_point = first_point or (lineno, t)
                elif _SMALL_INTEGER.fullmatch(t):
                    columns.setdefault(j, [True, None, None])
                    if columns[j][2] is None:
                        columns[j][2] = (lineno, t)
    if first_comma is None:
        return None if first_point is None else False
    lineno, t = first_comma
    if first_point is not None:
        if _COMMA_GROUPED.fullmatch(t):
            raise NumberFormatError(f"{name} line {lineno}: {t!r} looks like a thousands separator (line "
                                    f"{first_point[0]} writes {first_point[1]!r} with a decimal point); export "
                                    "without digit grouping")
        raise NumberFormatError(f"{name} line {lineno}: {t!r} has a decimal comma but line {first_point[0]} writes "
                                f"{first_point[1]!r} with a decimal point; a file uses one decimal mark: export it "
                                "again with one")
    for grouped, comma, small in columns.values():
        if grouped and comma is not None and small is not None:
            raise NumberFormatError(f"{name} line {comma[0]}: {comma[1]!r} looks like a thousands separator (every "
                                    f"comma number of its column has three digits after the comma, and line "
                                    f"{small[0]} writes {small[1]!r} without one); export without digit grouping")
    return True


def _field_number(token: str, decimal_comma: bool) -> float:
    """A field as a number of the grammar, its comma read as the decimal mark in a file of decimal commas (where
    a decimal point is refused: one mark per file, :func:`decimal_marks`); ValueError otherwise."""
    if decimal_comma:
        if "." in token:
            raise ValueError(token)
        token = token.replace(",", ".")
    return _number(token)
