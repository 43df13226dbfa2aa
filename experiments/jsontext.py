"""The text of ``report.json`` and ``meta.json``: strict JSON (RFC 8259) that any parser reads (jq, JavaScript's
``JSON.parse``), although a study's named values may be infinite or NaN, and the values read back from it."""
from __future__ import annotations

import json
import math

import numpy as np


def _plain(v):
    if isinstance(v, np.generic):
        return v.item()
    return str(v)


#: how a value that is not a finite number is written in JSON: a text that Python's ``float()`` and JavaScript's
#: ``Number()`` read back (JSON has no such number; the bare ``Infinity`` Python writes is refused by jq and JSON.parse)
NON_FINITE = {math.inf: "Infinity", -math.inf: "-Infinity"}


def _finite(v):
    """``v`` with every float that is infinite or NaN (NumPy's too, in lists, tuples and dicts) as its text."""
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float):
        return v if math.isfinite(v) else NON_FINITE.get(v, "NaN")
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_finite(x) for x in v]
    return v


def json_text(value, **kwargs) -> str:
    """``value`` as strict JSON (RFC 8259): a study's values, named by its analysis, may be infinite or NaN."""
    return json.dumps(_finite(value), default=_plain, allow_nan=False, **kwargs)


_FROM_TEXT = {"Infinity": math.inf, "-Infinity": -math.inf, "NaN": math.nan}


def _numbers(v):
    if isinstance(v, str):
        return _FROM_TEXT.get(v, v)
    if isinstance(v, dict):
        return {k: _numbers(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_numbers(x) for x in v]
    return v


def json_value(text: str):
    """The value :func:`json_text` wrote, its "Infinity", "-Infinity" and "NaN" texts the floats again (a study's
    findings hold numbers: a condition number of a degenerate layout is infinite)."""
    return _numbers(json.loads(text))
