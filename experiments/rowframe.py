"""The rows of a run as one DataFrame in task order, gathered from columnar parts.

A worker turns the rows of its chunk into a *part* (:func:`part_of`: one Series per column, the task index of
each row, where each column first appears), so the run's process never holds a row's values as Python objects;
it writes each part's numbers into the frame's arrays as the chunk arrives and keeps its other columns
(:class:`RowFrame`), joined at the end in task order, whatever order the chunks finished in. The rows served from
the row store (cached) are decoded into parts of their own.

The frame equals ``DataFrame(rows)`` of all rows in task order (``tests/test_engine.py``): the columns in the
order they first appear, a row without a column NaN, and the column types of one frame of all rows (a column of
numbers and None is float64, ints among floats are floats). A row's values in a part are the plain scalars JSON
gives back (the row store holds the same rows as JSON): a chunk with any other value (a list, a dict) has no part,
and its JSON text is decoded instead.
"""
from __future__ import annotations

import numpy as np

from methods import InvalidInputError

#: the value types a part carries as they are: exactly those JSON gives back unchanged
PLAIN = frozenset({str, int, float, bool, type(None)})


def part_of(rows: list[dict]) -> dict | None:
    """The columns of ``rows`` (each carries its ``task_index``), or None when a value is not a plain scalar."""
    first: dict = {}
    plain = PLAIN
    for pos, row in enumerate(rows):
        if type(row.get("task_index")) is not int:  # a row made outside a run (no task index): no place in a frame
            return None
        for name, value in row.items():
            if type(value) not in plain:
                return None
            if name not in first:
                first[name] = pos
    first.pop("task_index", None)
    return _part(rows, first)


def _part(rows: list[dict], first: dict) -> dict:
    import pandas as pd
    nan = float("nan")
    return {"task_index": np.array([r["task_index"] for r in rows], dtype=np.int64),
            "first": first,  # column -> position of the first row that has it (dict order: first appearance)
            "columns": {name: pd.Series([r.get(name, nan) for r in rows]) for name in first}}


#: column types written straight into the run's frame as chunks arrive (every other type is kept as the chunk's Series)
DENSE = (np.dtype(np.float64), np.dtype(np.int64))


class RowFrame:
    """The rows of a run of ``n_rows`` tasks, gathered as chunks arrive: a float64 or int64 column of a chunk is written
    into one array of ``n_rows`` values at its rows' task indices (no copy of the rows is kept besides the frame's
    own); other columns (text, booleans, Nones) are kept as the chunks' Series, joined into blocks of at least
    :attr:`block` rows, until :meth:`frame` joins them in task order. A task whose row arrives twice keeps the
    columns of its last row."""

    block = 5000

    def __init__(self, n_rows: int):
        self.n = n_rows
        self.seq = np.full(n_rows, -1, dtype=np.int64)  # the chunk that delivered each row last (-1: none yet)
        self.chunks = 0
        self.dense: dict = {}     # column -> (values, present): float64/int64 values, bool: the row has them
        self.pieces: dict = {}    # column -> [(task indices, chunk of each row, Series)]
        self.pending: dict = {}   # column -> rows in its small pieces not yet joined into a block
        self.first: dict = {}     # column -> (task index, rank) of the first row that has it: the column order

    def add(self, part: dict) -> None:
        index = np.asarray(part["task_index"], dtype=np.int64)
        if not len(index):
            return
        if index.min() < 0 or index.max() >= self.n:
            raise ValueError(f"a row's task index is outside 0..{self.n - 1}")
        chunk = self.chunks
        self.chunks += 1
        for rank, (name, pos) in enumerate(part["first"].items()):
            at = (int(index[pos]), rank)
            if name not in self.first or at < self.first[name]:
                self.first[name] = at
        again = index[self.seq[index] >= 0]
        if len(again):  # rows delivered before: the columns of their earlier row no longer count
            for _, present in self.dense.values():
                present[again] = False
        self.seq[index] = chunk
        for name, values in part["columns"].items():
            if values.dtype in DENSE:
                self._write(name, index, values.to_numpy())
            else:
                pieces = self.pieces.setdefault(name, [])
                pieces.append((index, np.full(len(index), chunk, dtype=np.int64), values))
                self.pending[name] = self.pending.get(name, 0) + len(index)
                if self.pending[name] >= self.block:
                    self._join(name)

    def _write(self, name: str, index, values) -> None:
        held = self.dense.get(name)
        if held is None:
            held = self.dense[name] = (np.empty(self.n, dtype=values.dtype), np.zeros(self.n, dtype=bool))
        elif held[0].dtype != values.dtype and held[0].dtype == np.int64:  # ints meet floats: float64, as pd.concat
            held = self.dense[name] = (held[0].astype(np.float64), held[1])
        held[0][index] = values
        held[1][index] = True

    def _join(self, name: str) -> None:
        """Join a column's small pieces (a slow study's one-row chunks) into one piece."""
        import pandas as pd
        pieces, small = self.pieces[name], self.pending.pop(name, 0)
        n, k = 0, len(pieces)
        while k > 0 and n < small:
            k -= 1
            n += len(pieces[k][0])
        tail = pieces[k:]
        if len(tail) > 1:
            pieces[k:] = [(np.concatenate([p[0] for p in tail]), np.concatenate([p[1] for p in tail]),
                           pd.concat([p[2] for p in tail], ignore_index=True))]

    def add_rows(self, rows: list[dict]) -> None:
        """Rows decoded from JSON (the row store's, or a chunk that came without a part)."""
        part = part_of(rows)
        if part is None:  # JSON gives back plain scalars, lists and dicts: a list or dict column stays as it is
            part = _any_part(rows)
        self.add(part)

    def frame(self):
        """All rows in task order, each column of the type one ``DataFrame`` of all rows would give it; refused
        unless every task has its row."""
        import pandas as pd
        missing = int((self.seq < 0).sum())
        if missing:
            raise MissingRows(missing)
        out = {}
        for name in sorted(self.first, key=self.first.__getitem__):
            col = self._column(name)
            out[name] = _numbers_if_numbers(col) if col.dtype == object else col
        self.dense.clear()
        self.pieces.clear()
        return pd.DataFrame(out, copy=False) if out else pd.DataFrame(index=range(self.n))

    def _column(self, name: str):
        import pandas as pd
        nan = float("nan")
        values, present = self.dense.pop(name, (None, None))
        kept = []  # the pieces of the rows' last chunks
        for index, chunk, piece in self.pieces.pop(name, []):
            current = self.seq[index] == chunk
            if current.all():
                kept.append((index, piece))
            elif current.any():
                kept.append((index[current], piece[current]))
        covered = present.copy() if present is not None else np.zeros(self.n, dtype=bool)
        for index, _ in kept:
            covered[index] = True
        absent = ~covered
        if values is None and not kept:  # every row that had it arrived again without it
            return pd.Series(np.full(self.n, nan))
        if not kept:  # numbers only: as pd.concat of the pieces and a NaN filler for the rows without the column
            if values.dtype == np.int64 and not absent.any():
                return pd.Series(values)
            col = values.astype(np.float64, copy=False)
            col[absent] = nan
            return pd.Series(col)
        if values is None:  # no numbers: the pieces (and the filler) joined, then put in task order
            if absent.any():
                rows = np.flatnonzero(absent)
                kept.append((rows, pd.Series([nan] * len(rows))))
            index = np.concatenate([i for i, _ in kept])
            col = kept[0][1] if len(kept) == 1 else pd.concat([p for _, p in kept], ignore_index=True)
            order = np.argsort(index, kind="stable")
            if (order != np.arange(len(order))).any():
                col = col.take(order)
            return col.reset_index(drop=True)
        if all(piece.isna().all() for _, piece in kept):  # numbers and missing values: float64 with NaN
            col = values.astype(np.float64, copy=False)
            col[~present] = nan
            return pd.Series(col)
        col = np.full(self.n, nan, dtype=object)  # numbers and other values (text, booleans): an object column
        col[present] = values[present].astype(object)
        for index, piece in kept:
            col[index] = piece.to_numpy(dtype=object)
        return pd.Series(col, dtype=object)


class MissingRows(InvalidInputError):
    """Rows of a run that no chunk delivered (one line; the next run computes them)."""

    def __init__(self, missing: int):
        super().__init__(f"{missing} rows are missing from the row store after the run; run the same command again "
                         f"(the stored rows are kept)")


def _any_part(rows: list[dict]) -> dict:
    first: dict = {}
    for pos, row in enumerate(rows):
        for name in row:
            first.setdefault(name, pos)
    first.pop("task_index", None)
    return _part(rows, first)


def _numbers_if_numbers(col):
    """An object column of numbers and None/NaN, as DataFrame(rows) makes it: float64 (ints too)."""
    import pandas as pd
    non_null = col.dropna()
    if len(non_null) and len(non_null) < len(col) and non_null.map(type).isin([float, int]).all():
        return pd.to_numeric(col)
    return col
