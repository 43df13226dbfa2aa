"""A study's findings: one paragraph filled from its named values by a ``str.format``-style template (``[report]
findings`` in its TOML), sandboxed: plain value names, bounded format specs, numbers and text only."""
from __future__ import annotations

import re
import string

import numpy as np


#: the named values every study's findings may use
BASE_VALUES = ("n_rows", "n_ok")
#: a format spec of a findings field: [[fill]align][sign][#][0][width][,|_][.precision][type], width <= 99
_SPEC = re.compile(r"^(?:[^{}]?[<>=^])?[+\- ]?#?0?(?P<width>\d{1,2})?[,_]?(?:\.(?P<precision>\d{1,2}))?[bcdeEfFgGnosxX%]?$")
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
#: the longest findings text (characters): a paragraph, not a document
MAX_FINDINGS = 4000


def _fields(template: str):
    """(literal, name, spec) of a ``str.format``-style template, or raise ValueError with the problem: a
    field is a plain name (no attribute or item access, no conversion) with a bounded format spec."""
    if not isinstance(template, str):
        raise ValueError(f"must be a string, got {template!r}")
    out = []
    for literal, name, spec, conversion in string.Formatter().parse(template):
        if name is None:
            out.append((literal, None, ""))
            continue
        if not _NAME.match(name):
            raise ValueError(f"{{{name}}}: a field is a plain value name (no attribute, item or positional access)")
        if conversion is not None:
            raise ValueError(f"{{{name}!{conversion}}}: conversions are not allowed")
        if not _SPEC.match(spec or ""):
            raise ValueError(f"{{{name}:{spec}}}: the format spec must be [[fill]align][sign][#][0][width <= 99]"
                             "[,][.precision <= 99][type]")
        out.append((literal, name, spec or ""))
    return out


def findings_problem(template, names: set[str] | None = None) -> str | None:
    """The problem with a findings template (None: fine); ``names``: the values it may use, when known."""
    try:
        fields_ = _fields(template)
    except ValueError as exc:
        return str(exc)
    if names is not None:
        unknown = sorted({n for _, n, _ in fields_ if n is not None} - names)
        if unknown:
            return f"unknown value(s) {', '.join(unknown)} (the values: {', '.join(sorted(names))})"
    return None


def render_findings(template: str, values: dict) -> str:
    """Fill ``template`` from ``values`` (numbers and text only), sandboxed: no attribute or item access, no
    conversions, widths and precisions below 100, the result one paragraph of at most MAX_FINDINGS characters
    (line breaks become spaces). Raises ValueError with the problem."""
    parts = []
    for literal, name, spec in _fields(template):
        parts.append(literal)
        if name is None:
            continue
        if name not in values:
            raise ValueError(f"unknown value {name!r} (the values: {', '.join(sorted(values))})")
        v = values[name]
        if isinstance(v, np.generic):
            v = v.item()
        if not isinstance(v, (int, float, str)) or isinstance(v, bool):
            v = str(v)
        try:
            parts.append(format(v, spec))
        except (ValueError, TypeError) as exc:
            raise ValueError(f"{{{name}:{spec}}}: {exc}") from None
    text = " ".join("".join(parts).split())
    return text if len(text) <= MAX_FINDINGS else text[:MAX_FINDINGS - 1] + "…"
