"""The text of ``report.json`` and ``meta.json``: strict JSON (RFC 8259) that any parser reads (jq, JavaScript's
``JSON.parse``), although a study's named values may be infinite or NaN, and the values read back from it, each as it
was written: a number that is not finite is a float again, a text is the same text (also the text "NaN")."""
from __future__ import annotations

import json
import math
import re

import numpy as np

#: how a value that is not a finite number is written in JSON: a text that Python's ``float()`` and JavaScript's
#: ``Number()`` read back (JSON has no such number; the bare ``Infinity`` Python writes is refused by jq and JSON.parse)
NON_FINITE = {math.inf: "Infinity", -math.inf: "-Infinity"}
_FROM_TEXT = {"Infinity": math.inf, "-Infinity": -math.inf, "NaN": math.nan}
#: a text that would read as one of those numbers, behind any number of backslashes: written with one backslash more
#: (a label "NaN" is written "\\NaN", one "\\NaN" as "\\\\NaN"), so that only a number is ever written as "NaN"
_LOOKS_NON_FINITE = re.compile(r"\\*(?:NaN|Infinity|-Infinity)")


def _finite(v):
    """``v`` with every float that is infinite or NaN (NumPy's too, in lists, tuples and dicts) as its text, every
    text that reads as such a number escaped (:data:`_LOOKS_NON_FINITE`), and every other object that JSON has no type
    for as its ``str``."""
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, str):
        return "\\" + v if _LOOKS_NON_FINITE.fullmatch(v) else v
    if isinstance(v, float):
        return v if math.isfinite(v) else NON_FINITE.get(v, "NaN")
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_finite(x) for x in v]
    if v is None or isinstance(v, int):
        return v
    return _finite(str(v))


def json_text(value, **kwargs) -> str:
    """``value`` as strict JSON (RFC 8259): a study's values, named by its analysis, may be infinite or NaN (written
    as the texts "Infinity", "-Infinity", "NaN"; a text that reads as one of them is escaped, see :func:`json_value`)."""
    return json.dumps(_finite(value), allow_nan=False, **kwargs)


def _numbers(v):
    if isinstance(v, str):
        if v in _FROM_TEXT:
            return _FROM_TEXT[v]
        return v[1:] if _LOOKS_NON_FINITE.fullmatch(v) else v
    if isinstance(v, dict):
        return {k: _numbers(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_numbers(x) for x in v]
    return v


def json_value(text: str):
    """The value :func:`json_text` wrote: its "Infinity", "-Infinity" and "NaN" texts the floats again (a study's
    findings hold numbers: a condition number of a degenerate layout is infinite), its escaped texts the texts they
    were (a label "NaN" stays a text)."""
    return _numbers(json.loads(text))
