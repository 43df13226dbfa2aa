"""Small text helpers shared by the renderers: ordinals, units, LaTeX escaping."""
from __future__ import annotations

import re


def ordinal(n) -> str:
    """English ordinal of an integer: 1st, 2nd, 3rd, 4th, 11th, 12th, 13th, 21st, 72nd, 91st, 101st, 111th.

    A float is rounded to the nearest integer first (a percentile of 90.3 is the 90th); use
    ``percentile_phrase`` to keep its decimals."""
    k = int(round(float(n)))
    if k < 0:
        raise ValueError(f"ordinal of a negative number ({n}) is not defined; pass a count or a rank")
    suffix = "th" if 11 <= k % 100 <= 13 else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"{k}{suffix}"


def percentile_phrase(p: float, decimals: int = 1) -> str:
    """'the 91st percentile' for a whole number, 'percentile 90.3' otherwise (never '90.3th')."""
    r = round(float(p), decimals)
    return f"the {ordinal(r)} percentile" if float(r).is_integer() else f"percentile {r:.{decimals}f}"


#: plain-text unit -> siunitx macro form (aliases: um, urad, deg)
SI_UNITS = {
    "µm": r"\micro\metre", "um": r"\micro\metre", "μm": r"\micro\metre", "mm": r"\milli\metre", "m": r"\metre",
    "nm": r"\nano\metre", "µrad": r"\micro\radian", "urad": r"\micro\radian", "μrad": r"\micro\radian",
    "mrad": r"\milli\radian", "rad": r"\radian", "°": r"\degree", "deg": r"\degree", "s": r"\second",
    "ms": r"\milli\second", "µs": r"\micro\second", "us": r"\micro\second", "ns": r"\nano\second",
    "%": r"\percent", "mm/min": r"\milli\metre\per\minute", "µm/m": r"\micro\metre\per\metre",
    "arcsec": r"\arcsecond", "K": r"\kelvin", "°C": r"\degreeCelsius",
}
#: plain-text unit -> the form a human reads (for HTML and figure labels)
HUMAN_UNITS = {"um": "µm", "μm": "µm", "urad": "µrad", "μrad": "µrad", "deg": "°", "us": "µs"}


def human_unit(unit: str | None) -> str:
    return "" if not unit else HUMAN_UNITS.get(unit, unit)


def si_unit(unit: str) -> str:
    """``\\si{...}`` for a unit; a unit without an SI form (e.g. 'R', 'radii', '1') is set as upright text."""
    if unit in SI_UNITS:
        return f"\\si{{{SI_UNITS[unit]}}}"
    return f"\\text{{{escape_text(unit)}}}" if unit else ""


_TEXT_MAP = [("\\", r"\textbackslash{}"), ("&", r"\&"), ("%", r"\%"), ("$", r"\$"), ("#", r"\#"), ("_", r"\_"),
             ("{", r"\{"), ("}", r"\}"), ("~", r"\textasciitilde{}"), ("^", r"\textasciicircum{}")]
_UNICODE = {"µ": r"\textmu{}", "μ": r"\textmu{}", "°": r"\textdegree{}", "±": r"\textpm{}", "×": r"\texttimes{}",
            "≥": r"$\geq$", "≤": r"$\leq$", "≈": r"$\approx$", "→": r"$\to$", "−": "--", "–": "--", "—": "---",
            "κ": r"$\kappa$", "σ": r"$\sigma$", "Δ": r"$\Delta$", "δ": r"$\delta$", "η": r"$\eta$", "ρ": r"$\rho$",
            "τ": r"$\tau$", "α": r"$\alpha$", "β": r"$\beta$", "γ": r"$\gamma$", "ε": r"$\varepsilon$",
            "²": r"\textsuperscript{2}", "³": r"\textsuperscript{3}", "₂": r"$_2$", "√": r"$\surd$", "…": r"\dots{}",
            "’": "'", "‘": "`", "“": "``", "”": "''"}


def escape_text(s: str) -> str:
    """Escape plain text for LaTeX (pdflatex with T1/utf8): specials, and Greek/maths symbols as math."""
    s = str(s)
    for a, b in _TEXT_MAP:
        s = s.replace(a, b)
    return "".join(_UNICODE.get(ch, ch) for ch in s)


def tex(s: str) -> str:
    """Text that may contain ``$...$`` maths: the maths is kept verbatim, the rest is escaped."""
    parts = re.split(r"(\$[^$]+\$)", str(s))
    return "".join(p if p.startswith("$") and p.endswith("$") and len(p) > 1 else escape_text(p) for p in parts)
