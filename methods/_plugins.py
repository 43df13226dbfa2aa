"""Loading third-party plugins from entry-point groups, once per group (one loader for all registries).

The method registry (group ``fitbench.methods``, :mod:`methods._registry`) and the data-source registry
(group ``fitbench.datasets``, :mod:`datasets.sources`) both call :func:`load_entry_points`; each entry point
names a module (or object) whose import registers what it brings. This module imports nothing of
fitbench, so any registry can use it without an import circle.
"""
from __future__ import annotations

import warnings
from importlib import metadata


class PluginLoadWarning(UserWarning):
    """A plugin's entry point failed to load; it was skipped and the built-ins still work."""


_loaded_groups: set[str] = set()


def _one_line(exc: BaseException) -> str:
    """``Type: first line of the message`` (an exception's message may span lines; a warning must not)."""
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


def load_entry_points(group: str, what: str) -> None:
    """Import every entry point of ``group`` once per process; ``what`` names what its plugins add
    (e.g. ``"method"``, ``"data source"``) for the warning.

    A broken plugin does not take the built-ins down: it is skipped with one :class:`PluginLoadWarning`
    of one line saying which entry point of which distribution failed, why, and what to do.
    """
    if group in _loaded_groups:
        return
    _loaded_groups.add(group)
    for ep in metadata.entry_points(group=group):
        try:
            ep.load()
        except Exception as exc:  # a third-party bug must not take the built-ins down
            dist = getattr(ep, "dist", None)
            origin = f"distribution {dist.name} {dist.version}" if dist is not None else "an unknown distribution"
            warnings.warn(f"{what} plugin {ep.name!r} (entry point {ep.value!r} of group {group!r}, "
                          f"{origin}) failed to load and is skipped: {_one_line(exc)}; fix or uninstall that "
                          f"distribution", PluginLoadWarning, stacklevel=3)
