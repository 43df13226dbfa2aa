"""pandas imported on first use: its import costs ~0.3 s, and small files are read without it
(:func:`datasets.io.columns.read_columns`). The modules that parse with pandas take :data:`pd` from here."""
from __future__ import annotations

import importlib


class _Lazy:
    """pandas imported on first use (its import costs ~0.3 s; small files are read without it)."""

    def __getattr__(self, name):
        return getattr(importlib.import_module("pandas"), name)


pd = _Lazy()
