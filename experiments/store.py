"""The row store: finished rows by cache key in SQLite, one committed transaction per row."""
from __future__ import annotations

import json
import os
import sqlite3
import time
from pathlib import Path


class RowStore:
    """Finished rows by cache key in SQLite: one committed transaction per row (atomic, crash-safe)."""

    def __init__(self, path: Path, log=print):
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        try:
            self.db = self._open(path)
        except sqlite3.DatabaseError as exc:  # garbage, a truncated file, a wrong table: never fatal
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
            self.db = self._open(path)

    @staticmethod
    def _open(path: Path) -> sqlite3.Connection:
        db = sqlite3.connect(path)
        try:
            db.execute("PRAGMA journal_mode=WAL")
            db.execute("PRAGMA synchronous=NORMAL")  # WAL: a commit survives a crash of the program
            db.execute("CREATE TABLE IF NOT EXISTS rows (key TEXT PRIMARY KEY, status TEXT, row TEXT)")
            db.commit()
            check = db.execute("PRAGMA quick_check").fetchone()[0]
            if check != "ok":
                raise sqlite3.DatabaseError(f"integrity check: {check}")
            cols = [r[1] for r in db.execute("PRAGMA table_info(rows)")]
            if cols != ["key", "status", "row"]:
                raise sqlite3.DatabaseError(f"table 'rows' has columns {cols}, not key, status, row")
            for (text,) in db.execute("SELECT row FROM rows"):
                json.loads(text)
        except (sqlite3.DatabaseError, ValueError, TypeError) as exc:
            db.close()
            raise sqlite3.DatabaseError(str(exc)) from None
        return db

    def done(self, keys: list[str]) -> dict[str, str]:
        """Status of the stored rows among ``keys``."""
        out = {}
        for i in range(0, len(keys), 500):
            chunk = keys[i:i + 500]
            q = f"SELECT key, status FROM rows WHERE key IN ({','.join('?' * len(chunk))})"
            out.update(dict(self.db.execute(q, chunk).fetchall()))
        return out

    def put(self, key: str, row: dict) -> None:
        with self.db:
            self.db.execute("INSERT OR REPLACE INTO rows VALUES (?, ?, ?)", (key, row.get("status"), json.dumps(row)))

    def get(self, keys: list[str]) -> list[dict]:
        rows = {}
        for i in range(0, len(keys), 500):
            chunk = keys[i:i + 500]
            q = f"SELECT key, row FROM rows WHERE key IN ({','.join('?' * len(chunk))})"
            rows.update({k: json.loads(r) for k, r in self.db.execute(q, chunk).fetchall()})
        return [rows[k] for k in keys if k in rows]

    def get_by_key(self, keys: list[str]) -> dict[str, dict]:
        rows = {}
        for i in range(0, len(keys), 500):
            chunk = keys[i:i + 500]
            q = f"SELECT key, row FROM rows WHERE key IN ({','.join('?' * len(chunk))})"
            rows.update({k: json.loads(r) for k, r in self.db.execute(q, chunk).fetchall()})
        return rows

    def forget(self, keys: list[str]) -> None:
        with self.db:
            self.db.executemany("DELETE FROM rows WHERE key = ?", [(k,) for k in keys])

    def close(self):
        self.db.close()
