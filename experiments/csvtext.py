"""``results.csv`` text, made column by column: the bytes ``DataFrame.to_csv(index=False)`` writes, except that each
float is written as the shortest text that reads back as the same double, in JSON's number syntax (``0.00001234``,
``1.5e-7``, ``1e+16``; a whole number as an integer, ``3``), the text of the row store's rows (:mod:`orjson` writes each float column in one call: pandas'
float formatting costs 1.0 s of a 40,000-row study here, Python's ``%.17g`` 0.16 s, orjson 0.02 s). A missing value
is an empty field; a text column is formatted once per distinct value, and the :mod:`csv`
writer pandas uses quotes the rare text that needs it. Columns of another type than float64, int64, bool, str or
object go to pandas itself with the same float text (``tests/test_engine.py`` compares the bytes with pandas').
"""
from __future__ import annotations

import csv
import hashlib
import io
import os
import re

import numpy as np
import orjson


def _fields(col) -> list[str] | None:
    """One column's CSV fields: a float64 column's floats as :func:`float_texts`, an int64 column's ints as orjson
    writes them (``%d``'s text), any other's values as text (a missing value: ''; text quoted as :mod:`csv` quotes
    it); None for a dtype left to pandas."""
    kind = col.dtype
    if kind == np.float64:
        return float_texts(col.to_numpy())
    if kind == np.int64:
        values = col.to_numpy()
        return orjson.dumps(np.ascontiguousarray(values), option=orjson.OPT_SERIALIZE_NUMPY).decode()[1:-1].split(",") \
            if len(values) else []
    if kind == np.bool_:
        return ["True" if v else "False" for v in col.to_numpy().tolist()]
    if kind == object or str(kind) == "str":
        import pandas as pd
        values = col.to_numpy(dtype=object)
        missing = col.isna().to_numpy()
        if pd.api.types.infer_dtype(values, skipna=True) in ("string", "empty"):  # only texts: equal means the same
            return _by_distinct(values, _text_field, missing)
        return _quoted(["" if m else str(v) for v, m in zip(values.tolist(), missing.tolist())])
    return None


def float_texts(values: np.ndarray) -> list[str]:
    """The text of each float64 of ``values`` in ``results.csv``: the shortest that reads back as the same double, in
    JSON's syntax (orjson's, in one call for the column), a whole number without its ``.0`` (``3``, ``-0``: as ``%d``
    and ``%.17g`` write it, an iteration count of a column with missing values); a NaN is an empty field, an infinity
    pandas' ``inf``/``-inf``."""
    if not len(values):
        return []
    finite = np.isfinite(values)
    whole = bool(finite.all())
    text = orjson.dumps(np.ascontiguousarray(values if whole else np.where(finite, values, 0.0), dtype=np.float64),
                        option=orjson.OPT_SERIALIZE_NUMPY).decode()
    texts = text.replace(".0,", ",").replace(".0]", "]")[1:-1].split(",")  # a whole number as an integer: 3, not 3.0
    if not whole:
        for i in np.flatnonzero(~finite).tolist():
            v = values[i]
            texts[i] = "" if v != v else ("inf" if v > 0 else "-inf")
    return texts


def float_text(value: float) -> str:
    """:func:`float_texts` of one float (pandas' ``float_format`` for the columns left to it)."""
    return float_texts(np.array([value], dtype=np.float64))[0]


def _text_field(value) -> str:
    text = str(value)
    return _csv_field(text) if _SPECIAL.search(text) else text


def _by_distinct(values: np.ndarray, field, missing: np.ndarray) -> list[str]:
    """``field(v)`` of each value, '' where ``missing``, computed once per distinct value (a column repeats a few texts
    over its rows: a data set's parameters, a status, a method's message)."""
    texts: dict = {}
    out = []
    for v, m in zip(values.tolist(), missing.tolist()):
        if m:
            out.append("")
            continue
        text = texts.get(v)
        if text is None:
            text = texts[v] = field(v)
        out.append(text)
    return out


_SPECIAL = re.compile(r'[,"\r\n]')


def _quoted(fields: list[str]) -> list[str]:
    """Fields as the :mod:`csv` writer pandas uses writes them (``QUOTE_MINIMAL``, delimiter ``,``, quote ``"``): only
    a field holding one of those characters or a line break may need quotes, and the writer itself says how."""
    special = _SPECIAL.search
    return [_csv_field(f) if special(f) else f for f in fields]


def _csv_field(field: str) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator=os.linesep, quoting=csv.QUOTE_MINIMAL).writerow([field, ""])
    return buf.getvalue()[:-len(os.linesep) - 1]


def write_csv(df, fh, *, header: bool = True) -> None:
    """Write ``df`` to the text file ``fh`` as ``df.to_csv(fh, index=False, header=header, float_format=float_text)``
    does, byte for byte."""
    columns = [_fields(df[c]) for c in df.columns] if df.columns.is_unique and len(df.columns) > 1 else [None]
    if any(c is None for c in columns):  # (one column: csv quotes an empty field that is a row alone)
        df.to_csv(fh, index=False, header=header, float_format=float_text)
        return
    end = os.linesep
    if header:
        fh.write(",".join(_quoted([str(c) for c in df.columns])) + end)
    if len(df):
        fh.write(end.join(map(",".join, zip(*columns))) + end)


def csv_text(df, header: bool) -> str:
    """:func:`write_csv` of ``df`` as a string (a block of ``results.csv``; a worker process may make it)."""
    buf = io.StringIO()
    write_csv(df, buf, header=header)
    return buf.getvalue()


def blocks(df, rows: int = 5000):
    """The (block of rows, header?) arguments of :func:`csv_text` whose texts, one after the other, are the whole
    file."""
    for i in range(0, max(len(df), 1), rows):
        yield df.iloc[i:i + rows], i == 0


def write_results(df, path, texts=None) -> str:
    """``df`` as ``results.csv`` (:func:`write_csv`), streamed a block at a time into a temporary file that replaces
    ``path`` at the end (atomic); return the SHA-256 of the bytes written. ``texts``: the blocks' texts in order, made
    elsewhere (the idle worker processes of the run); by default they are made here."""
    from methods.files import atomic_path
    digest = hashlib.sha256()
    if texts is None:
        texts = (csv_text(*args) for args in blocks(df))
    try:
        with atomic_path(path, make_parents=True) as tmp, open(tmp, "wb") as fh:
            for text in texts:
                data = text.encode("utf-8", "backslashreplace")   # (a row's text is writable: experiments.rows)
                digest.update(data)
                fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
    finally:
        close = getattr(texts, "close", None)
        if close is not None:  # texts not read (the disk is full): their making ends
            close()
    return digest.hexdigest()
