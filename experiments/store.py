"""The row store: finished rows by cache key in SQLite, a committed transaction per batch of rows.

A store that is not a row store (garbage, a truncated file, a wrong table, rows that are not JSON objects) is
moved aside and recomputed; a store that cannot be *written* (disk full, an I/O error, a file-size limit,
a read-only folder) is left where it is, untouched, and the run stops with one line (:class:`StoreIOError`):
its rows are healthy and a later run uses them.
"""
from __future__ import annotations

import json
import os
import sqlite3
import time
from pathlib import Path
from urllib.parse import quote

from methods import InvalidInputError

#: sqlite messages of a store that is not readable as a row store (everything else is the environment's)
_CORRUPT = ("file is not a database", "malformed", "integrity check", "table 'rows' has columns", "not json",
            "not a json object")


class StoreIOError(InvalidInputError):
    """The row store cannot be written or read for a reason of the environment (disk full, I/O error,
    permissions); the store itself is healthy and kept."""


def _io_error(path: Path, exc: Exception) -> StoreIOError:
    text = str(exc)
    if "full" in text or getattr(exc, "errno", None) == 28:
        why = "the disk is full"
    elif getattr(exc, "errno", None) == 27:
        why = "the file-size limit is reached (ulimit -f)"
    elif "readonly" in text or "read-only" in text:
        why = "it is read-only"
    elif "locked" in text:
        why = "another process holds it locked"
    else:
        why = "an I/O error"
    return StoreIOError(f"cannot write the row store {path}: {why} ({text}); its finished rows are kept, "
                        f"free the space or fix the cause and run the same command again")


def _is_corruption(exc: Exception) -> bool:
    if isinstance(exc, (ValueError, TypeError)):
        return True
    text = str(exc).lower()
    return any(s in text for s in _CORRUPT)


#: the page size of a new row store (bytes)
PAGE_BYTES = 16384


class RowStore:
    """Finished rows by cache key in SQLite: one committed transaction per batch (atomic, crash-safe)."""

    def __init__(self, path: Path, log=print):
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        try:
            self.db = self._open(path)
        except sqlite3.DatabaseError as exc:
            if not _is_corruption(exc):  # disk full, I/O error, permissions: the store is not to blame
                raise _io_error(path, exc) from None
            stamp, n = time.strftime('%Y%m%dT%H%M%S'), 0
            aside = path.with_name(f"{path.name}.corrupt-{stamp}")
            while aside.exists():
                n += 1
                aside = path.with_name(f"{path.name}.corrupt-{stamp}-{n}")
            for suffix in ("", "-wal", "-shm"):
                src = Path(str(path) + suffix)
                if src.exists():
                    os.replace(src, Path(str(aside) + suffix))
            log(f"   {path} is not a readable row store ({exc}); moved aside to {aside.name}, its rows are recomputed")
            try:
                self.db = self._open(path)
            except sqlite3.DatabaseError as exc2:
                raise _io_error(path, exc2) from None

    @staticmethod
    def _open(path: Path) -> sqlite3.Connection:
        db = sqlite3.connect(path)
        try:
            # pages of 16 KiB (a new store; an existing one keeps its own): a row is about 700 bytes of JSON, and
            # 40,000 rows were stored in 0.11 s instead of 0.16 s with SQLite's default of 4 KiB (fewer B-tree pages
            # to split and write to the log)
            db.execute(f"PRAGMA page_size={PAGE_BYTES}")
            db.execute("PRAGMA journal_mode=WAL")
            # WAL without fsync: a commit is in the operating system's hands at once, so it survives a crash or
            # a kill of the program (not a power cut: the store is a cache). An fsync per chunk cost 10-30 ms.
            db.execute("PRAGMA synchronous=OFF")
            db.execute("CREATE TABLE IF NOT EXISTS rows (key TEXT PRIMARY KEY, status TEXT, row TEXT)")
            # which studies' rows the store holds whole (RowStore.complete); a change of the rows by any program
            # forgets it: an update or a delete through these triggers, an insert (or a replace, which inserts)
            # by the largest rowid it leaves behind (no trigger on inserts: it cost 2.5 us a row)
            db.execute("CREATE TABLE IF NOT EXISTS complete (fingerprint TEXT PRIMARY KEY, n_rows INTEGER, "
                       "last_rowid INTEGER)")
            for event in ("UPDATE", "DELETE"):
                db.execute(f"CREATE TRIGGER IF NOT EXISTS rows_{event.lower()} AFTER {event} ON rows "
                           "BEGIN DELETE FROM complete; END")
            db.commit()
            check = db.execute("PRAGMA quick_check").fetchone()[0]
            if check != "ok":
                raise sqlite3.DatabaseError(f"integrity check: {check}")
            cols = [r[1] for r in db.execute("PRAGMA table_info(rows)")]
            if cols != ["key", "status", "row"]:
                raise sqlite3.DatabaseError(f"table 'rows' has columns {cols}, not key, status, row")
            # SQLite checks in C that each row is JSON and starts with '{' (an object; the 40,000 rows of a study in
            # about 30 ms); what it doubts (NaN, Infinity, another value than an object) Python decodes: a row must be
            # a JSON object (a stored list or number failed the decoding of every later run)
            try:
                doubtful = db.execute("SELECT row FROM rows WHERE NOT json_valid(row) OR substr(row, 1, 1) <> '{'")
            except sqlite3.OperationalError as exc:  # an SQLite without JSON functions
                if "no such function" not in str(exc):
                    raise
                doubtful = db.execute("SELECT row FROM rows")
            for (text,) in doubtful:
                if not isinstance(json.loads(text), dict):
                    raise ValueError(f"a row is {text[:40]!r}, not a JSON object")
        except (ValueError, TypeError) as exc:
            db.close()
            what = str(exc) if "not a JSON object" in str(exc) else f"a row is not JSON: {exc}"
            raise sqlite3.DatabaseError(what) from None
        except sqlite3.DatabaseError:
            db.close()
            raise
        return db

    def _guard(self, func, *args):
        try:
            return func(*args)
        except sqlite3.DatabaseError as exc:
            if _is_corruption(exc):
                raise
            raise _io_error(self.path, exc) from None

    def empty(self) -> bool:
        """Whether the store holds no row (a new one: nothing to look up)."""
        return self._guard(lambda: self.db.execute("SELECT 1 FROM rows LIMIT 1").fetchone()) is None

    def done(self, keys: list[str]) -> dict[str, str]:
        """Status of the stored rows among ``keys``."""
        out = {}
        for i in range(0, len(keys), 500):
            chunk = keys[i:i + 500]
            q = f"SELECT key, status FROM rows WHERE key IN ({','.join('?' * len(chunk))})"
            out.update(dict(self._guard(lambda: self.db.execute(q, chunk).fetchall())))
        return out

    def put(self, key: str, row: dict) -> None:
        self.put_many([key], [row])

    def put_many(self, keys: list[str], rows: list[dict]) -> None:
        """Store rows in one transaction (all or none)."""
        data = [(k, r.get("status"), json.dumps(r)) for k, r in zip(keys, rows)]

        def write():
            with self.db:
                self.db.executemany("INSERT OR REPLACE INTO rows VALUES (?, ?, ?)", data)
        self._guard(write)

    def put_encoded(self, keys: list[str], statuses: list, texts: list[str]) -> None:
        """Store rows already encoded as JSON (:func:`experiments.rows.encode_rows`) in one transaction."""
        data = list(zip(keys, statuses, texts))

        def write():
            with self.db:
                self.db.executemany("INSERT OR REPLACE INTO rows VALUES (?, ?, ?)", data)
        self._guard(write)

    def put_batch(self, keys: list[str], batch: dict) -> None:
        """Store a chunk's rows as a worker encoded them (:func:`experiments.rows.encode_rows`)."""
        self.put_encoded(keys, batch["status"], batch["row"])

    def get(self, keys: list[str]) -> list[dict]:
        rows = self.get_by_key(keys)
        return [rows[k] for k in keys if k in rows]

    def get_by_key(self, keys: list[str], decode=json.loads) -> dict[str, dict]:
        rows = {}
        for i in range(0, len(keys), 500):
            chunk = keys[i:i + 500]
            q = f"SELECT key, row FROM rows WHERE key IN ({','.join('?' * len(chunk))})"
            rows.update({k: decode(r) for k, r in self._guard(lambda: self.db.execute(q, chunk).fetchall())})
        return rows

    def mark_complete(self, fingerprint: str, n_rows: int) -> None:
        """Record that the store holds every row of a study (``experiments.engine.fingerprint``), none to run again."""
        def write():
            with self.db:
                self.db.execute("INSERT OR REPLACE INTO complete VALUES (?, ?, (SELECT MAX(rowid) FROM rows))",
                                (fingerprint, n_rows))
        self._guard(write)

    def complete(self, fingerprint: str) -> int | None:
        """The number of rows of the study ``fingerprint`` if the store holds them all unchanged since
        :meth:`mark_complete`, else None."""
        row = self._guard(lambda: self.db.execute(
            "SELECT n_rows FROM complete WHERE fingerprint = ? AND last_rowid IS (SELECT MAX(rowid) FROM rows)",
            (fingerprint,)).fetchone())
        return None if row is None else int(row[0])

    @staticmethod
    def holds_complete(path: Path, fingerprint: str) -> int | None:
        """:meth:`complete` of the store at ``path``, read without changing it (a store that cannot be read as a row
        store: None; the run that opens it says why)."""
        try:   # read and write, never create: as the last connection it removes the WAL's -wal and -shm files, which
            # a read-only one leaves beside the store of a run that had nothing to do
            db = sqlite3.connect(f"file:{quote(Path(path).resolve().as_posix())}?mode=rw", uri=True)
        except sqlite3.Error:
            return None
        try:
            row = db.execute("SELECT n_rows FROM complete WHERE fingerprint = ? AND last_rowid IS "
                             "(SELECT MAX(rowid) FROM rows)", (fingerprint,)).fetchone()
        except sqlite3.Error:
            return None
        finally:
            db.close()
        return None if row is None else int(row[0])

    def forget(self, keys: list[str]) -> None:
        self._guard(lambda: self._forget(keys))

    def _forget(self, keys):
        with self.db:
            self.db.executemany("DELETE FROM rows WHERE key = ?", [(k,) for k in keys])

    def close(self):
        self.db.close()
