"""The instrument reader: every file a user hands to fitbench is read here. Points (any two columns),
circular-test runs (x, y or angle + radial deviation, one or both directions in one file), ISO 230-2
positioning tables (long or wide laser exports, :func:`read_positioning`) and multilateration lengths
(:func:`read_multilateration`). Header optional; comma, semicolon, tab or whitespace separated (tab and
whitespace files may use decimal commas, header or not; fields may be double-quoted, quoted decimal commas
too); UTF-8, UTF-16 or UTF-32 (with a BOM or without), else Windows-1252 (:func:`file_encoding`); ``#`` and ``%`` comment lines; ``skip_rows``
drops a preamble (instrument software writes test conditions above the table). Every reader takes the
file's length unit (``unit``, default mm) and returns millimetres.

One decimal mark per file (:func:`decimal_marks`: digit grouping such as ``1,000`` beside ``3.7308`` is refused,
never read as a decimal comma); a units row under the header (``X;Y`` / ``µm;µm``) gives the columns' units; a
last line cut in its number (no line end, fewer decimals than its column) is refused (:func:`refuse_cut_last_line`).

One number grammar for every file and size (:data:`NUMBER`: optional sign, digits with an optional
decimal point, optional exponent; ``nan``/``inf`` are read and then refused as not finite): Python's
``float('117_677670')`` would accept what a person reads as two numbers. The Unicode minus sign ``−``
(U+2212, as spreadsheets and instrument software export negative numbers) is read as ``-``
(:func:`ascii_minus`); dashes that only look like one (en dash U+2013, hyphens, :data:`DASHES`) and digit grouping
(``1,000``, ``1 045,9`` with a space, U+00A0 or U+202F) are refused by name (:func:`number_problem`). Only regular files are read (a
FIFO or a device is refused without blocking, :func:`methods.files.open_regular`) and no line may exceed
:data:`MAX_LINE_CHARS`. Large numeric files are parsed by pandas' C parser straight from the file with a
float64 dtype and only the columns used (peak memory within 3x the returned array). Malformed input is
refused with the file name and line number (a :class:`DataFileError`, one kind of
:class:`InvalidInputError`); the line-by-line diagnosis runs only after the fast parser failed.
"""
from __future__ import annotations

import codecs
import contextlib
import csv
import importlib
import os
import re
import warnings
from dataclasses import dataclass, field

import numpy as np

from methods import InvalidInputError
from methods.files import NotRegularFileError, open_regular
from methods.units import canonical, to_mm


class _Lazy:
    """pandas imported on first use (its import costs ~0.3 s; small files are read without it)."""

    def __getattr__(self, name):
        return getattr(importlib.import_module("pandas"), name)


pd = _Lazy()

#: longest line read (characters): a measurement table's line is far shorter; /dev/zero-like content is refused
MAX_LINE_CHARS = 1 << 16
#: the one number grammar of every reader (ASCII digits; no '_' separators, no hexadecimal, no 'd' exponent)
NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NON_FINITE = {"nan", "+nan", "-nan", "inf", "+inf", "-inf", "infinity", "+infinity", "-infinity"}

COMMENT_PREFIXES = ("#", "%", "//")
SNIFF_LINES = 200
PLANES = {"xy": ("x", "y"), "yz": ("y", "z"), "zx": ("z", "x"), "xz": ("x", "z"), "yx": ("y", "x"), "zy": ("z", "y")}


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


#: the encoding decided per file (path, size, modification time): :func:`file_encoding`
_ENCODINGS: dict = {}


class EncodingNote(UserWarning):
    """A file that is not UTF-8, read as Windows-1252 (or Latin-1): its non-ASCII characters may be wrong."""


def file_encoding(path) -> str:
    """The text encoding of ``path``: UTF-32 or UTF-16 when it starts with their byte-order mark, or when its first
    64 KiB hold NUL bytes and read as such text without one (:func:`_wide_without_bom`), UTF-8 (a BOM
    skipped) when its bytes are UTF-8, else Windows-1252 (``cp1252``, the Windows exports' ANSI code page, a
    superset of Latin-1's printable characters), or Latin-1 for bytes cp1252 leaves undefined. The UTF-8
    check streams the file in 4 MiB blocks (ASCII blocks are checked without decoding)."""
    name = os.fspath(path)
    try:
        st = os.stat(name)
        key = (os.path.abspath(name), st.st_size, st.st_mtime_ns)
    except OSError:
        return "utf-8-sig"
    if key in _ENCODINGS:
        return _ENCODINGS[key]
    try:
        with open_regular(name, encoding=None) as fh:
            head = fh.read(1 << 16)
            enc = ("utf-32" if head[:4] in (codecs.BOM_UTF32_LE, codecs.BOM_UTF32_BE) else
                   "utf-16" if head[:2] in (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE) else
                   _wide_without_bom(head) if b"\x00" in head else None)
            if enc is None:
                fh.seek(0)
                enc, dec = "utf-8-sig", codecs.getincrementaldecoder("utf-8")()
                while True:
                    block = fh.read(1 << 22)
                    try:
                        if not block:
                            dec.decode(b"", final=True)
                            break
                        if not block.isascii():
                            dec.decode(block)
                    except UnicodeDecodeError:
                        enc = "cp1252"
                        break
                if enc == "cp1252":
                    fh.seek(0)
                    try:
                        codecs.decode(fh.read(), "cp1252")
                    except UnicodeDecodeError:
                        enc = "latin-1"
    except (OSError, InvalidInputError):
        return "utf-8-sig"   # the open below reports it in one line
    _ENCODINGS[key] = enc
    return enc


#: bytes per code unit of the wide encodings :func:`file_encoding` may decide (1 for the others)
CODE_UNIT_BYTES = {"utf-16": 2, "utf-16-le": 2, "utf-16-be": 2, "utf-32": 4, "utf-32-le": 4, "utf-32-be": 4}


def _wide_without_bom(head: bytes) -> str | None:
    """The UTF-32 or UTF-16 byte order (``utf-32-le``, ..., ``utf-16-be``) in which the first bytes of a file
    holding NUL bytes decode strictly to text without NULs, nearly all printable and mostly ASCII (a table
    saved as "Unicode" without a byte-order mark); None for anything else (a binary file, a stray NUL in ASCII
    text: read as before, its line refused)."""
    for enc in ("utf-32-le", "utf-32-be", "utf-16-le", "utf-16-be"):
        try:
            text = codecs.getincrementaldecoder(enc)().decode(head, final=False)
        except UnicodeDecodeError:
            continue
        if text and "\x00" not in text and sum(c.isascii() for c in text) >= 0.5 * len(text) and \
                sum(c.isprintable() or c in "\r\n\t" for c in text) >= 0.99 * len(text):
            return enc
    return None


def note_encoding(path) -> None:
    """Warn (:class:`EncodingNote`) when ``path`` is read as Windows-1252 or Latin-1 rather than UTF-8."""
    enc = file_encoding(path)
    if enc in ("cp1252", "latin-1"):
        warnings.warn(f"{os.fspath(path)}: not UTF-8; read as {'Windows-1252 (cp1252)' if enc == 'cp1252' else 'Latin-1'}"
                      ", the usual Windows export encoding (check its header's °, µ; save as UTF-8 to silence this)",
                      EncodingNote, stacklevel=3)


#: the first bytes of files that are not text tables, what they are and what to do (a spreadsheet read as
#: cp1252 text gave "not UTF-8; read as Windows-1252" and "a header but no data lines")
NOT_TEXT = ((b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1", "an Excel 97-2003 workbook (an OLE2 compound file)",
             "save it as CSV (UTF-8) or text (tab delimited) from the spreadsheet program"),
            (b"PK\x03\x04", "a zip archive", "unpack it, or read the table it holds"),
            (b"PK\x05\x06", "an empty zip archive", "give the measurement file itself"),
            (b"\x1f\x8b", "a gzip-compressed file", "decompress it first (gunzip)"),
            (b"%PDF", "a PDF document", "export the measurements from the instrument software as CSV or text"),
            (b"\x89PNG", "a PNG image", "give the measurement file, not a picture of it"))
#: a zip archive by its name: what a spreadsheet program saved
ZIP_SPREADSHEETS = {".xlsx": "an Excel workbook", ".xlsm": "an Excel workbook", ".xltx": "an Excel template",
                    ".ods": "an OpenDocument spreadsheet", ".numbers": "a Numbers spreadsheet"}


def not_text(path) -> str | None:
    """What is wrong when ``path`` is a spreadsheet, an archive, a PDF or an image rather than a text table (its
    first bytes, :data:`NOT_TEXT`): 'x.xlsx is an Excel workbook (a zip archive), not a text table: save it as
    CSV ...'; None for anything else (also when it cannot be opened: the reader then says why)."""
    name = os.fspath(path)
    try:
        with open_regular(name, encoding=None) as fh:
            head = fh.read(8)
    except (OSError, InvalidInputError):
        return None
    for magic, what, todo in NOT_TEXT:
        if head.startswith(magic):
            if magic == b"PK\x03\x04":
                sheet = ZIP_SPREADSHEETS.get(os.path.splitext(name)[1].lower())
                if sheet:
                    what, todo = f"{sheet} (a zip archive)", ("save it as CSV (UTF-8) from the spreadsheet program "
                                                              "(Excel: File > Save As > CSV UTF-8) and give that file")
            return f"{name} is {what}, not a text table: {todo}"
    return None


def _open_text(path, missing_hint: str = "give a path or a data set name from 'datasets.list()'"):
    """``path`` opened as text in its encoding (:func:`file_encoding`: UTF-8 with or without BOM, UTF-16 with
    BOM, else Windows-1252), refusing a FIFO or a device, a spreadsheet, an archive or a PDF (:func:`not_text`);
    errors are one line."""
    name = os.fspath(path)
    if (why := not_text(name)) is not None:
        raise DataFileError(why)
    try:
        return open_regular(name, encoding=file_encoding(name))
    except FileNotFoundError:
        raise DataFileError(f"{name}: no such file{f' ({missing_hint})' if missing_hint else ''}") from None
    except NotRegularFileError as exc:
        raise DataFileError(str(exc)) from None
    except OSError as exc:
        raise DataFileError(f"{name}: cannot be read ({exc.strerror or exc})") from None


def _too_long(name, lineno) -> DataFileError:
    return DataFileError(f"{name} line {lineno}: longer than {MAX_LINE_CHARS} characters; not a table of "
                         "measurements (is it the right file?)")


def iter_lines(fh, name):
    """(line number, line) of an open text file, each line at most :data:`MAX_LINE_CHARS` characters, its Unicode
    minus signs written as '-' (:func:`ascii_minus`)."""
    lineno = 0
    while True:
        try:
            line = fh.readline(MAX_LINE_CHARS + 1)
        except (UnicodeDecodeError, OSError) as exc:
            raise DataFileError(f"{name}: cannot be read as text ({exc})") from None
        if not line:
            return
        lineno += 1
        if len(line.rstrip("\r\n")) > MAX_LINE_CHARS:
            raise _too_long(name, lineno)
        yield lineno, ascii_minus(line)


def read_lines(path, missing_hint: str = "give a path or a data set name from 'datasets.list()'") -> list[str]:
    """The lines of a text file (without line ends), read with :func:`iter_lines`."""
    name = os.fspath(path)
    with _open_text(name, missing_hint) as fh:
        return [ln.rstrip("\r\n") for _, ln in iter_lines(fh, name)]


def check_line_lengths(path) -> None:
    """Refuse a file holding a line longer than :data:`MAX_LINE_CHARS` bytes (vectorised over 4 MiB blocks),
    before a parser that reads a whole line into memory sees it."""
    name = os.fspath(path)
    limit = (MAX_LINE_CHARS + 1) * CODE_UNIT_BYTES.get(file_encoding(name), 1)   # bytes; + 1: a CR before the LF
    with _open_text(name) as text:
        fh = text.buffer
        lineno, run = 1, 0
        while True:
            block = fh.read(1 << 22)
            if not block:
                return
            a = np.frombuffer(block, dtype=np.uint8)
            nl = np.flatnonzero(a == 10)
            if nl.size == 0:
                run += a.size
                if run > limit:
                    raise _too_long(name, lineno)
                continue
            lengths = np.diff(nl, prepend=-1) - 1
            lengths[0] += run
            long = np.flatnonzero(lengths > limit)
            if long.size:
                raise _too_long(name, lineno + int(long[0]))
            lineno += nl.size
            run = a.size - 1 - int(nl[-1])
            if run > limit:
                raise _too_long(name, lineno)


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


#: units a header may carry, to their canonical names
LENGTH_UNITS = {"nm": "nm", "µm": "µm", "um": "µm", "micron": "µm", "microns": "µm", "mm": "mm", "m": "m",
                "in": "in", "inch": "in"}
ANGLE_UNITS = {"deg": "deg", "degree": "deg", "degrees": "deg", "°": "deg", "rad": "rad", "radian": "rad",
               "radians": "rad"}
#: what a column is, by its header key (lower case; spaces, '_', '-' and '.' removed; unit taken off)
ROLES = {"x": "x", "y": "y", "z": "z",
         **dict.fromkeys(("angle", "theta", "phi", "winkel", "sampleangle", "angularposition", "polarangle"), "angle"),
         **dict.fromkeys(("deviation", "radialdeviation", "dr", "deltar", "error", "radialerror", "raddev",
                          "radialdev", "dev", "abweichung", "abw", "radialabweichung", "radiusdeviation", "radialdisplacement"), "deviation"),
         **dict.fromkeys(("radius", "r", "radialposition"), "radius"),
         **dict.fromkeys(("direction", "dir", "run", "pass", "richtung"), "direction")}


def parse_name(name: str) -> tuple[str, str | None]:
    """(key, unit) of a header name: the unit in ``()``, ``[]`` or ``{}``, after ``/``, or as a ``_um``-style suffix
    (``Radial deviation (um)``, ``angle[deg]``, ``dr/µm``, ``radial_deviation_um`` -> ``radialdeviation``,
    ``µm``); the key in lower case without spaces, ``_``, ``-`` or ``.``. The unit is canonical (``µm``,
    ``deg``) when fitbench knows it, else as written."""
    n = str(name).strip().lower().replace("μ", "µ")
    unit = None
    m = re.fullmatch(r"(.*?)\s*[(\[{]\s*([^)\]}]*?)\s*[)\]}]", n) or re.fullmatch(r"(.*?)\s*/\s*([^/\s]+)", n)
    if m and m.group(1):
        n, unit = m.group(1), m.group(2)
    else:
        m = re.fullmatch(r"(.*?)[\s_\-]+([a-zµ°]+)", n)
        if m and m.group(1) and (m.group(2) in LENGTH_UNITS or m.group(2) in ANGLE_UNITS):
            n, unit = m.group(1), m.group(2)
    key = re.sub(r"[\s_\-.]+", "", n)
    if unit is not None:
        unit = LENGTH_UNITS.get(unit, ANGLE_UNITS.get(unit, unit))
    return key, unit


def column_unit(layout, k: int, kind: str) -> str | None:
    """The unit the header gives column ``k`` ('length' or 'angle'), None when it gives none; a unit of the
    other kind or an unknown one is refused in one line."""
    if not layout.header:
        return None
    key, unit = parse_name(layout.header[k])
    if unit is None:
        if re.search(r"[\[\](){}<>|µμ°]", key):   # a unit fitbench cannot take apart: never read the column as mm
            raise DataFileError(f"{layout.name}: cannot tell the unit of column {layout.header[k]!r}; write it as "
                                "'NAME [UNIT]' (x [µm])")
        return None
    known = LENGTH_UNITS if kind == "length" else ANGLE_UNITS
    if unit in known.values():
        return unit
    want = "a length unit (nm, µm, mm, m, in)" if kind == "length" else "an angle unit (deg, rad)"
    raise DataFileError(f"{layout.name}: column {layout.header[k]!r} carries the unit {unit!r}; expected {want}")


def length_unit(layout, idx, unit: str | None) -> str:
    """The length unit of the columns ``idx``: the header's, the declared ``unit`` (--unit), or mm. A header
    unit that contradicts ``unit``, or two columns in different units, is an error."""
    found = {layout.header[k]: column_unit(layout, k, "length") for k in idx} if layout.header else {}
    given = {c: u for c, u in found.items() if u is not None}
    if len(set(given.values())) > 1:
        raise DataFileError(f"{layout.name}: the columns {', '.join(given)} are in different units "
                            f"({', '.join(sorted(set(given.values())))}); convert them to one unit")
    header = next(iter(given.values()), None)
    if unit is not None and header is not None and canonical(unit) != header:
        col = next(iter(given))
        raise DataFileError(f"{layout.name}: the header says column {col!r} is in {header} but --unit says "
                            f"{canonical(unit)}; drop --unit or correct the header")
    return header or (canonical(unit) if unit is not None else "mm")


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

    def fields(self) -> list[tuple[str, str | None]]:
        """(key, unit) of each header name (:func:`parse_name`); [] without a header."""
        return [parse_name(h) for h in self.header] if self.header else []


def sniff(path, skip_rows: int = 0) -> Layout:
    """Read at most the first ``SNIFF_LINES`` lines: separator, decimal comma, header, comment style."""
    name = os.fspath(path)
    if skip_rows < 0:
        raise DataFileError(f"{name}: --skip-rows must be >= 0, got {skip_rows}")
    fh = _open_text(name)
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
        return Layout(name, sep, decimal_comma, None, 0, body[0][0], len(head), comment, preamble, body)
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
        lineno, ln = body[1]
        k = len(_split(ln, sep))
        raise DataFileError(f"{name} line {lineno}: {k} field{'s' if k != 1 else ''} where the header (line "
                            f"{body[0][0]}) has {len(head)}: {ln!r}{preamble_hint(name, body[0][0])}")
    decimal_comma = _marks(name, body[1:], sep, decimal_comma)
    return Layout(name, sep, decimal_comma, head, body[0][0], body[1][0], len(head), comment, preamble, body[1:],
                  units_line)


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


def _names_above(skip_rows: int) -> str:
    """The advice for a header of units read after ``skip_rows`` skipped lines: skip one line fewer."""
    if not skip_rows:
        return ""
    return ("; if the names are on the line above, drop --skip-rows" if skip_rows == 1 else
            f"; if the names are on the line above, give --skip-rows {skip_rows - 1}")


#: units a units row or a header may name that fitbench does not read: refused by name, never taken as a column
OTHER_UNITS = {"cm", "dm", "km", "mil", "mils", "thou", "ft", "gon", "grad", "mrad", "µrad", "urad", "arcsec", "arcmin",
               "ms", "min", "%", "ppm", "µm/m", "um/m", "mm/min", "°c", "hz"}


def _unit_word(token: str) -> str | None:
    """The unit a field of a units row names (``µm``, ``[mm]``, ``(deg)``), canonical when fitbench reads it,
    else as written when it is a unit it does not read (:data:`OTHER_UNITS`); None when it is no unit."""
    t = str(token).strip().lower().replace("μ", "µ")
    t = re.sub(r"^[\[({]\s*(.*?)\s*[\])}]$", r"\1", t)
    return LENGTH_UNITS.get(t, ANGLE_UNITS.get(t, t if t in OTHER_UNITS else None))


def _units_row(tokens) -> list | None:
    """The units of a units row (``µm;µm``, ``;deg;µm``: one per field, None for an empty field), or None when
    ``tokens`` is not one (every non-empty field a unit, at least one)."""
    units = [_unit_word(t) if t.strip() else None for t in tokens]
    if not any(units) or any(u is None and t.strip() for u, t in zip(units, tokens)):
        return None
    return units


def _with_units(name, header: list, units: list, lineno: int) -> list:
    """The header names with the units of the units row under them (line ``lineno``) as ``NAME [UNIT]``; a name
    that carries another unit already is refused."""
    if len(units) > len(header):
        raise DataFileError(f"{name} line {lineno}: a units row of {len(units)} fields under a header of "
                            f"{len(header)}; give one unit per column")
    out = list(header)
    for k, u in enumerate(units):
        if u is None:
            continue
        had = parse_name(header[k])[1]
        if had is not None and had != u:
            raise DataFileError(f"{name} line {lineno}: the units row says {u} for column {header[k]!r}, whose name "
                                f"says {had}; correct one of them")
        if had is None:
            out[k] = f"{header[k]} [{u}]"
    return out


def _diagnose(layout: Layout, idx, skip_rows: int):
    """Locate the first bad line (runs only after the fast parser failed)."""
    name = layout.name
    for lineno, ln in enumerate(read_lines(name), start=1):
        ln = ln.strip()
        if lineno < layout.first_data_line or not ln or ln.startswith(COMMENT_PREFIXES):
            continue
        if "\x00" in ln:
            raise DataFileError(f"{name} line {lineno}: holds NUL bytes, so it is not a text table; if it is UTF-16 or "
                                "UTF-32 text, save it as UTF-8 (or with a byte-order mark)")
        toks = _split(ln, layout.sep)
        if len(toks) != layout.ncol:
            where = f"the header (line {layout.header_line})" if layout.header else "the first line"
            raise DataFileError(f"{name} line {lineno}: {len(toks)} field{'s' if len(toks) != 1 else ''} where {where} "
                                f"has {layout.ncol}: {ln!r}{skip_rows_hint(layout, before=lineno)}")
        for j in idx:
            tok = toks[j].replace(",", ".") if layout.decimal_comma else toks[j]
            if not _is_number(tok) or (layout.decimal_comma and "." in toks[j]):
                why = number_problem(toks[j], layout.decimal_comma)
                if why:
                    raise NumberFormatError(f"{name} line {lineno}: {why}")
                raise DataFileError(f"{name} line {lineno}: {toks[j]!r} is not a number"
                                    f"{skip_rows_hint(layout, before=lineno)}")
            if not np.isfinite(_number(tok)):
                raise DataFileError(f"{name} line {lineno}: {toks[j]!r} is not a finite number; remove or repair the point")
    raise DataFileError(f"{name}: could not be parsed (unexpected format); use one row of numbers per line")


def _field_number(token: str, decimal_comma: bool) -> float:
    """A field as a number of the grammar, its comma read as the decimal mark in a file of decimal commas (where
    a decimal point is refused: one mark per file, :func:`decimal_marks`); ValueError otherwise."""
    if decimal_comma:
        if "." in token:
            raise ValueError(token)
        token = token.replace(",", ".")
    return _number(token)


def unterminated_last_line(path) -> tuple[int, str] | None:
    """(line number, text) of the last line of ``path`` when the file does not end with a line end (LF or CR),
    else None. Reads the last byte; only a file without a final line end is read again, counting its lines
    over 4 MiB blocks (UTF-16/32 files are decoded)."""
    name = os.fspath(path)
    enc = file_encoding(name)
    if enc in CODE_UNIT_BYTES:
        last = None
        with _open_text(name) as fh:
            for last in iter_lines(fh, name):
                pass
        return None if last is None or last[1].endswith(("\n", "\r")) else (last[0], last[1])
    lf = cr = 0
    tail = b""
    with open_regular(name, encoding=None) as fh:
        size = fh.seek(0, os.SEEK_END)
        fh.seek(max(size - 1, 0))
        if fh.read(1) in (b"", b"\n", b"\r"):
            return None                          # the usual case: ends with a line end, no pass over the file
        fh.seek(0)
        while block := fh.read(1 << 22):
            lf += block.count(b"\n")
            cr += block.count(b"\r")
            tail = (tail + block)[-(4 * MAX_LINE_CHARS):]
    if not tail or tail.endswith((b"\n", b"\r")):
        return None
    text = ascii_minus(re.split(r"\r\n|\r|\n", tail.decode(enc, errors="replace"))[-1])
    return (lf if lf else cr) + 1, text


def _decimals(token: str) -> int | None:
    """Digits after the decimal mark ('.' or ',') of a number written without an exponent (0 without a mark);
    None for anything else."""
    t = token.strip()
    if not re.fullmatch(r"[+-]?[0-9]*(?:[.,][0-9]*)?", t) or not re.search(r"[0-9]", t):
        return None
    return len(re.split(r"[.,]", t, maxsplit=1)[1]) if re.search(r"[.,]", t) else 0


#: a column's numbers compared with a last line that has no line end (at least this many, all alike)
CUT_REFERENCE_ROWS = 3


def refuse_cut_last_line(name, last, rows, columns) -> None:
    """Refuse a file whose last line has no line end (``last``: its line number and fields, or None) and, in
    one of ``columns``, fewer digits after the decimal mark than every other number of that column in ``rows``
    (token lists of the file's first data lines): the file was cut in the middle of that number (an interrupted
    copy, transfer or export). An exporter writes a column with a fixed number of decimals; the last number alone
    with fewer, where the file stops without a line end, is a cut and not a measurement: reading it would move
    the figures (one cut circular-test point tripled G). A last line without a line end whose numbers look like
    the others' is read."""
    if last is None:
        return
    lineno, text = last
    cut = None
    for k in columns:
        ref = {_decimals(r[k]) for r in rows if k < len(r)}
        if len(rows) < CUT_REFERENCE_ROWS or len(ref) != 1:
            continue
        want = ref.pop()
        got = _decimals(text[k]) if k < len(text) else None
        if want is not None and got is not None and got < want:
            cut = (text[k], got, want)
            break
    if cut is not None:
        raise DataFileError(f"{name} line {lineno}: the file ends without a line end in {cut[0]!r}, which has {cut[1]} "
                            f"digit(s) after the decimal mark where the column's other numbers have {cut[2]}: the "
                            "file looks cut (truncated); copy or export it again, or delete that line")


def _check_last_line(layout: Layout, idx) -> None:
    """:func:`refuse_cut_last_line` for a file read by :func:`read_columns` (the reference: the sniffed data rows)."""
    last = unterminated_last_line(layout.name)
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
    for lineno, raw in enumerate(read_lines(layout.name), start=1):
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
    check_line_lengths(layout.name)
    dtype = {k: (object if k in strings else np.float64) for k in usecols}

    def parse(usecols=usecols, *, decimal="," if layout.decimal_comma else ".", thousands=None, minus=False):
        """The columns ``usecols`` by pandas' C parser (``minus``: from a stream writing U+2212 as '-')."""
        try:
            with contextlib.ExitStack() as stack:
                source = _AsciiMinus(stack.enter_context(_open_text(layout.name))) if minus else layout.name
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
    if not ok and _holds_unicode_minus(layout.name):   # parsed again, its minus signs in ASCII
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
    for lineno, raw in enumerate(read_lines(layout.name), start=1):
        ln = raw.split(layout.comment, 1)[0].strip()
        if lineno < layout.first_data_line or not ln:
            continue
        toks = _split(ln, layout.sep)
        if len(toks) == layout.ncol:
            out.append((lineno, [toks[k] for k in columns]))
    return out


def _holds_unicode_minus(path) -> bool:
    """Whether the text of ``path`` holds a Unicode minus sign (U+2212), read in blocks of 4 Mi characters."""
    with _open_text(path) as fh:
        while block := fh.read(1 << 22):
            if "\u2212" in block:
                return True
    return False


@dataclass
class Resolved:
    """Which columns of a file hold what: ``kind`` 'xy' (idx: the two coordinates) or 'polar' (idx: angle,
    then the radial deviation or the radius, ``polar_value``); ``direction``: the run column or None."""

    kind: str
    idx: list
    polar_value: str | None = None
    direction: int | None = None


def resolve(layout: Layout, columns=None, plane: str | None = None) -> Resolved:
    """The instrument layout of a file, decided by its header where it can (:data:`ROLES`, :func:`parse_name`):
    angle + radial deviation (or radius) when the header names both, else x, y (``plane`` picks its named
    pair). ``columns`` names any layout's two columns (header names, case and spaces ignored, or 0-based
    numbers); an angle among them makes the file polar. A header that names an angle is never read as x, y."""
    name = layout.name
    roles = [ROLES.get(k) for k, _ in layout.fields()]
    d_col = roles.index("direction") if "direction" in roles else None
    if columns is not None and tuple(str(c).strip().lower() for c in columns) == ("x", "y") and \
            not ("x" in roles and "y" in roles):
        columns = None  # the default pair, absent from the header: decide by the header
    if plane is not None:
        if plane.lower() not in PLANES:
            raise DataFileError(f"unknown plane {plane!r}; use one of {', '.join(PLANES)}")
        return Resolved("xy", layout.index(PLANES[plane.lower()]), None, d_col)
    if columns is not None:
        idx = layout.index(columns)
        if len(idx) != 2 or idx[0] == idx[1]:
            raise DataFileError(f"{name}: give two different columns, got {tuple(columns)!r}")
        r = [roles[k] for k in idx] if roles else [None, None]
        if "angle" in r:
            if r[1] == "angle":
                idx, r = idx[::-1], r[::-1]
            return Resolved("polar", idx, "radius" if r[1] == "radius" else "deviation", d_col)
        return Resolved("xy", idx, None, d_col)
    if layout.header is None:
        if layout.ncol != 2:
            raise DataFileError(f"{name} line {layout.first_data_line}: {layout.ncol} columns and no header; "
                                "add a header line naming the x and y columns (or --columns 0 1)")
        return Resolved("xy", [0, 1])
    a = roles.index("angle") if "angle" in roles else None
    v = next((roles.index(r) for r in ("deviation", "radius") if r in roles), None)
    if a is not None and v is not None:
        return Resolved("polar", [a, v], roles[v], d_col)
    if "x" in roles and "y" in roles and "z" in roles:
        raise DataFileError(_which_plane(layout, [roles.index(c) for c in "xyz"]))
    if "x" in roles and "y" in roles:
        return Resolved("xy", [roles.index("x"), roles.index("y")], None, d_col)
    if a is not None:
        raise DataFileError(f"{name}: the column {layout.header[a]!r} is an angle but no radial deviation or radius "
                            f"column was found (columns: {', '.join(layout.header)}); name it e.g. 'radial deviation "
                            "(um)' or give --columns ANGLE DEVIATION")
    if len(layout.header) < 2:
        raise DataFileError(f"{name} line {layout.header_line}: header has fewer than two columns"
                            f"{skip_rows_hint(layout)}")
    others = [k for k in range(layout.ncol) if k != d_col]
    if len(others) == 2:
        return Resolved("xy", others, None, d_col)
    raise DataFileError(f"{name}: which two columns? the header has {', '.join(layout.header)}; "
                        f"give --columns NAME NAME or --plane xy|yz|zx{skip_rows_hint(layout)}")


def _which_plane(layout: Layout, idx: list) -> str:
    """The refusal of a file with x, y and z columns and no choice: a CMM, tracker or 3-D ballbar export of a
    circle in any plane. Names the columns, the spread of each in the first data lines (:attr:`Layout.sample`)
    and the ``--plane`` of the two that spread most; reading x, y of a ZX-plane circle gave a 3.77 km radius."""
    names = ", ".join(layout.header[k] for k in idx)
    hint = ""
    rows = [_split(ln.split(layout.comment, 1)[0].strip(), layout.sep) for _, ln in layout.sample]
    try:
        vals = np.array([[_field_number(r[k], layout.decimal_comma) for k in idx] for r in rows if len(r) == layout.ncol],
                        dtype=float)
    except (ValueError, IndexError, InvalidInputError):
        vals = np.empty((0, 3))
    if len(vals) >= 3 and np.isfinite(vals).all():
        spread = np.ptp(vals, axis=0)
        flat = int(np.argmin(spread))
        plane = {0: "yz", 1: "zx", 2: "xy"}[flat]
        hint = (f"; in its first {len(vals)} data lines {', '.join(f'{c} spans {v:.6g}' for c, v in zip('xyz', spread))}"
                f" (the file's unit): the points lie in the {plane.upper()} plane, give --plane {plane}")
    return (f"{layout.name}: the header has three coordinate columns ({names}); which plane is the circle in? give "
            f"--plane xy|yz|zx or --columns A B (fitbench does not guess){hint}")


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
    return preamble_hint(layout.name, layout.header_line, before)


def preamble_hint(name, header_line: int = 1, before: int | None = None) -> str:
    """:func:`skip_rows_hint` for the file ``name`` whose header was taken from line ``header_line``: the hint
    when the first data row (:func:`_numeric_fields`; a direction or run label allowed) lies below the line
    after that header (and after line ``before``, the line an error names), else ''."""
    previous = None
    name = os.fspath(name)
    try:
        with _open_text(name) as fh:
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


def angle_unit_of(layout: Layout, k: int, angle_unit: str | None) -> str:
    """'deg' or 'rad' for the angle column ``k``: the header's unit or ``angle_unit`` (--angle-unit); a
    contradiction, or neither, is an error."""
    header = column_unit(layout, k, "angle")
    if angle_unit is not None and angle_unit not in ("deg", "rad"):
        raise DataFileError(f"--angle-unit must be deg or rad, got {angle_unit!r}")
    if header is not None and angle_unit is not None and header != angle_unit:
        raise DataFileError(f"{layout.name}: the header says column {layout.header[k]!r} is in {header} but "
                            f"--angle-unit says {angle_unit}; drop --angle-unit or correct the header")
    au = header or angle_unit
    if au is None:
        raise DataFileError(f"{layout.name}: is the angle column {layout.header[k] if layout.header else k!r} in "
                            "degrees or radians? name it 'angle [deg]' / 'angle [rad]' or give --angle-unit deg|rad")
    return au


#: deviations alone (no nominal radius) are placed about a radius this many times their span: the circle's
#: curvature then changes the RON parameters by about 1 / this factor (the limaçon approximation of
#: roundness instruments, ISO 12181-1 clause 3)
DEVIATION_ALONE_RADIUS_FACTOR = 1e6


def polar_to_points(angles_rad, values_mm, polar_value: str, nominal_radius: float | None,
                    nominal_center=(0.0, 0.0), name: str = "data") -> tuple[np.ndarray, str | None]:
    """Angle + radial deviation (about ``nominal_radius``) or radius, as x, y about ``nominal_center`` (mm),
    and a note when the deviations had no nominal radius. A radius (nominal + deviation) <= 0 is refused: the
    point would be placed on the opposite side of the centre and every form figure would be wrong."""
    note = None
    if polar_value == "radius":
        r = values_mm
    else:
        if nominal_radius is None:
            span = float(np.ptp(values_mm)) if values_mm.size else 0.0
            nominal_radius = max(DEVIATION_ALONE_RADIUS_FACTOR * span, 1.0)
            note = (f"radial deviations without a nominal radius: placed about a circle of {nominal_radius:.6g} mm "
                    f"({DEVIATION_ALONE_RADIUS_FACTOR:g} x their span; form parameters as an instrument's limaçon "
                    "evaluation; centre and radius are not the part's)")
        r = float(nominal_radius) + values_mm
    bad = np.flatnonzero(~(r > 0))
    if bad.size:
        k = int(np.argmin(r))
        if polar_value == "radius":
            raise DataFileError(f"{name}: a radius of {r[k]:.6g} mm (point {k + 1}); radii must be > 0")
        raise DataFileError(f"{name}: the nominal radius {float(nominal_radius):g} mm + the radial deviation "
                            f"{values_mm[k] * 1e3:.6g} µm (point {k + 1}) is {r[k]:.6g} mm <= 0; give the part's "
                            "nominal radius in mm (--nominal-radius)")
    cx, cy = (float(v) for v in nominal_center)
    return np.column_stack([cx + r * np.cos(angles_rad), cy + r * np.sin(angles_rad)]), note


#: radial deviations (of an angle + deviation file) read as mm because neither the header nor ``--unit`` gives a
#: unit, beyond which µm is the likelier unit: roundness and ballbar traces deviate by tens of µm, and an
#: instrument exporting µm without a unit (±0.8 µm read as ±0.8 mm) would turn RONt or G into mm
ASSUMED_DEVIATION_LIMIT_MM = 0.1


def _unit_assumed(layout: Layout, k: int, values) -> str:
    """The note saying a unit-less deviation column was read as mm; a :class:`~methods.units.UnitWarning` too
    when its deviations exceed :data:`ASSUMED_DEVIATION_LIMIT_MM` (the likely unit and the options named)."""
    from methods.units import UnitWarning
    col = repr(layout.header[k]) if layout.header else f"{k} (0-based)"
    v = np.abs(np.asarray(values, dtype=float))
    largest = float(np.max(v[np.isfinite(v)])) if np.isfinite(v).any() else 0.0
    if largest > ASSUMED_DEVIATION_LIMIT_MM:
        warnings.warn(f"radial deviations up to {largest:.6g} mm in {layout.name} (read as mm: the column {col} names "
                      f"no unit) are implausible for a circular test or a roundness trace (tens of µm); is the deviation "
                      f"column in µm? (--unit um), or give --unit mm to keep mm", UnitWarning, stacklevel=4)
    return f"the deviation column {col} names no unit: read as mm (give --unit um if it is in µm)"


@dataclass
class CircularRuns:
    """The runs read from one file: a list of (label, (N, 2) points in mm, in the file's order)."""

    runs: list
    source: str
    kind: str          # 'xy' or 'polar'
    unit: str
    notes: list = field(default_factory=list)
    angle_unit: str | None = None
    axes: tuple = ("x", "y")   # names of the two coordinates: the header's names of x, y columns, else x, y
    unit_assumed: bool = False  # no unit in the header nor given: ``unit`` is mm by default


def _axes(layout: Layout, res: Resolved) -> tuple:
    """Names of the two coordinates read: the header's keys of an x, y layout (``z``, ``x`` for a z-x plane),
    else ``x``, ``y`` (angle + deviation files are placed in an x, y plane; header-less files have no names)."""
    keys = [k for k, _ in layout.fields()]
    if res.kind != "xy" or not keys:
        return ("x", "y")
    return tuple(keys[i] or f"column {i}" for i in res.idx)


def read_runs(path, *, columns=None, plane=None, unit: str | None = None, skip_rows: int = 0,
              angle_unit: str | None = None, nominal_radius: float | None = None, nominal_center=(0.0, 0.0),
              need_nominal_radius: bool = True) -> CircularRuns:
    """One measurement file in any instrument layout (:func:`resolve`): x, y columns or angle + radial
    deviation / radius, holding one run or both directions (a ``direction`` or ``run`` column; rows of each
    run in the order measured). Lengths in the header's unit or ``unit`` (a contradiction is an error),
    returned in mm; angle + deviation are placed about ``nominal_center`` with ``nominal_radius`` (mm; with
    ``need_nominal_radius`` false the deviations alone are evaluated, :func:`polar_to_points`).

    The angle + deviation layout follows what ballbar and roundness software lists as its data (sample angle
    and radial deviation per point, e.g. the Renishaw Ballbar 20 "data" view and its text export); we found
    no public specification of those exports, so the column names accepted are ours (:data:`ROLES`;
    confidence: low for byte-for-byte compatibility, high for the content)."""
    layout = sniff(path, skip_rows)
    name = layout.name
    res = resolve(layout, columns, plane)
    notes = []
    au = None
    if res.kind == "polar":
        au = angle_unit_of(layout, res.idx[0], angle_unit)
        if nominal_radius is None and need_nominal_radius and res.polar_value == "deviation":
            raise DataFileError(f"{name}: an angle + radial-deviation file needs --nominal-radius to place the points")
        lu = length_unit(layout, [res.idx[1]], unit)
        assumed = unit is None and column_unit(layout, res.idx[1], "length") is None
    else:
        lu = length_unit(layout, res.idx, unit)
        assumed = unit is None and all(column_unit(layout, k, "length") is None for k in res.idx)
    strings = (res.direction,) if res.direction is not None else ()
    cols = read_columns(layout, res.idx, skip_rows=skip_rows, strings=strings)
    f = to_mm(1.0, lu)
    if res.kind == "polar":
        ang = cols[res.idx[0]] if au == "rad" else np.radians(cols[res.idx[0]])
        if assumed and res.polar_value == "deviation":
            notes.append(_unit_assumed(layout, res.idx[1], cols[res.idx[1]]))
        pts, note = polar_to_points(ang, cols[res.idx[1]] * f, res.polar_value, nominal_radius, nominal_center,
                                    name=name)
        if note:
            notes.append(note)
    else:
        pts = np.empty((len(cols[res.idx[0]]), 2), dtype=np.float64)
        pts[:, 0], pts[:, 1] = cols[res.idx[0]], cols[res.idx[1]]
        if f != 1.0:
            pts *= f
    axes = _axes(layout, res)
    if res.direction is None:
        return CircularRuns([("file", pts)], name, res.kind, lu, notes, au, axes, assumed)
    labels = pd.Series(cols[res.direction]).astype(str).str.strip()
    runs = []
    for lab in pd.unique(labels):
        mask = (labels == lab).to_numpy()
        low = lab.lower()
        tag = "cw" if low in CW_WORDS else "ccw" if low in CCW_WORDS else lab
        runs.append((tag, pts[mask]))
    if len(runs) > 2:
        raise DataFileError(f"{name}: {len(runs)} runs in the direction/run column ({', '.join(l for l, _ in runs)}); "
                            "a circular test has two (CW and CCW)")
    return CircularRuns(runs, name, res.kind, lu,
                        notes + [f"{len(runs)} run(s) read from the column {layout.header[res.direction]!r}"], au, axes,
                        assumed)


def read_profile(path, *, columns=None, plane=None, unit: str | None = None, skip_rows: int = 0,
                 angle_unit: str | None = None, nominal_radius: float | None = None) -> CircularRuns:
    """One closed profile (roundness, a fit) in any instrument layout (:func:`read_runs`); deviations without
    ``nominal_radius`` are evaluated alone. A file holding two runs is refused (one profile is needed)."""
    got = read_runs(path, columns=columns, plane=plane, unit=unit, skip_rows=skip_rows, angle_unit=angle_unit,
                    nominal_radius=nominal_radius, need_nominal_radius=False)
    if len(got.runs) != 1:
        raise DataFileError(f"{got.source}: holds {len(got.runs)} runs ({', '.join(l for l, _ in got.runs)}); "
                            "give a file with one profile")
    return got


def points_unit(path, columns=None, *, plane: str | None = None, unit: str | None = None,
                skip_rows: int = 0) -> str:
    """The length unit :func:`read_points` reads ``path`` in (the header's, ``unit``, or mm)."""
    layout = sniff(path, skip_rows)
    return length_unit(layout, _xy(layout, columns, plane).idx, unit)


def _xy(layout: Layout, columns, plane) -> Resolved:
    """:func:`resolve` for a reader of x, y: an angle + deviation file is refused in one line."""
    res = resolve(layout, columns, plane)
    if res.kind == "polar":
        raise DataFileError(f"{layout.name}: holds an angle ({layout.header[res.idx[0]] if layout.header else res.idx[0]!r}) "
                            "and a radial deviation, not x, y; this command needs x, y columns")
    return res


def read_points(path, columns=None, *, plane: str | None = None, unit: str | None = None,
                skip_rows: int = 0) -> np.ndarray:
    """Read an (N, 2) float array of x, y (mm) from a text file.

    ``columns``: two header names (case and spaces ignored; units in the header allowed) or 0-based
    indices (default: x, y from the header); ``plane`` ('xy', 'yz', 'zx') picks the named columns of that plane.
    Without a header the file must have exactly two columns (or ``columns`` as indices); with a header lacking
    the names, the first two columns are used only when the file has exactly two, else the error lists the
    columns; a header naming x, y and z needs ``plane`` or ``columns`` (:func:`_which_plane`). A file whose
    header names an angle is refused (it is not x, y; :func:`read_profile` reads it). ``unit``: the file's
    length unit (default: the header's, else mm; a contradiction with the header is an error)."""
    layout = sniff(path, skip_rows)
    res = _xy(layout, columns, plane)
    lu = length_unit(layout, res.idx, unit)
    cols = read_columns(layout, res.idx, skip_rows=skip_rows)
    out = np.empty((len(cols[res.idx[0]]), 2), dtype=np.float64)
    out[:, 0], out[:, 1] = cols[res.idx[0]], cols[res.idx[1]]
    if lu != "mm":
        out *= to_mm(1.0, lu)
    return out


CW_WORDS = {"cw", "g02", "g2", "clockwise", "-", "-1"}
CCW_WORDS = {"ccw", "g03", "g3", "counterclockwise", "counter-clockwise", "anticlockwise", "+", "+1", "1"}


# ------------------------------------------------------------------ tables with named columns
TARGET_NAMES = ("target", "position", "target position", "target [mm]", "target (mm)", "target position (mm)",
                "target position [mm]", "position [mm]", "position (mm)", "nominal", "soll", "sollposition")
RUN_COLUMN = re.compile(r"^\s*(?:run|lauf|messung|r)?\s*[_#.]?\s*(\d+)\s*[_\s(\[]*"
                  r"(\+|-|up|down|u|d|fwd|rev|forward|reverse|pos|neg|↑|↓|hin|rück|rueck)?\s*[)\]]?\s*(?:\[.*\]|\(.*\))?\s*$",
                  re.IGNORECASE)



def read_table(path, *, no_data_hint: str = "", keep_default_na: bool = True, skip_rows: int = 0):
    """A delimited text table with a header (separator and decimal comma as :func:`sniff` decides; blank and
    comment lines skipped; ``skip_rows`` preamble lines dropped; decimal commas turned into points) as a
    DataFrame of strings, with the file's line number of each data row. Errors are one line."""
    import io

    if skip_rows < 0:
        raise DataFileError(f"--skip-rows must be >= 0, got {skip_rows}")
    kept, lines = [], []
    all_lines = read_lines(path, "")
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
        raise DataFileError(f"{path}: malformed table ({str(exc).splitlines()[0]})") from None
    units = _units_row(df.iloc[0].fillna("").astype(str).tolist()) if len(df) else None
    if units is not None:                     # a units row under the header: into the names, as NAME [UNIT]
        df.columns = _with_units(path, [str(c) for c in df.columns], units, lines[1])
        df, lines = df.iloc[1:].reset_index(drop=True), lines[:1] + lines[2:]
        if not len(df):
            raise DataFileError(f"{path}: no data lines{f' ({no_data_hint})' if no_data_hint else ''}")
    cells = df.fillna("").astype(str).apply(lambda c: c.str.strip()).values.tolist()
    marks = decimal_marks(path, zip(lines[1:], cells))
    decimal_comma = decimal_comma if marks is None else marks
    last = unterminated_last_line(path)
    if last is not None and last[0] == lines[-1]:
        refuse_cut_last_line(path, (last[0], cells[-1]), cells[:-1][:SNIFF_LINES], range(len(df.columns)))
    if decimal_comma:
        df = df.apply(lambda col: col.str.replace(r"^\s*([+-]?[0-9]*),([0-9]+(?:[eE][+-]?[0-9]+)?)\s*$", r"\1.\2",
                                                  regex=True)
                      if pd.api.types.is_string_dtype(col) or col.dtype == object else col)
    return df, lines[1:]


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


def _wide_to_long(df: pd.DataFrame, name: str, lines) -> tuple[pd.DataFrame, np.ndarray] | None:
    """A wide export (one column per run) as the long table; None when ``df`` is not wide."""
    cols = [str(c).strip() for c in df.columns]
    low = [c.lower() for c in cols]
    t = next((low.index(n) for n in TARGET_NAMES if n in low), None)
    if t is None or "run" in low:
        return None
    d_col = low.index("direction") if "direction" in low else None
    runs = {}
    for k, c in enumerate(cols):
        if k in (t, d_col):
            continue
        m = RUN_COLUMN.match(c)
        if not m:
            raise DataFileError(f"{name}: column {c!r} is neither the target, a direction nor a run "
                                    "(wide layout: target, run 1 +, run 1 -, ... or target, direction, run 1, run 2, ...)")
        runs[k] = (int(m.group(1)), m.group(2))
    if not runs:
        return None
    # 'Forward'/'Reverse' ('Hin'/'Rück') are the laser software's run order, not the axis direction (ISO 230-2: ↑ is
    # an approach in the + direction): the forward runs pass the targets in the order the file lists them
    from methods.positioning.data import RUN_ORDER_TAGS, RunOrderNote
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
                    f"{'increasing' if forward == '+' else 'decreasing'} ({targets[0]:g} to {targets[-1]:g} in the file's "
                    f"unit), so the forward runs are read as approaches in the {'+ (↑)' if forward == '+' else '− (↓)'} direction and "
                    f"the reverse runs as {'− (↓)' if forward == '+' else '+ (↑)'} (--forward-direction "
                    f"{'-' if forward == '+' else '+'} if the forward runs moved the other way)")
        warnings.warn(RunOrderNote(text, forward), stacklevel=4)
    other = {"+": "-", "-": "+"}
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
        else:
            # no direction anywhere: a unidirectional test approached in the + direction
            direction = np.full(len(df), "+" if tag is None or tag.lower() in ("+", "up", "u", "pos", "↑") else "-")
        rows.append(pd.DataFrame({"target": df.iloc[:, t].to_numpy(), "direction": direction, "run": run,
                                  "deviation": df.iloc[:, k].to_numpy(), "_line": lines}))
    long = pd.concat(rows, ignore_index=True)
    return long.drop(columns="_line"), long["_line"].to_numpy()



def _header_unit(found: dict, given: str | None, option: str, name) -> str | None:
    """The one unit the header gives columns ``found`` ({column: unit}), checked against the option's value."""
    units = set(found.values())
    if len(units) > 1:
        raise DataFileError(f"{name}: the columns {', '.join(found)} are in different units "
                            f"({', '.join(sorted(units))}); convert them to one unit")
    header = units.pop() if units else None
    if header is not None and header not in LENGTH_UNITS.values():
        raise DataFileError(f"{name}: column {next(iter(found))!r} carries the unit {header!r}; expected a length "
                            "unit (nm, µm, mm, m, in)")
    if header is not None and given is not None and canonical(given) != header:
        raise DataFileError(f"{name}: the header says column {next(iter(found))!r} is in {header} but {option} says "
                            f"{canonical(given)}; drop {option} or correct the header")
    return header or (canonical(given) if given is not None else None)


def read_positioning(path, *, unit: str | None = None, deviation_unit: str | None = None, skip_rows: int = 0,
                     with_units: bool = False):
    """An ISO 230-2 positioning file, long or wide layout (:mod:`methods.positioning.data` describes them), as
    :class:`methods.positioning.PositioningData`. Header names are read like every reader's (:func:`parse_name`:
    ``Target (mm)``, ``Deviation [µm]``, ``Run 1 + (um)``); lengths are converted to mm from the header's units,
    else ``unit`` (targets, actual positions; default mm) and ``deviation_unit`` (deviations; default the
    targets' unit); a header unit contradicting them is an error. ``with_units``: also return the two units."""
    try:
        return _read_positioning(path, unit=unit, deviation_unit=deviation_unit, skip_rows=skip_rows,
                                 with_units=with_units)
    except InvalidInputError as exc:
        _add_preamble_hint(exc, path, skip_rows)
        raise


def _add_preamble_hint(exc: InvalidInputError, path, skip_rows: int) -> None:
    """Append :func:`preamble_hint` to the message of ``exc`` (a file read without --skip-rows whose data
    rows start below a preamble: its first line was taken as the header)."""
    if skip_rows == 0 and len(exc.args) == 1 and "--skip-rows" not in str(exc.args[0]) and \
            not isinstance(exc, NumberFormatError):
        hint = preamble_hint(path)
        if hint:
            exc.args = (f"{exc.args[0]}{hint}",)


def _read_positioning(path, *, unit, deviation_unit, skip_rows, with_units):
    from methods.positioning import from_frame

    # 'nan' and 'inf' stay text here and are refused as not finite by _numeric_column, like every reader
    df, lines = read_table(path, skip_rows=skip_rows, keep_default_na=False)
    empty = (df.isna() | df.apply(lambda c: c.astype(str).str.strip() == "")).any(axis=1).to_numpy()
    if empty.any():
        k = int(np.flatnonzero(empty)[0])
        raise DataFileError(f"{path} line {lines[k]}: missing field(s)")
    lines = np.array(lines)
    target_keys = {parse_name(n)[0] for n in TARGET_NAMES}
    renamed, lengths, deviations = {}, {}, {}
    for c in df.columns:
        key, u = parse_name(c)
        role = key if key in ("target", "direction", "run", "deviation", "actual") else \
            "target" if key in target_keys else None
        if role is not None and role not in renamed.values():
            renamed[c] = role
        if u is not None and role in ("target", "actual"):
            lengths[str(c)] = u
        elif u is not None and (role == "deviation" or (role is None and RUN_COLUMN.match(str(c)))):
            deviations[str(c)] = u
    unit = _header_unit(lengths, unit, "--unit", path) or "mm"
    deviation_unit = _header_unit(deviations, deviation_unit, "--deviation-unit", path) or unit
    df = df.rename(columns=renamed)
    wide = _wide_to_long(df, str(path), lines)
    if wide is not None:
        df, lines = wide
    cols = {str(c).lower().strip(): c for c in df.columns}
    for key in ("target", "run", "deviation", "actual"):
        if key in cols:
            df[cols[key]] = _numeric_column(df[cols[key]], key, path, lines)
    data = from_frame(df, str(path), lines=lines, unit=unit, deviation_unit=deviation_unit)
    return (data, unit, deviation_unit) if with_units else data


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
                raise DataFileError(f"{path}: column {str(c).strip()!r} carries the unit {u!r}; expected a length unit "
                                    "(nm, µm, mm, m, in)")
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
