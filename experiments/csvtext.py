"""``results.csv`` text, the bytes ``DataFrame.to_csv(index=False, float_format="%.17g")`` writes, made column by
column: pandas formats each float of a float column through a Python callable with its own overhead (1.0 s of a
40,000-row study here); this formats a float64 column with one ``"%.17g" %`` per value and hands the rows to the same
:mod:`csv` writer pandas uses (minimal quoting, ``"`` doubled). Columns of another type than float64, int64, bool,
str or object go to pandas itself, so the text is always pandas' (``tests/test_engine.py`` compares the bytes).
"""
from __future__ import annotations

import csv
import os

import numpy as np


def _strings(col) -> list[str] | None:
    """The CSV text of each value of one column (a missing value: ''), or None for a dtype left to pandas."""
    kind = col.dtype
    if kind == np.float64:
        return ["" if v != v else "%.17g" % v for v in col.to_numpy().tolist()]
    if kind == np.int64:
        return list(map(str, col.to_numpy().tolist()))
    if kind == np.bool_:
        return ["True" if v else "False" for v in col.to_numpy().tolist()]
    if kind == object or str(kind) == "str":
        missing = col.isna().to_numpy().tolist()
        return ["" if m else str(v) for v, m in zip(col.to_numpy(dtype=object).tolist(), missing)]
    return None


def write_csv(df, fh, *, header: bool = True) -> None:
    """Write ``df`` to the text file ``fh`` as ``df.to_csv(fh, index=False, header=header, float_format="%.17g")``
    does, byte for byte."""
    columns = [_strings(df[c]) for c in df.columns] if df.columns.is_unique and len(df.columns) else [None]
    if any(c is None for c in columns):
        df.to_csv(fh, index=False, header=header, float_format="%.17g")
        return
    writer = csv.writer(fh, lineterminator=os.linesep, quoting=csv.QUOTE_MINIMAL)
    if header:
        writer.writerow([str(c) for c in df.columns])
    if len(df):
        writer.writerows(zip(*columns))
