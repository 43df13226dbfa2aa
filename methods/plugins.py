"""Loading third-party plugins from entry-point groups, once per group (one loader for all registries).

The method registry (group ``fitbench.methods``, :mod:`methods._registry`) and the data-source registry
(group ``fitbench.datasets``, :mod:`datasets.sources`) both call :func:`load_entry_points`; each entry point
names a module (or object) whose import registers what it brings. Loading is transactional: registries
add their entries through :func:`add_entry`, and whatever an entry point added before it failed is taken
out again, so a plugin that fails to load registers nothing (no method, no data source). What a plugin registered is
attributed to its distribution (:func:`distributions_of`, recorded in each study's ``meta.json``).
This module imports nothing of fitbench, so any registry can use it without an import circle.
"""
from __future__ import annotations

import signal
import threading
import warnings
from contextlib import contextmanager
from importlib import metadata

#: the top-level packages of fitbench itself: never a plugin, wherever the environment lives
OWN_PACKAGES = frozenset({"methods", "datasets", "experiments", "fitbench"})


class PluginLoadWarning(UserWarning):
    """A plugin's entry point failed to load; it was skipped and the built-ins still work."""


_loaded_groups: set[str] = set()
_MISSING = object()
#: (registry, key, what it held before) of every entry added, in order (undone when a plugin fails)
_JOURNAL: list[tuple[dict, object, object]] = []
#: module -> (distribution, version) of what entry points registered
_MODULE_DIST: dict[str, tuple[str, str]] = {}
#: (group, entry point name, its value) of every entry point that failed to load in this process
_FAILED: set[tuple[str, str, str]] = set()


#: > 0 while fitbench registers its own entries (:func:`own_entries`): those are journaled to no plugin
_OWN_DEPTH = 0


def add_entry(registry: dict, key, entry) -> None:
    """``registry[key] = entry``, journaled: an entry point that fails while loading has its additions taken out
    of every registry (methods, data sources, ...), and what a successful one added is attributed to its
    distribution (``entry.module``). Entries added inside :func:`own_entries`, or defined in fitbench's own
    modules (a built-in module a plugin imported first), are not journaled: they are no plugin's."""
    module = getattr(entry, "module", None)
    if not _OWN_DEPTH and not (isinstance(module, str) and module.split(".")[0] in OWN_PACKAGES):
        _JOURNAL.append((registry, key, registry.get(key, _MISSING)))
    registry[key] = entry


@contextmanager
def own_entries():
    """Registration of fitbench's own entries (the built-in methods, loaded by a plugin's first ``register``
    when no one loaded them before): what is added inside belongs to no plugin, so a plugin that fails later
    does not take it out, and a plugin that loads is not named as its distribution."""
    global _OWN_DEPTH
    _OWN_DEPTH += 1
    try:
        yield
    finally:
        _OWN_DEPTH -= 1


def _one_line(exc: BaseException) -> str:
    """``Type: first line of the message`` (an exception's message may span lines; a warning must not); a plugin's
    exception whose message cannot be printed is named by its type alone."""
    name = getattr(type(exc), "__name__", None)
    name = name if isinstance(name, str) else "an exception"
    try:
        text = str(exc)
        text = text.strip().splitlines() if isinstance(text, str) else []
    except Exception:  # the plugin's own __str__
        text = []
    return f"{name}: {text[0]}" if text else name


class _ProcessSignals:
    """While plugins load (main thread): every Python signal handler is wrapped so that what it raises is known to be
    the process's (the user's Ctrl-C, a SIGTERM, a row's time limit), not the plugin's. A plugin's import that raises
    a ``BaseException`` of its own (``sys.exit()``, ``KeyboardInterrupt``, ``GeneratorExit``) is a failed plugin; one
    raised by a handler, or by the plugin while handling it, is raised again (Ctrl-C stops the process as usual)."""

    def __init__(self):
        self.raised: list[BaseException] = []
        self.wrapped: dict = {}

    def __enter__(self):
        if threading.current_thread() is not threading.main_thread():
            return self   # Python runs signal handlers in the main thread only: nothing raised here is a signal's
        for sig in signal.valid_signals():
            try:
                handler = signal.getsignal(sig)
            except (OSError, ValueError):
                continue
            if callable(handler):
                wrapper = self._wrap(handler)
                try:
                    signal.signal(sig, wrapper)
                except (OSError, ValueError, RuntimeError):
                    continue
                self.wrapped[sig] = (handler, wrapper)
        return self

    def _wrap(self, handler):
        def on_signal(signum, frame):
            try:
                return handler(signum, frame)
            except BaseException as exc:
                self.raised.append(exc)
                raise
        return on_signal

    def __exit__(self, *exc_info):
        for sig, (handler, wrapper) in self.wrapped.items():
            if signal.getsignal(sig) is wrapper:   # a plugin that installed its own handler keeps it
                signal.signal(sig, handler)
        return False

    def caused(self, exc: BaseException | None) -> BaseException | None:
        """The exception a signal handler raised that ``exc`` is (or was raised while handling), else None."""
        seen = set()
        while exc is not None and id(exc) not in seen:
            seen.add(id(exc))
            if any(exc is r for r in self.raised):
                return exc
            exc = exc.__cause__ or exc.__context__
        return None


def load_entry_points(group: str, what: str, before=None) -> None:
    """Import every entry point of ``group`` once per process; ``what`` names what its plugins add
    (e.g. ``"method"``, ``"data source"``) for the warning; ``before()``, when given, runs once before the
    first entry point is imported, and only if the group has any (the method registry loads its built-ins
    there, so plugins always load after them).

    A broken plugin does not take the built-ins down: it is skipped with one :class:`PluginLoadWarning`
    of one line saying which entry point of which distribution failed, why, and what to do; whatever it
    registered before it failed is removed again (from every tracked registry).
    """
    if group in _loaded_groups:
        return
    _loaded_groups.add(group)
    entry_points = metadata.entry_points(group=group)
    if before is not None and len(entry_points):
        try:
            before()
        except BaseException:
            _loaded_groups.discard(group)
            raise
    with _ProcessSignals() as signals:
        for ep in entry_points:
            _load_one(ep, group, what, signals)


def _load_one(ep, group: str, what: str, signals: _ProcessSignals) -> None:
    """Import one entry point; whatever it raises (an ``Exception`` or any other ``BaseException``: a plugin's
    ``sys.exit()`` at import must not end the process with the plugin's status) takes out what it registered, with
    one warning line. An interrupt a signal handler raised (the user's Ctrl-C) is raised again."""
    mark = len(_JOURNAL)
    dist = getattr(ep, "dist", None)
    try:
        ep.load()
    except BaseException as exc:  # a third-party bug must not take the built-ins, or the process, down
        _undo(mark)
        own = signals.caused(exc)
        if own is not None:   # the user's Ctrl-C (or what the plugin made of it): the process stops as usual
            raise own
        _FAILED.add((group, ep.name, ep.value))
        origin = f"distribution {dist.name} {dist.version}" if dist is not None else "an unknown distribution"
        warnings.warn(f"{what} plugin {ep.name!r} (entry point {ep.value!r} of group {group!r}, "
                      f"{origin}) failed to load and is skipped: {_one_line(exc)}; fix or uninstall that "
                      f"distribution", PluginLoadWarning, stacklevel=4)
        return
    if signals.raised:   # the plugin swallowed the user's interrupt: it still stops the process
        _undo(mark)
        raise signals.raised[0]
    if dist is not None:
        for registry, key, _ in _JOURNAL[mark:]:
            module = getattr(registry.get(key), "module", None)
            if module:
                _MODULE_DIST[module] = (dist.name, dist.version)


def _undo(mark: int) -> None:
    """Take out every registry entry added since the journal held ``mark`` entries."""
    while len(_JOURNAL) > mark:
        registry, key, previous = _JOURNAL.pop()
        if previous is _MISSING:
            registry.pop(key, None)
        else:
            registry[key] = previous


def failed(group: str, ep) -> bool:
    """Whether the entry point ``ep`` of ``group`` failed to load in this process (it registered nothing; importing its
    module again, or its parent package to find it, would run the failing code again)."""
    return (group, ep.name, ep.value) in _FAILED


def distributions_of(modules) -> dict[str, str]:
    """{distribution: version} of the modules that are not fitbench's own (plugins), wherever they are
    installed (a virtual environment inside the checkout included): the distribution whose entry point
    registered the module, else the one that provides its top-level package."""
    out = {}
    for m in modules:
        if m in _MODULE_DIST:
            name, version = _MODULE_DIST[m]
            out[name] = version
            continue
        top = m.split(".")[0]
        if top in OWN_PACKAGES or top == "__main__":
            continue
        for dist_name in metadata.packages_distributions().get(top, []):
            out[dist_name] = metadata.version(dist_name)
    return out


__all__ = ["PluginLoadWarning", "load_entry_points", "add_entry", "own_entries", "distributions_of", "failed",
           "OWN_PACKAGES"]
