"""The rows of a run as one DataFrame in task order, gathered from columnar parts.

A worker turns the rows of its chunk into a *part* (:func:`part_of`: one NumPy array per column, of the type a
Series of the column would have, the task index of each row, where each column first appears), so the run's process never holds a row's values as Python objects;
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
    if not rows:
        return _part(rows, {})
    names = tuple(rows[0])
    if all(tuple(row) == names for row in rows):  # the same columns in the same order (a chunk of results): transposed
        columns = list(zip(*[row.values() for row in rows]))
        types = [set(map(type, column)) for column in columns]
        if not all(t <= PLAIN for t in types):
            return None
        at = dict(zip(names, zip(columns, types)))
        index, kinds = at.pop("task_index", (None, None))
        if index is None or kinds != {int}:  # a row made outside a run (no task index): no place in a frame
            return None
        return _shipped(np.array(index, dtype=np.int64), dict.fromkeys(at, 0),
                        {name: _series(column, kinds) for name, (column, kinds) in at.items()})
    first: dict = {}
    plain = PLAIN
    for pos, row in enumerate(rows):
        if type(row.get("task_index")) is not int:
            return None
        for name, value in row.items():
            if type(value) not in plain:
                return None
            if name not in first:
                first[name] = pos
    first.pop("task_index", None)
    return _part(rows, first)


def _part(rows: list[dict], first: dict) -> dict:
    nan = float("nan")
    return _columns(np.array([r["task_index"] for r in rows], dtype=np.int64), first,
                    {name: [r.get(name, nan) for r in rows] for name in first})


def _columns(index: np.ndarray, first: dict, values: dict) -> dict:
    import pandas as pd
    return _shipped(index, first, {name: pd.Series(column) for name, column in values.items()})


def _shipped(index: np.ndarray, first: dict, series: dict) -> dict:
    """A part as it travels from a worker: each column as a NumPy array, float64 and int64 as they are, any other
    type as an object array of the Series' values, and the names of the columns whose Series was of pandas' text type
    (a pickled Series cost 0.35 ms to unpickle whatever its length: 4 us a row in the run's process)."""
    import pandas as pd
    columns, texts = {}, []
    for name, col in series.items():
        if type(col) is np.ndarray:  # made without a Series (:func:`_series`)
            columns[name] = col if col.dtype in DENSE else col.astype(object)
        elif col.dtype in DENSE:
            columns[name] = col.to_numpy()
        else:
            columns[name] = col.to_numpy(dtype=object)
            if isinstance(col.dtype, pd.StringDtype):
                texts.append(name)
    return {"task_index": index,
            "first": first,  # column -> position of the first row that has it (dict order: first appearance)
            "columns": columns, "texts": texts}


_DTYPE_OF = {float: np.float64, bool: np.bool_}


def _series(values: tuple, kinds: set):
    """``pd.Series(list(values))``, or for a column of one number type (``kinds``: the types of its values) the NumPy
    array of that Series, made without pandas' inference (the same dtype and values)."""
    import pandas as pd
    if len(kinds) == 1:
        (kind,) = kinds
        if kind in _DTYPE_OF:
            return np.array(values, dtype=_DTYPE_OF[kind])
        if kind is int:
            try:
                return np.array(values, dtype=np.int64)
            except OverflowError:  # beyond 64 bits: pandas' own choice (uint64 or object)
                pass
    return pd.Series(list(values))


#: column types written into a column's number array (every other type goes to its object array)
DENSE = (np.dtype(np.float64), np.dtype(np.int64))
#: a column's text is shared across chunks (one object per distinct value) while its distinct values are at most
#: :data:`SHARE_RATIO` of its rows (or fewer than :data:`SHARE_MIN`); a column of mostly distinct text (the seed
#: stream's label) is shared within each chunk only, so that no table of its values is kept
SHARE_MIN, SHARE_RATIO = 4096, 0.25


class RowFrame:
    """The rows of a run of ``n_rows`` tasks, gathered as chunks arrive. Each column is held in arrays of ``n_rows``
    values written at the rows' task indices, with a mask of the rows that have it: float64 and int64 values in a
    number array, every other value (text, booleans, None) in an object array, so no chunk's Series is kept and a
    task whose row arrives twice keeps the columns of its last row. Equal texts are stored as one object (a row's
    message or label was its own string: 10^5 rows of one certificate message held 10^5 copies of it)."""

    def __init__(self, n_rows: int):
        self.n = n_rows
        self.arrived = np.zeros(n_rows, dtype=bool)
        self.numbers: dict = {}   # column -> (float64/int64 values, bool: the row has a number there)
        self.objects: dict = {}   # column -> (object values, bool: the row has an object there)
        self.shared: dict = {}    # column -> {text: the one object of it} (None: shared within each chunk only)
        self.counted: dict = {}   # column -> rows of it written as objects so far
        self.first: dict = {}     # column -> (task index, rank) of the first row that has it: the column order

    def add(self, part: dict) -> None:
        index = np.asarray(part["task_index"], dtype=np.int64)
        if not len(index):
            return
        if index.min() < 0 or index.max() >= self.n:
            raise ValueError(f"a row's task index is outside 0..{self.n - 1}")
        for rank, (name, pos) in enumerate(part["first"].items()):
            at = (int(index[pos]), rank)
            if name not in self.first or at < self.first[name]:
                self.first[name] = at
        again = index[self.arrived[index]]
        if len(again):  # rows delivered before: the columns of their earlier row no longer count
            for held in (self.numbers, self.objects):
                for _, present in held.values():
                    present[again] = False
        self.arrived[index] = True
        texts = part["texts"]
        for name, values in part["columns"].items():
            if values.dtype in DENSE:
                self._numbers(name, index, values)
            else:
                self._objects(name, index, values, name in texts)

    def _numbers(self, name: str, index, values) -> None:
        held = self.numbers.get(name)
        if held is None:
            held = self.numbers[name] = (np.empty(self.n, dtype=values.dtype), np.zeros(self.n, dtype=bool))
        elif held[0].dtype != values.dtype and held[0].dtype == np.int64:  # ints meet floats: float64, as pd.concat
            held = self.numbers[name] = (held[0].astype(np.float64), held[1])
        held[0][index] = values
        held[1][index] = True

    def _objects(self, name: str, index, values, text: bool) -> None:
        held = self.objects.get(name)
        if held is None:
            held = self.objects[name] = (np.empty(self.n, dtype=object), np.zeros(self.n, dtype=bool))
        held[0][index] = self._one_object_per_text(name, values, text)
        held[1][index] = True

    def _one_object_per_text(self, name: str, array, text: bool):
        """The object array ``array`` (the part's own: written into) with equal texts as one object (see
        :data:`SHARE_RATIO`); ``text``: the column was of pandas' text type in its part."""
        import pandas as pd
        if not (text or pd.api.types.infer_dtype(array, skipna=True) == "string"):
            return array  # numbers, booleans, None among them: left as they are (True == 1 to a hash table)
        codes, uniques = pd.factorize(array)  # a missing value (None, NaN) has code -1 and stays as it is
        seen = self.shared.setdefault(name, {})
        self.counted[name] = self.counted.get(name, 0) + len(array)
        if seen is not None:
            uniques = [seen.setdefault(text, text) for text in uniques.tolist()]
            if len(seen) > max(SHARE_MIN, SHARE_RATIO * self.counted[name]):
                self.shared[name] = None
        one = np.empty(len(uniques), dtype=object)
        one[:] = uniques
        known = codes >= 0
        if known.all():
            return one[codes]
        array[known] = one[codes[known]]
        return array

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
        missing = int((~self.arrived).sum())
        if missing:
            raise MissingRows(missing)
        self.shared.clear()
        out = {}
        for name in sorted(self.first, key=self.first.__getitem__):
            col = self._column(name)
            out[name] = _numbers_if_numbers(col) if col.dtype == object else col
        return pd.DataFrame(out, copy=False) if out else pd.DataFrame(index=range(self.n))

    def _column(self, name: str):
        import pandas as pd
        nan = float("nan")
        values, present = self.numbers.pop(name, (None, None))
        objects, has = self.objects.pop(name, (None, None))
        if objects is not None and not has.any():
            objects = None  # every row that had an object there arrived again without it
        if objects is None:  # numbers only: as pd.concat of the chunks and a NaN filler for the rows without them
            if values is None:
                return pd.Series(np.full(self.n, nan))
            if values.dtype == np.int64 and present.all():
                return pd.Series(values)
            col = values.astype(np.float64, copy=False)
            col[~present] = nan
            return pd.Series(col)
        if values is not None and not present.any():
            values = None
        if values is None:  # no numbers: the objects, typed as one Series of them all (DataFrame(rows) does the same)
            objects[~has] = nan
            return pd.Series(objects.tolist())
        if pd.isna(objects[has]).all():  # numbers and missing values: float64 with NaN
            col = values.astype(np.float64, copy=False)
            col[~present] = nan
            return pd.Series(col)
        col = np.full(self.n, nan, dtype=object)  # numbers and other values (text, booleans): an object column
        col[present] = values[present].astype(object)
        col[has] = objects[has]
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
