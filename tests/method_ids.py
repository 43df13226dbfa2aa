"""The methods the method tests run on: fitbench's own methods of a family (``MethodSpec.builtin``), never an
installed plugin's unasked (the README's example plugin, a centroid fit, is not held to exact-data recovery), plus the
plugin methods named in the environment variable ``FITBENCH_TEST_METHODS`` (comma-separated ids): how a plugin author
runs fitbench's method tests on a method (docs/plugins.md, "Testing a plugin method")."""
from __future__ import annotations

import os

import methods

ENV = "FITBENCH_TEST_METHODS"


def asked() -> list[str]:
    """The plugin method ids ``FITBENCH_TEST_METHODS`` names (an id no installed method has is an error: a typo
    would otherwise test nothing and pass)."""
    ids = [i.strip() for i in os.environ.get(ENV, "").split(",") if i.strip()]
    known = {s.id for s in methods.list_methods()}
    unknown = [i for i in ids if i not in known]
    if unknown:
        raise LookupError(f"{ENV} names {', '.join(unknown)}, which no installed method is "
                          f"(see python -m methods list)")
    return ids


def method_specs(family: str) -> list:
    """The specs of the family's methods the tests run on: the built-ins and the asked plugins, sorted by id."""
    wanted = set(asked())
    return [s for s in methods.list_methods(family) if s.builtin or s.id in wanted]


def method_ids(family: str) -> list[str]:
    return [s.id for s in method_specs(family)]
