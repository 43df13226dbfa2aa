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

The package, one module per concern; each imports only those above it in this list:

* :mod:`~datasets.io.numbers`: the number grammar, digit grouping, minus signs, one decimal mark per file; the errors
* :mod:`~datasets.io.textfile`: bytes to lines: encodings and BOMs, spreadsheets by their magic bytes, long lines,
  a last line cut in its number
* :mod:`~datasets.io.delimiters`: comment lines, separators, decimal commas, quoted fields
* :mod:`~datasets.io.headers`: header names and their units, a units row under the header
* :mod:`~datasets.io.layout`: :func:`sniff` (a file's first lines as a :class:`Layout`) and the ``--skip-rows`` hint
* :mod:`~datasets.io.roles`: :func:`resolve`: which columns hold x, y, angle, deviation, radius, direction; planes
* :mod:`~datasets.io.columns`: :func:`read_columns`: numeric columns, pandas-free for small files, else the C parser
* :mod:`~datasets.io.polar`: angle + radial deviation (or radius) to points, the angle unit
* :mod:`~datasets.io.runs`: circular-test runs and roundness profiles (:func:`read_runs`, :func:`read_profile`)
* :mod:`~datasets.io.points`: points files (:func:`read_points`)
* :mod:`~datasets.io.tables`: tables with named columns (:func:`read_table`)
* :mod:`~datasets.io.positioning`: ISO 230-2 positioning tables, long and wide (:func:`read_positioning`)
* :mod:`~datasets.io.multilateration`: multilateration lengths and stations (:func:`read_multilateration`)

(:mod:`~datasets.io._pandas`: pandas imported on first use.) Every public name is importable from
``datasets.io`` itself, as before the split.
"""
from __future__ import annotations

from datasets.io.columns import SMALL_FILE_BYTES, read_columns
from datasets.io.delimiters import COMMENT_PREFIXES, SNIFF_LINES
from datasets.io.headers import ANGLE_UNITS, LENGTH_UNITS, OTHER_UNITS, column_unit, length_unit, parse_name
from datasets.io.layout import Layout, preamble_hint, skip_rows_hint, sniff
from datasets.io.multilateration import read_multilateration
from datasets.io.numbers import (DASHES, NUMBER, DataFileError, NumberFormatError, ascii_minus, decimal_marks,
                                 number_problem)
from datasets.io.points import points_unit, read_points
from datasets.io.polar import ASSUMED_DEVIATION_LIMIT_MM, DEVIATION_ALONE_RADIUS_FACTOR, angle_unit_of, polar_to_points
from datasets.io.positioning import RUN_COLUMN, TARGET_NAMES, read_positioning
from datasets.io.roles import PLANES, ROLES, Resolved, resolve
from datasets.io.runs import CCW_WORDS, CW_WORDS, CircularRuns, read_profile, read_runs
from datasets.io.tables import read_table
from datasets.io.textfile import (CODE_UNIT_BYTES, CUT_REFERENCE_ROWS, MAX_LINE_CHARS, NOT_TEXT, ZIP_SPREADSHEETS,
                                  EncodingNote, check_line_lengths, file_encoding, iter_lines, not_text, note_encoding,
                                  read_lines, refuse_cut_last_line, unterminated_last_line)
from datasets.io.numbers import _AsciiMinus  # noqa: F401 (private; imported from datasets.io before the split)

__all__ = ["ANGLE_UNITS", "ASSUMED_DEVIATION_LIMIT_MM", "CCW_WORDS", "CODE_UNIT_BYTES", "COMMENT_PREFIXES",
           "CUT_REFERENCE_ROWS", "CW_WORDS", "DASHES", "DEVIATION_ALONE_RADIUS_FACTOR", "LENGTH_UNITS",
           "MAX_LINE_CHARS", "NOT_TEXT", "NUMBER", "OTHER_UNITS", "PLANES", "ROLES", "RUN_COLUMN", "SMALL_FILE_BYTES",
           "SNIFF_LINES", "TARGET_NAMES", "ZIP_SPREADSHEETS", "CircularRuns", "DataFileError", "EncodingNote", "Layout",
           "NumberFormatError", "Resolved", "angle_unit_of", "ascii_minus", "check_line_lengths", "column_unit",
           "decimal_marks", "file_encoding", "iter_lines", "length_unit", "not_text", "note_encoding", "number_problem",
           "parse_name", "points_unit", "polar_to_points", "preamble_hint", "read_columns", "read_lines",
           "read_multilateration", "read_points", "read_positioning", "read_profile", "read_runs", "read_table",
           "refuse_cut_last_line", "resolve", "skip_rows_hint", "sniff", "unterminated_last_line"]
