"""A file's bytes as lines of text, before any table is seen.

The encoding (:func:`file_encoding`): UTF-32 or UTF-16 with a byte-order mark or without one (a table saved as
"Unicode"), UTF-8 with or without a BOM, else Windows-1252 (the ANSI code page of Windows exports, with an
:class:`EncodingNote`) or Latin-1. A spreadsheet, an archive, a PDF or an image is refused by its first bytes
(:data:`NOT_TEXT`, :func:`not_text`: an Excel 97-2003 OLE2 workbook, an ``.xlsx``/``.ods`` zip), XML, HTML and JSON
(fitbench's own ``--json`` results among them) by their first characters (:func:`markup`); only regular files
are opened (a FIFO or a device is refused without blocking, :func:`methods.files.open_regular`); no line may exceed
:data:`MAX_LINE_CHARS` (:func:`iter_lines`, :func:`check_line_lengths`); a last line without a line end cut in its
number is refused (:func:`unterminated_last_line`, :func:`refuse_cut_last_line`)."""
from __future__ import annotations

import codecs
import io
import os
import re
import warnings

import numpy as np

from datasets.io.numbers import DataFileError, ascii_minus
from methods import InvalidInputError
from methods.files import NotRegularFileError, open_regular


#: longest line read (characters): a measurement table's line is far shorter; /dev/zero-like content is refused
MAX_LINE_CHARS = 1 << 16


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


def not_text(path, skip_rows: int = 0) -> str | None:
    """What is wrong when ``path`` is a spreadsheet, an archive, a PDF or an image rather than a text table (its
    first bytes, :data:`NOT_TEXT`): 'x.xlsx is an Excel workbook (a zip archive), not a text table: save it as
    CSV ...', or XML, HTML or JSON (:func:`markup`, below the ``skip_rows`` lines --skip-rows skips); None for
    anything else (also when it cannot be opened: the reader then says why)."""
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
    return markup(name, skip_rows)


#: characters of a file's start read to tell XML or JSON (:func:`markup`)
MARKUP_HEAD_CHARS = 4096
#: JSON files up to this size (bytes) are parsed to tell a JSON value from a table starting with '[' (an INI-like
#: '[General]' preamble) or '{' (a '{Probe 3}' preamble), and to recognise fitbench's own results
MARKUP_PARSE_BYTES = 16 << 20

_XML_NAME = r"[A-Za-z_][\w.:-]*"
#: an XML element's start tag: a name, attributes name="value" (or 'value'), '>' or '/>' ('<Operator: J. Smith>'
#: is none: 'J.' is no attribute)
_XML_START_TAG = re.compile(rf"<({_XML_NAME})(?:\s+{_XML_NAME}\s*=\s*(?:\"[^\"<]*\"|'[^'<]*'))*\s*(/?)>")
#: what may stand before the root element: comments, a document type declaration, processing instructions
_XML_PROLOG = re.compile(r"(?:\s+|<!--.*?-->|<!doctype[^<>\[]*(?:\[.*?\])?\s*>|<\?.*?\?>)*", re.I | re.S)
#: a large file's JSON object start, '{"name":' (or '{}'), when it is too large to be parsed
_JSON_OBJECT_START = re.compile(r'\{\s*(?:"(?:[^"\\\n]|\\.)*"\s*:|\})')


def _xml_root(head: str) -> str | None:
    """The root element's name when ``head`` (a file's start, without leading blanks) is markup: an XML declaration,
    or (after comments, a doctype, processing instructions) a start tag that closes and is followed by another tag
    or by text and its own end tag; else None (a table whose first line is '<Operator: J. Smith>' or '<Probe 3>')."""
    if re.match(r"<\?xml[\s?]", head, re.I):
        root = re.search(rf"<({_XML_NAME})", re.sub(r"<\?.*?\?>|<!--.*?-->|<!.*?>", "", head, flags=re.S))
        return root.group(1) if root else ""
    rest = head[_XML_PROLOG.match(head).end():]
    tag = _XML_START_TAG.match(rest)
    if not tag:
        return None
    after = rest[tag.end():]
    if re.match(rf"\s*<(?:/?{_XML_NAME}|!--)", after) or \
            (not tag.group(2) and re.match(rf"[^<]*</{re.escape(tag.group(1))}\s*>", after)):
        return tag.group(1)
    return None


def _markup_preamble_hint(head: str, skip_rows: int) -> str:
    """'; if line 1 is a preamble above a table, give --skip-rows 1' when only the first lines of ``head`` are markup
    (no '<' below them: '<Operator>J. Smith</Operator>' above a CSV table), else ''."""
    lines = head.splitlines()
    k = next((i for i, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("<")), None)
    if k is None or "<" in "\n".join(lines[k:]):
        return ""
    first = int(skip_rows) + 1
    where = f"line {first} is" if k == 1 else f"lines {first}-{first + k - 1} are"
    return f"; if {where} a preamble above a table, give --skip-rows {int(skip_rows) + k}"


def markup(path, skip_rows: int = 0) -> str | None:
    """What is wrong when ``path`` is XML (or HTML) or JSON rather than a text table, from its first characters in
    its encoding below the ``skip_rows`` lines --skip-rows skips (a skipped line is never refused): 'test.b5r is an
    XML file (root <BallbarTest>: an instrument's own format?), not a text table: export ...', 'r.json is JSON (a
    fitbench result ...)'; None for anything else. XML only when the start looks like markup (:func:`_xml_root`),
    JSON only when it parses as JSON (a table's preamble may start with '<', '{' or '[')."""
    import json
    name = os.fspath(path)
    try:
        with open_regular(name, encoding=file_encoding(name)) as fh:
            for _ in range(max(int(skip_rows), 0)):
                if not fh.readline(MAX_LINE_CHARS + 1):
                    break
            head = fh.read(MARKUP_HEAD_CHARS)
            rest = (head + fh.read()) if head.lstrip("\ufeff \t\r\n")[:1] in ("{", "[") and \
                os.path.getsize(name) <= MARKUP_PARSE_BYTES else None
    except (OSError, InvalidInputError, UnicodeDecodeError, ValueError):
        return None
    raw, head = head.lstrip("\ufeff"), head.lstrip("\ufeff \t\r\n")
    if head.startswith("<"):
        if re.match(r"<(!doctype\s+html|html[\s>])", head, re.I):
            return (f"{name} is an HTML page, not a text table: save the measurement file itself (not the web page "
                    "showing it) as CSV or text")
        root = _xml_root(head)
        if root is None:
            return None
        what = f"root <{root}>: " if root else ""
        return (f"{name} is an XML file ({what}an instrument's own format?), not a text table: export the measured "
                "points as CSV or text from the instrument software (one point per line, columns named in a header)"
                + _markup_preamble_hint(raw, skip_rows))
    if not head.startswith(("{", "[")):
        return None
    data, parsed = None, False
    if rest is not None:
        try:
            data, parsed = json.loads(rest.lstrip("\ufeff \t\r\n")), True
        except (ValueError, RecursionError):   # '[General]', '[mm]', '{Probe 3}': a preamble or header, not JSON
            return None
    elif not (head.startswith("{") and _JSON_OBJECT_START.match(head)):
        return None          # too large to parse: JSON only when it starts as a JSON object does
    if parsed and isinstance(data, dict) and isinstance(data.get("units"), dict):
        return (f"{name} is JSON (a fitbench result, as --json writes it: 'fitbench history DIR' trends a folder of "
                "them), not a points table: give the file of measured points the result was made from")
    return (f"{name} is a JSON file, not a text table: export the measured points as CSV or text (one point per "
            "line, columns named in a header)")


#: the DOS end-of-file mark (Ctrl-Z) that old instrument PCs write after a file's last line: ignored there
DOS_EOF = b"\x1a"


def text_end(path) -> int | None:
    """The size in bytes of ``path`` without the DOS end-of-file marks (:data:`DOS_EOF`) at its very end (and a line
    end after them), or None when it ends without one (or is UTF-16/32 text, or cannot be read). A Ctrl-Z anywhere else is data (refused as
    such by the readers)."""
    name = os.fspath(path)
    if file_encoding(name) in CODE_UNIT_BYTES:
        return None
    try:
        with open_regular(name, encoding=None) as fh:
            size = fh.seek(0, os.SEEK_END)
            fh.seek(max(size - 64, 0))
            tail = fh.read()
    except (OSError, InvalidInputError):
        return None
    body = tail.rstrip(b"\r\n")              # a mark alone on the last line ('\x1a\r\n', as DOS tools write it)
    if len(body) == len(body.rstrip(DOS_EOF)):
        return None
    return size - (len(tail) - len(body.rstrip(DOS_EOF)))


class _UpTo(io.RawIOBase):
    """A binary file read up to ``end`` bytes (its text before a DOS end-of-file mark)."""

    def __init__(self, raw, end: int):
        super().__init__()
        self._raw, self._left = raw, end

    def readable(self) -> bool:
        return True

    def readinto(self, b) -> int:
        n = min(len(b), self._left)
        if n <= 0:
            return 0
        got = self._raw.readinto(memoryview(b)[:n]) or 0
        self._left -= got
        return got

    def close(self) -> None:
        self._raw.close()
        super().close()


def _open_text(path, missing_hint: str = "give a path or a data set name from 'datasets.list()'", skip_rows: int = 0):
    """``path`` opened as text in its encoding (:func:`file_encoding`: UTF-8 with or without BOM, UTF-16 with
    BOM, else Windows-1252), refusing a FIFO or a device, a spreadsheet, an archive or a PDF, or XML or JSON below
    the ``skip_rows`` lines --skip-rows skips (:func:`not_text`); errors are one line. A DOS end-of-file mark
    (Ctrl-Z) at the file's end is not read (:func:`text_end`)."""
    name = os.fspath(path)
    if (why := not_text(name, skip_rows)) is not None:
        raise DataFileError(why)
    try:
        if (end := text_end(name)) is not None:
            raw = open_regular(name, encoding=None)
            return io.TextIOWrapper(io.BufferedReader(_UpTo(raw, end)), encoding=file_encoding(name))
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


def read_lines(path, missing_hint: str = "give a path or a data set name from 'datasets.list()'",
               skip_rows: int = 0) -> list[str]:
    """The lines of a text file (without line ends), read with :func:`iter_lines`; ``skip_rows``: the lines
    --skip-rows skips, never refused as markup (all lines are returned)."""
    name = os.fspath(path)
    with _open_text(name, missing_hint, skip_rows) as fh:
        return [ln.rstrip("\r\n") for _, ln in iter_lines(fh, name)]


def check_line_lengths(path, skip_rows: int = 0) -> None:
    """Refuse a file holding a line longer than :data:`MAX_LINE_CHARS` characters (code units of its encoding,
    vectorised over 4 MiB blocks), before a parser that reads a whole line into memory sees it (``skip_rows``: as
    :func:`read_lines`). Lines end as the readers' universal newlines end them: LF, CR LF or a lone CR (an old Mac
    export), in UTF-16 and UTF-32 files too (their code units are compared, not their bytes)."""
    name = os.fspath(path)
    dtype = _code_unit(name)
    limit = MAX_LINE_CHARS + 1   # code units; + 1: a CR LF's LF, counted in the next line
    with _open_text(name, skip_rows=skip_rows) as text:
        fh = text.buffer
        lineno, run, after_cr, rest = 1, 0, False, b""
        while True:
            block = rest + fh.read(1 << 22)
            cut = len(block) - len(block) % dtype.itemsize
            block, rest = block[:cut], block[cut:]
            if not block:
                return
            a = np.frombuffer(block, dtype=dtype)
            ends = (a == 10) | (a == 13)
            ends[1:] &= ~((a[1:] == 10) & (a[:-1] == 13))   # CR LF ends one line, at its CR
            if after_cr and a[0] == 10:   # the LF of a CR LF split between two blocks
                ends[0] = False
            after_cr = bool(a[-1] == 13)
            nl = np.flatnonzero(ends)
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


def _code_unit(name: str) -> np.dtype:
    """The code unit of ``name``'s encoding as a NumPy type: a byte, or UTF-16's or UTF-32's unit in the file's
    byte order (its byte-order mark, else the encoding's name)."""
    enc = file_encoding(name)
    size = CODE_UNIT_BYTES.get(enc, 1)
    if size == 1:
        return np.dtype(np.uint8)
    if enc.endswith(("-le", "-be")):
        order = "<" if enc.endswith("-le") else ">"
    else:   # the byte-order mark says
        with open(name, "rb") as fh:
            head = fh.read(size)
        order = "<" if head[:2] == b"\xff\xfe" else ">"
    return np.dtype(f"{order}u{size}")


def unterminated_last_line(path, skip_rows: int = 0) -> tuple[int, str] | None:
    """(line number, text) of the last line of ``path`` when the file does not end with a line end (LF or CR),
    else None. Reads the last byte; only a file without a final line end is read again, counting its lines
    over 4 MiB blocks (UTF-16/32 files are decoded; ``skip_rows``: as :func:`read_lines`)."""
    name = os.fspath(path)
    enc = file_encoding(name)
    if enc in CODE_UNIT_BYTES:
        last = None
        with _open_text(name, skip_rows=skip_rows) as fh:
            for last in iter_lines(fh, name):
                pass
        return None if last is None or last[1].endswith(("\n", "\r")) else (last[0], last[1])
    lf = cr = 0
    tail = b""
    end = text_end(name)   # before a DOS end-of-file mark
    with open_regular(name, encoding=None) as fh:
        size = fh.seek(0, os.SEEK_END) if end is None else end
        fh.seek(max(size - 1, 0))
        if size == 0 or fh.read(1) in (b"", b"\n", b"\r"):
            return None                          # the usual case: ends with a line end, no pass over the file
        fh.seek(0)
        while fh.tell() < size and (block := fh.read(min(1 << 22, size - fh.tell()))):
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
