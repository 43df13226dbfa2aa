"""The row store: finished rows by cache key in SQLite, one committed transaction per row."""
from __future__ import annotations

import json
import sqlite3
from pathlib import Path


class RowStore:
    """Finished rows by cache key in SQLite: one committed transaction per row (atomic, crash-safe)."""

    def __init__(self, path: Path):
        path.parent.mkdir(parents=True, exist_ok=True)
        self.db = sqlite3.connect(path)
        self.db.execute("PRAGMA journal_mode=WAL")
        self.db.execute("PRAGMA synchronous=NORMAL")  # WAL: a commit survives a crash of the program
        self.db.execute("CREATE TABLE IF NOT EXISTS rows (key TEXT PRIMARY KEY, status TEXT, row TEXT)")
        self.db.commit()

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

    def forget(self, keys: list[str]) -> None:
        with self.db:
            self.db.executemany("DELETE FROM rows WHERE key = ?", [(k,) for k in keys])

    def close(self):
        self.db.close()
