"""Modules imported on first use, so that ``import methods`` loads only what registration needs
(scipy.optimize, clarabel, pandas, shapely, nlopt cost about a second at start-up).

>>> pd = lazy_module("pandas")      # nothing imported yet
>>> pd.DataFrame                    # doctest: +SKIP  (pandas is imported here, once)
"""
from __future__ import annotations

import importlib


class LazyModule:
    """Stands for the module ``name``; the first attribute read imports it (later reads go straight
    to the imported module, which Python keeps in sys.modules)."""

    def __init__(self, name: str):
        self.__dict__["_name"] = name

    def __getattr__(self, attr):
        module = importlib.import_module(self.__dict__["_name"])
        return getattr(module, attr)

    def __setattr__(self, attr, value):
        setattr(importlib.import_module(self.__dict__["_name"]), attr, value)

    def __repr__(self):
        return f"<lazy module {self.__dict__['_name']!r}>"


def lazy_module(name: str) -> LazyModule:
    """A stand-in for ``import name`` that imports on first attribute access."""
    return LazyModule(name)
