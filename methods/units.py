"""Length units of input files and the plausibility check of a declared unit.

Every reader takes the unit of its file (``nm``, ``µm``/``um``, ``mm``, ``m``, ``in``; default ``mm``)
and returns millimetres: fitbench computes in mm and rad, writes JSON in mm and rad (with a ``units``
field) and prints µm, µrad and ° for people.
"""
from __future__ import annotations

import warnings

import numpy as np

from methods._errors import InvalidInputError

#: millimetres per unit
MM_PER = {"nm": 1e-6, "µm": 1e-3, "um": 1e-3, "micron": 1e-3, "mm": 1.0, "m": 1e3, "in": 25.4, "inch": 25.4}
UNIT_CHOICES = ("nm", "µm", "um", "mm", "m", "in")
#: what the JSON outputs say about themselves
JSON_UNITS = {"length": "mm", "angle": "rad", "time": "s", "ratio": "1 (m/m)", "feed": "mm/min"}


class UnitWarning(UserWarning):
    """A value implausible for its declared unit (a likely unit mix-up)."""


def mm_per(unit: str) -> float:
    """Millimetres per ``unit``; a one-line error for an unknown unit."""
    key = str(unit).strip().replace("μ", "µ")
    if key.lower() in MM_PER:
        return MM_PER[key.lower()] if key != "µm" else 1e-3
    if key in MM_PER:
        return MM_PER[key]
    raise InvalidInputError(f"unknown length unit {unit!r}; use one of {', '.join(UNIT_CHOICES)}")


def canonical(unit: str) -> str:
    """The printed name of a unit (um -> µm)."""
    mm_per(unit)
    key = str(unit).strip().replace("μ", "µ").lower()
    return {"um": "µm", "micron": "µm", "inch": "in"}.get(key, key)


def to_mm(values, unit: str):
    """``values`` (array or float) converted from ``unit`` to mm (a no-op, without a copy, for mm)."""
    f = mm_per(unit)
    return values if f == 1.0 else np.asarray(values, dtype=float) * f


def likely_unit(size_mm: float, expected_mm: float) -> str | None:
    """The unit that would make ``size_mm`` (read with the declared unit, converted to mm) about
    ``expected_mm``: the ratio rounded to the nearest power of 1000 (or 25.4 for inches)."""
    if not (np.isfinite(size_mm) and size_mm > 0 and expected_mm > 0):
        return None
    ratio = size_mm / expected_mm
    for name, factor in (("µm", 1e3), ("nm", 1e6), ("m", 1e-3)):
        if factor / 30 < ratio < factor * 30:
            return name
    return None


def warn_implausible(what: str, size_mm: float, limit_mm: float, declared: str, typical_mm: float | None = None,
                     option: str = "--unit"):
    """Warn (``UnitWarning``) when ``size_mm`` exceeds ``limit_mm``, naming the likely unit of the file's numbers
    (``size_mm`` back in the ``declared`` unit, :func:`likely_unit`) and the command-line
    ``option`` that declares it (``--deviation-unit`` when the values are deviations read apart from the targets)."""
    if np.isfinite(size_mm) and size_mm > limit_mm:
        # the unit the file's numbers (size_mm in the declared unit) are likely in: 236 mm read as µm is nm
        guess = likely_unit(size_mm / mm_per(declared), typical_mm if typical_mm else limit_mm / 10)
        hint = f"; is the file in {guess}? ({option} {guess.replace('µ', 'u')})" if guess else ""
        warnings.warn(f"{what} up to {size_mm:.6g} mm (read as {canonical(declared)}) are implausible{hint}",
                      UnitWarning, stacklevel=3)
        return True
    return False
