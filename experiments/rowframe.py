"""The rows of a run as one DataFrame in task order, gathered from columnar parts.

A worker turns the rows of its chunk into a *part* (:func:`part_of`: one Series per column, the task index of
each row, where each column first appears), so the run's process never holds a row's values as Python objects;
it keeps the parts as they arrive (:class:`RowFrame`) and joins them once at the end, in task order, whatever
order the chunks finished in. The rows served from the row store (cached) are decoded into parts of their own.

The frame equals ``DataFrame(rows)`` of all rows in task order (``tests/test_engine.py``): the columns in the
order they first appear, a row without a column NaN, and the column types of one frame of all rows (a column of
numbers and None is float64, ints among floats are floats). A row's values in a part are the plain scalars JSON
gives back (the row store holds the same rows as JSON): a chunk with any other value (a list, a dict) has no part,
and its JSON text is decoded instead.
"""
from __future__ import annotations

import numpy as np

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


class RowFrame:
    """The parts of a run, kept as one Series per column and block of at least :attr:`block` rows (small parts, such
    as the single rows of slow studies, are joined into blocks first) until :meth:`frame` joins them in task order."""

    block = 5000

    def __init__(self):
        self.parts: list = []    # (task indices, {column: (first task index, rank)}, {column: Series})
        self.pending: list = []  # small parts, until they make a block
        self.n_pending = 0

    def add(self, part: dict) -> None:
        index = part["task_index"]
        if not len(index):
            return
        order = {name: (int(index[pos]), rank) for rank, (name, pos) in enumerate(part["first"].items())}
        self.pending.append((index, order, part["columns"]))
        self.n_pending += len(index)
        if self.n_pending >= self.block:
            self._flush()

    def add_rows(self, rows: list[dict]) -> None:
        """Rows decoded from JSON (the row store's, or a chunk that came without a part)."""
        part = part_of(rows)
        if part is None:  # JSON gives back plain scalars, lists and dicts: a list or dict column stays as it is
            part = _any_part(rows)
        self.add(part)

    def _flush(self) -> None:
        if not self.pending:
            return
        if len(self.pending) == 1:
            self.parts.append(self.pending[0])
        else:
            order: dict = {}
            for _, o, _ in self.pending:
                for name, at in o.items():
                    if name not in order or at < order[name]:
                        order[name] = at
            index = np.concatenate([idx for idx, _, _ in self.pending])
            self.parts.append((index, order, _joined([(len(idx), cols) for idx, _, cols in self.pending], order)))
        self.pending, self.n_pending = [], 0

    def frame(self, n_rows: int):
        """All rows in task order (a task run twice: its last row); refused unless there are ``n_rows``."""
        import pandas as pd
        self._flush()
        if not self.parts or not n_rows:
            if n_rows:
                raise MissingRows(n_rows)
            self.parts.clear()
            return pd.DataFrame()
        index = np.concatenate([p[0] for p in self.parts])
        if len(index) == n_rows and (np.diff(index) > 0).all() and index[0] == 0 and index[-1] == n_rows - 1:
            keep = None  # every row once, in task order (one worker): nothing to reorder
        else:
            last = np.unique(index[::-1], return_index=True)[1]  # the last occurrence of each task index ...
            keep = len(index) - 1 - last                         # ... as positions in ``index``, in task order
            present = int(((index[keep] >= 0) & (index[keep] < n_rows)).sum())
            if present != n_rows or len(keep) != n_rows:
                raise MissingRows(n_rows - present)
        first: dict = {}
        for _, order, _ in self.parts:  # a column's place: the first row (in task order) that has it
            for name, at in order.items():
                if name not in first or at < first[name]:
                    first[name] = at
        out = {}
        sized = [(len(index), cols) for index, _, cols in self.parts]
        self.parts.clear()
        for name in sorted(first, key=first.__getitem__):
            col = _column(sized, name)
            if keep is not None:
                col = col.take(keep).reset_index(drop=True)
            if col.dtype == object:
                col = _numbers_if_numbers(col)
            out[name] = col
        return pd.DataFrame(out, copy=False)


def _column(sized: list, name: str):
    """One column of consecutive parts ((rows, {column: Series}) each; a part without it: NaN), each part's piece
    freed as it is taken."""
    import pandas as pd
    pieces = [cols.pop(name) if name in cols else pd.Series([float("nan")] * n) for n, cols in sized]
    return pieces[0] if len(pieces) == 1 else pd.concat(pieces, ignore_index=True)


def _joined(sized: list, order: dict) -> dict:
    return {name: _column(sized, name) for name in order}


class MissingRows(RuntimeError):
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
