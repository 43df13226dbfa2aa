"""``results.csv`` text, the bytes ``DataFrame.to_csv(index=False, float_format="%.17g")`` writes, made column by
column: pandas formats each float of a float column through a Python callable with its own overhead (1.0 s of a
40,000-row study here); this formats each row with one ``%`` (``%.17g`` for a float, ``%d`` for an int), text and
a column with missing values once per distinct value, has the :mod:`csv` writer pandas uses quote the rare text that
needs it. Columns of another
type than float64, int64, bool, str or object go to pandas itself, so the text is always pandas' (``tests/test_engine.py`` compares the bytes).
"""
from __future__ import annotations

import csv
import hashlib
import io
import os
import re

import numpy as np


def _fields(col) -> tuple[str, list] | None:
    """One column as (the ``%`` conversion of its field, its values for it): a float64 column without a missing value
    as its floats for ``%.17g``, an int64 column as its ints for ``%d``, any other as its CSV fields for ``%s`` (a
    missing value: ''; text quoted as :mod:`csv` quotes it); None for a dtype left to pandas."""
    kind = col.dtype
    if kind == np.float64:
        values = col.to_numpy()
        nan = np.isnan(values)
        if not nan.any():
            return "%.17g", values.tolist()
        return "%s", _by_distinct(values.view(np.int64), lambda v: "%.17g" % v, nan, float)  # by bits: 0.0, -0.0
    if kind == np.int64:
        return "%d", col.to_numpy().tolist()
    if kind == np.bool_:
        return "%s", ["True" if v else "False" for v in col.to_numpy().tolist()]
    if kind == object or str(kind) == "str":
        import pandas as pd
        values = col.to_numpy(dtype=object)
        missing = col.isna().to_numpy()
        if pd.api.types.infer_dtype(values, skipna=True) in ("string", "empty"):  # only texts: equal means the same
            return "%s", _by_distinct(values, _text_field, missing)
        return "%s", _quoted(["" if m else str(v) for v, m in zip(values.tolist(), missing.tolist())])
    return None


def _text_field(value) -> str:
    return _quoted([str(value)])[0]


def _by_distinct(values: np.ndarray, field, missing: np.ndarray, read=None) -> list[str]:
    """``field(v)`` of each value, '' where ``missing``, computed once per distinct value (a column repeats a few texts
    or numbers over its rows: a data set's parameters, a status, a method's message). ``values`` are compared as they
    are (floats as their bits, so that 0.0 and -0.0 stay apart) and ``read`` makes the value ``field`` takes."""
    import pandas as pd
    codes, uniques = pd.factorize(values)
    uniques = np.asarray(uniques)
    if read is float:
        uniques = uniques.view(np.float64)
    texts = [field(v) for v in uniques.tolist()] + [""]
    codes = np.where(missing, len(texts) - 1, codes)
    return [texts[c] for c in codes.tolist()]


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
    """Write ``df`` to the text file ``fh`` as ``df.to_csv(fh, index=False, header=header, float_format="%.17g")``
    does, byte for byte."""
    columns = [_fields(df[c]) for c in df.columns] if df.columns.is_unique and len(df.columns) > 1 else [None]
    if any(c is None for c in columns):  # (one column: csv quotes an empty field that is a row alone)
        df.to_csv(fh, index=False, header=header, float_format="%.17g")
        return
    end = os.linesep
    if header:
        fh.write(",".join(_quoted([str(c) for c in df.columns])) + end)
    if len(df):
        line = ",".join(spec for spec, _ in columns)  # one % per row formats all its fields
        fh.write(end.join(map(line.__mod__, zip(*(values for _, values in columns)))) + end)


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
        with atomic_path(path, make_parents=True) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
            for text in texts:
                digest.update(text.encode("utf-8"))
                fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
    finally:
        close = getattr(texts, "close", None)
        if close is not None:  # texts not read (the disk is full): their making ends
            close()
    return digest.hexdigest()
