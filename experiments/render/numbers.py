"""One number format per table column, chosen from the column's values so that the differences the table is
about stay visible (a 22 µm difference between two 299 mm semi-axes is not rounded away), used alike by the
HTML, Markdown and LaTeX renderings.

``column_format(values, digits)``: whole numbers as integers; otherwise ``digits`` significant digits of the
column's largest magnitude, with more decimals (up to 6 more) while two values that differ by more than a
relative ``MATTERS`` (1e-6) of that magnitude would print alike, and at least as many as keep two significant
digits of the smallest value (16.6470 and 0.0080 in one column). A column spanning more decades than that (the
largest magnitude >= 1e5, the smallest value needing more than ``MAX_FIXED_DECIMALS`` decimals, or so many that
the largest would print more than 3 significant digits beyond ``digits``) prints each
number with ``digits`` significant digits ("significant": 43.3, 0.422 and 4.31×10⁻¹⁰ in one column, as siunitx
prints a cell without a fixed format), in plain notation between 1e-3 and 1e5 and scientific beyond, unless most of
its values lie beyond: then every cell is scientific (one exponent per cell, one mantissa width per column), as
when the largest magnitude is below 1e-3. Never ×10⁰: a mantissa whose exponent is 0 prints alone (as
siunitx prints ``2.229e0`` in the PDF), which only a column spanning more than about six decades can show. ``table_formats`` chooses the
format jointly for the columns that share a unit (semi-axes a and b of 299.024 and 299.002 mm stay apart even
though each column alone has no spread) and gives every one of them that format. No format prints more decimals
or significant digits than the values carry (``within_given``): a column a study rounded to 95.5 prints 95.5, not
95.50, since the renderer alone decides the digits shown and a padding zero would claim a digit the data lost.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
#: header words that make a column a count or a dimensionless number (shown without the table's unit)
_COUNT = re.compile(r"(?:^|[\s_])(n|runs?|rows?|counts?|iterations?|evaluations?|nfev|nit|points?|repetitions?|"
                    r"sets?|problems?|starts?|slopes?|ratios?|exponents?|not[\s_]converged)(?:$|[\s_])", re.I)
MAX_EXTRA_DECIMALS = 6
MAX_FIXED_DECIMALS = 5   #: a column whose smallest value needs more decimals than this is printed in scientific notation


PLAIN = (1e-3, 1e5)   #: magnitudes printed in plain notation by a "significant" format


@dataclass(frozen=True)
class NumberFormat:
    kind: str            #: "integer" | "fixed" | "exponent" | "significant" | "exact" (each number as given)
    decimals: int = 0    #: decimals (fixed) or mantissa decimals (exponent, significant: digits - 1)

    def text(self, v: float) -> str:
        """Plain text (HTML, Markdown): 2080, 0.0123, 4.07×10⁸; "exact": the shortest decimal that gives back
        the stored value, without padding zeros (0.029807 stays 0.029807)."""
        if v is None or not np.isfinite(v):
            return "–"
        if self.kind == "integer":
            return f"{int(round(v))}"
        if self.kind == "exact":
            s = np.format_float_positional(float(v), trim="-")
            return s[1:] if s.startswith("-") and float(s) == 0 else s
        if self.kind == "fixed":
            s = f"{v:.{self.decimals}f}"
            return s[1:] if s.startswith("-") and float(s) == 0 else s
        if v == 0:
            return "0"
        if self.kind == "significant" and PLAIN[0] <= abs(v) < PLAIN[1]:
            s = f"{v:.{max(0, self.decimals - math.floor(math.log10(abs(v))))}f}"
            return s[1:] if s.startswith("-") and float(s) == 0 else s
        m, e = f"{v:.{self.decimals}e}".split("e")
        if int(e) == 0:             # never ×10⁰ (as siunitx prints 2.229e0 in the PDF: 2.229)
            return m
        return f"{m}×10{str(int(e)).translate(_SUPERSCRIPT)}"


MATTERS = 1e-6   #: relative differences below this (of the largest magnitude) need not stay visible


def _distinct(v: np.ndarray, scale: float) -> int:
    if scale <= 0:
        return 1
    q = np.sort(v / scale)
    return 1 + int(np.sum(np.diff(q) > MATTERS))


def given_digits(values) -> tuple[int, int]:
    """(decimals, significant digits) the numbers carry: the most of either in the shortest decimal that gives
    back each value (95.5 -> 1 decimal, 3 digits; 0.348 -> 3, 3; an unrounded mean 95.48213... -> 14, 16). A value
    rounded before it reached the renderer has no digit beyond these: printing more would pad it with zeros that
    claim digits the data does not have (95.50 for a coverage of 95.48 % rounded to 95.5)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v) & (v != 0)]
    decimals = significant = 0
    for x in v:
        text = np.format_float_positional(abs(float(x)), trim="-")
        whole, _, frac = text.partition(".")
        decimals = max(decimals, len(frac))
        significant = max(significant, len((whole + frac).lstrip("0")))
    return decimals, significant


def within_given(fmt: NumberFormat, values) -> NumberFormat:
    """``fmt`` with no more decimals (fixed) or significant digits (significant, exponent) than the ``values``
    carry (:func:`given_digits`): a printed digit is a digit of the data, never a padding zero."""
    if fmt.kind not in ("fixed", "significant", "exponent"):
        return fmt
    decimals, significant = given_digits(values)
    if fmt.kind == "fixed":
        return NumberFormat("fixed", min(fmt.decimals, decimals))
    return NumberFormat(fmt.kind, max(0, min(fmt.decimals, significant - 1)))


def column_format(values, digits: int = 3) -> NumberFormat:
    """The format of a column of numbers (see the module docstring), never with more digits than the values
    carry (:func:`within_given`)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return within_given(_column_format(v, digits), v)


def _column_format(v: np.ndarray, digits: int) -> NumberFormat:
    digits = max(1, int(digits))
    if v.size == 0:
        return NumberFormat("fixed", 0)
    if np.all(v == np.round(v)) and np.max(np.abs(v)) < 1e15:
        return NumberFormat("integer")
    top = float(np.max(np.abs(v)))
    if top == 0:
        return NumberFormat("fixed", 0)
    need = _distinct(v, top)
    low = float(np.min(np.abs(v[v != 0]))) if np.any(v != 0) else top
    fixed = max(0, digits - 1 - math.floor(math.log10(top)))
    two_digits = 1 - math.floor(math.log10(low))      # decimals that keep two significant digits of the smallest
    # decimals that keep two digits of the smallest value would print the largest with more than 3 significant
    # digits beyond the table's (RONt 1748.66665 µm beside 0.00013 µm): too spread for one number of decimals
    overshoot = math.floor(math.log10(top)) + 1 + two_digits > digits + 3
    if top >= 1e5 or top < 1e-3 or two_digits > MAX_FIXED_DECIMALS or (two_digits > fixed and overshoot):
        # so spread that plain decimals would not keep two digits of the smallest: each number with its own
        # significant digits (43.3 beside 4.31×10⁻¹⁰), not 4.33×10¹ for an ordinary number
        nonzero = np.abs(v[v != 0])
        if np.mean((nonzero >= PLAIN[0]) & (nonzero < PLAIN[1])) >= 0.5:
            return NumberFormat("significant", digits - 1)
        # huge or tiny: 4.07×10⁸
        d = digits - 1
        while d < digits - 1 + MAX_EXTRA_DECIMALS and len({f"{x:.{d}e}" for x in v}) < need:
            d += 1
        return NumberFormat("exponent", d)
    # plain decimals for the whole column, as many as keep two digits of its smallest value (16.647 and 0.0080
    # in one column, not 1.665×10¹ beside 8.000×10⁻³, nor scientific beside plain)
    d = max(fixed, two_digits)
    base = d
    while d < base + MAX_EXTRA_DECIMALS and len(np.unique(np.round(v, d))) < need:
        d += 1
    return NumberFormat("fixed", d)


def declared_format(decimals: dict | None = None, exact=()) -> dict:
    """{column: NumberFormat} of a table's declared columns: ``decimals`` {column: n} fixed with n decimals (the
    resolution its comparison needs: 299.0132 mm against 299.0131 mm, decimals 4), ``exact`` columns each number
    as given (published values)."""
    out = {c: NumberFormat("fixed", int(n)) for c, n in (decimals or {}).items()}
    out.update({c: NumberFormat("exact") for c in exact or ()})
    return out


def table_formats(df, columns, units: dict, digits: int = 3, declared: dict | None = None) -> dict:
    """{column: NumberFormat} for the number ``columns`` of ``df``; a column in ``declared`` ({column:
    NumberFormat}, :func:`declared_format`) gets its declared format; of the others, columns with the same
    non-empty unit (``units[column]``) share one format chosen from all their values, the rest get their own."""
    import pandas as pd
    declared = declared or {}
    groups: dict = {}
    for c in columns:
        if c in declared:
            continue
        groups.setdefault(("unit", units.get(c)) if units.get(c) else ("column", c), []).append(c)
    out = {}
    for cols in groups.values():
        values = np.concatenate([pd.to_numeric(df[c], errors="coerce").to_numpy(float) for c in cols])
        joint = column_format(values, digits)
        alone = {c: column_format(pd.to_numeric(df[c], errors="coerce").to_numpy(float), digits) for c in cols}
        # fixed decimals shared by the columns of one unit; where that does not suit them all, each its own
        shared = joint.kind == "fixed" and all(f.kind in ("fixed", "integer") for f in alone.values())
        for c in cols:
            out[c] = joint if shared else alone[c]
    # a declared number of decimals too is never more than the values carry
    out.update({c: within_given(f, pd.to_numeric(df[c], errors="coerce").to_numpy(float))
                for c, f in declared.items() if c in columns})
    return {c: out[c] for c in columns}


def is_count(name) -> bool:
    """A column whose header names a count (runs, n, iterations, ...) or a dimensionless number (slope, ratio):
    it carries no unit."""
    return bool(_COUNT.search(str(name)))


_UNIT_WORDS = {"um": "µm", "μm": "µm", "urad": "µrad", "μrad": "µrad", "us": "µs", "μs": "µs", "um/m": "µm/m",
               "deg": "°"}


def human_unit_text(value):
    """A cell of a unit column as a person reads it (um -> µm, urad -> µrad, um/m -> µm/m); other values as given."""
    return _UNIT_WORDS.get(value, value) if isinstance(value, str) else value


#: a field name (snake_case, no spaces or dots: ``best_rms_um``, ``kappa_stations``) and its unit suffix
_FIELD = re.compile(r"^[A-Za-z][A-Za-z0-9]*(?:_[A-Za-z0-9]+)+$")
_SUFFIX_UNITS = {"um": "µm", "mm": "mm", "nm": "nm", "urad": "µrad", "deg": "°", "ms": "ms", "us": "µs", "pct": "%"}


def _suffix_unit(name) -> str:
    """The unit a field name ends with ('best_rms_um' -> 'µm'), or ''."""
    text = str(name)
    if not _FIELD.match(text):
        return ""
    return _SUFFIX_UNITS.get(text.rsplit("_", 1)[1], "")


def header_unit(name) -> str:
    """The unit a header names: in brackets ('R [mm]' -> 'mm') or as a field name's suffix ('dx_um' -> 'µm');
    else ''."""
    m = re.search(r"\[([^\]]+)\]\s*$", str(name))
    return human_unit_text(m.group(1).strip()) if m else _suffix_unit(name)


def human_header(name) -> str:
    """A column header as a person reads it: ASCII unit spellings inside [...] or (...) become µm, µrad, µs
    (``x_c - nominal [um]`` -> ``x_c - nominal [µm]``); a field name loses its unit suffix (the unit is shown
    once, in brackets: :func:`header_unit`) and its underscores (``best_rms_um`` -> ``best rms``,
    ``kappa_points_published`` -> ``kappa points published``); a method id (``circle.kasa``) is kept."""
    text = str(name)
    if _FIELD.match(text):
        if _suffix_unit(text):
            text = text.rsplit("_", 1)[0]
        return text.replace("_", " ")

    def fix(m):
        inner = re.sub(r"(?<![A-Za-z])(um/m|um|urad|us|μm|μrad|μs|deg)(?![A-Za-z])",
                       lambda w: _UNIT_WORDS[w.group(1)], m.group(2))
        return m.group(1) + inner + m.group(3)
    return re.sub(r"([\[(])([^\])]*)([\])])", fix, str(name))
