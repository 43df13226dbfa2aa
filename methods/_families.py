"""Discovery of a family's method modules: every public module of a family package registers its methods on
import, so adding a method is adding one file (``methods/circle/my_fit.py``) and nothing else."""
from __future__ import annotations

import importlib
import pkgutil


def import_method_modules(package: str, path) -> list[str]:
    """Import every module of ``package`` (its ``__path__`` is ``path``) whose name does not start with an
    underscore, in sorted order, and return their names."""
    names = sorted(m.name for m in pkgutil.iter_modules(path) if not m.name.startswith("_"))
    for name in names:
        importlib.import_module(f"{package}.{name}")
    return names
