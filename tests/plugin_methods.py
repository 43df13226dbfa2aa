"""A plugin's methods (and data sources) registered in the test's process for one test, then taken out of their
registry again (they must not leak into ``circle.*`` of another test): given as functions, or as a plugin module's
source run here."""
from __future__ import annotations

import contextlib

from datasets import sources
from methods import _registry, register


@contextlib.contextmanager
def registered(funcs: dict, **spec):
    """``{id: function}`` registered as methods (``methods.register(id, **spec)``) while in the block."""
    for mid, func in funcs.items():
        register(mid, **spec)(func)
    try:
        yield
    finally:
        for mid in funcs:
            _registry._REGISTRY.pop(mid, None)


@contextlib.contextmanager
def plugin_here(code: str, name: str):
    """``code``, a plugin module's source, run here as module ``name`` (its namespace, yielded); the methods it
    registers are registered while in the block."""
    namespace = {"__name__": name}
    exec(compile(code, name, "exec"), namespace)
    ids = [k for k, v in _registry._REGISTRY.items() if v.func.__globals__ is namespace]
    try:
        yield namespace
    finally:
        for mid in ids:
            _registry._REGISTRY.pop(mid, None)


@contextlib.contextmanager
def sources_registered(funcs: dict, **spec):
    """``{name: function}`` registered as data sources (``datasets.sources.register_source(name, **spec)``) while in
    the block."""
    for name, func in funcs.items():
        sources.register_source(name, **spec)(func)
    try:
        yield
    finally:
        for name in funcs:
            sources._REGISTRY.pop(name, None)
