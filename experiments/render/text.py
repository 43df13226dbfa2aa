"""Small text helpers shared by the renderers: ordinals, units, LaTeX escaping."""
from __future__ import annotations

import re
import unicodedata


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


_SPECIALS = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_", "{": r"\{",
             "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}",
             "[": "{[}", "]": "{]}"}   # a bracket after \\ in a table would be read as its optional argument
_UNICODE = {"µ": r"\textmu{}", "μ": r"\textmu{}", "°": r"\textdegree{}", "±": r"\textpm{}", "×": r"\texttimes{}",
            "≥": r"$\geq$", "≤": r"$\leq$", "≈": r"$\approx$", "→": r"$\to$", "−": "--", "–": "--", "—": "---",
            "κ": r"$\kappa$", "σ": r"$\sigma$", "Δ": r"$\Delta$", "δ": r"$\delta$", "η": r"$\eta$", "ρ": r"$\rho$",
            "τ": r"$\tau$", "α": r"$\alpha$", "β": r"$\beta$", "γ": r"$\gamma$", "ε": r"$\varepsilon$",
            "λ": r"$\lambda$", "π": r"$\pi$", "θ": r"$\theta$", "φ": r"$\varphi$", "ω": r"$\omega$",
            "Σ": r"$\Sigma$", "Ω": r"$\Omega$", "∞": r"$\infty$", "≠": r"$\neq$", "·": r"$\cdot$",
            "₂": r"$_2$", "√": r"$\surd$", "…": r"\dots{}",
            "’": "'", "‘": "`", "“": "``", "”": "''", "⌀": r"$\varnothing$", "∅": r"$\varnothing$",
            "✓": r"$\checkmark$", "✔": r"$\checkmark$", "✗": r"$\times$", "•": r"\textbullet{}",
            "\u00a0": "~", "€": r"\texteuro{}", "«": r"\guillemotleft{}", "»": r"\guillemotright{}"}
_UNICODE.update({ch: f"\\textsuperscript{{{d}}}" for ch, d in zip("⁰¹²³⁴⁵⁶⁷⁸⁹", "0123456789")})  # 10⁶, mm²
_UNICODE["⁻"] = r"\textsuperscript{--}"
#: what pdflatex sets with T1 + utf8 beyond ASCII: U+00A0-U+017F (Latin-1 and Latin Extended-A) except the nine
#: letters T1 has no glyph for (found by compiling each; tests/test_report_security.py compiles all of them);
#: anything else is mapped above or written as [U+XXXX]
_LATIN = {chr(c) for c in range(0xA0, 0x180)} - set("ĦħĸĿŀŉŦŧſ")


def _char(ch: str) -> str:
    if ch in _SPECIALS:
        return _SPECIALS[ch]
    if ch in _UNICODE:
        return _UNICODE[ch]
    if " " <= ch < "\x7f" or ch in _LATIN:
        return ch
    cat = unicodedata.category(ch)
    if cat.startswith("Z"):
        return " "
    if cat in ("Cc", "Cf", "Cs", "Co", "Cn", "Mn", "Me"):
        return ""                                # controls, direction marks, joiners, lone combining marks
    return f"\\texttt{{[U+{ord(ch):04X}]}}"        # a character pdflatex cannot set, named so no text is lost


def escape_text(s: str) -> str:
    """Escape plain text for LaTeX (pdflatex with T1/utf8) in one pass: specials and brackets, Greek and
    maths symbols as maths, Latin letters as they are, every other character by its code point ``[U+6771]``;
    line breaks become spaces (a blank line would end a caption's or a heading's argument)."""
    s = re.sub(r"\s+", " ", unicodedata.normalize("NFC", str(s)))
    return "".join(_char(ch) for ch in s)


#: the maths a ``$...$`` span may hold (anything else is set as text): ASCII letters, digits, spacing and
#: operators, one subscript and one superscript per atom, braces, and these control words
MATH_SYMBOLS = frozenset("""alpha beta gamma delta epsilon varepsilon zeta eta theta vartheta kappa lambda mu nu xi pi
    rho sigma tau upsilon phi varphi chi psi omega Gamma Delta Theta Lambda Xi Pi Sigma Phi Psi Omega
    le leq ge geq ne neq approx sim simeq equiv propto pm mp times cdot div circ infty partial nabla sum prod
    lvert rvert ldots cdots dots to rightarrow leftarrow quad qquad surd max min log ln exp sin cos tan""".split())
MATH_ONE_ARG = frozenset("sqrt mathrm mathit mathbf mathcal operatorname text hat bar tilde vec overline".split())
_MATH_TOKEN = re.compile(r"\\[A-Za-z]+|\\[,;:! ]|[A-Za-z0-9]|[ +\-=<>()/.,;:|!*]|[_^{}]")


def safe_math(body: str) -> bool:
    """Whether ``body`` (between the dollars) is in the declared maths subset, so that it can neither run a
    command outside ``MATH_SYMBOLS``/``MATH_ONE_ARG``/``\\frac`` nor stop the compilation: at most 200
    characters, balanced groups, every argument present, at most one sub- and one superscript per atom."""
    if len(body) > 200 or not body.strip():
        return False
    toks, pos = [], 0
    for m in _MATH_TOKEN.finditer(body):
        if m.start() != pos:
            return False
        toks.append(m.group(0))
        pos = m.end()
    if pos != len(body):
        return False
    i = 0

    def group() -> bool:               # '{' sequence '}'
        nonlocal i
        if i >= len(toks) or toks[i] != "{":
            return False
        i += 1
        if not sequence():
            return False
        if i >= len(toks) or toks[i] != "}":
            return False
        i += 1
        return True

    def atom() -> bool:
        nonlocal i
        t = toks[i]
        if t == "{":
            return group()
        if t in ("}", "_", "^"):
            return False
        i += 1
        if t.startswith("\\") and t[1:].isalpha():
            word = t[1:]
            if word == "frac":
                return group() and group()
            if word in MATH_ONE_ARG:
                return group()
            return word in MATH_SYMBOLS
        return True

    def sequence() -> bool:
        nonlocal i
        while i < len(toks) and toks[i] != "}":
            if not atom():
                return False
            seen = set()
            while i < len(toks) and toks[i] in ("_", "^"):
                if toks[i] in seen:
                    return False
                seen.add(toks[i])
                i += 1
                if i >= len(toks) or toks[i] in ("}", "_", "^") or toks[i] == " ":
                    return False
                if toks[i] == "{":
                    if not group():
                        return False
                elif toks[i].startswith("\\") and toks[i][1:].isalpha():
                    word = toks[i][1:]
                    i += 1
                    if word in MATH_ONE_ARG:
                        if not group():
                            return False
                    elif word not in MATH_SYMBOLS:
                        return False
                else:
                    i += 1
        return True

    return sequence() and i == len(toks)


def tex(s: str) -> str:
    """Text that may contain ``$...$`` maths: a span in the declared subset (``safe_math``) is kept as maths,
    everything else (other spans included) is escaped as text."""
    parts = re.split(r"(\$[^$\n]+\$)", str(s))
    return "".join(p if len(p) > 2 and p.startswith("$") and p.endswith("$") and safe_math(p[1:-1])
                   else escape_text(p) for p in parts)


_IDENTIFIER_BREAK = re.compile(r"(?<=[A-Za-z0-9])\\_(?=[A-Za-z0-9])")


def breakable(tex_text: str) -> str:
    """Escaped prose (``tex``) whose identifiers may break across lines after their underscores
    (``circle.levenberg\\_marquardt``: ``\\hspace{0pt}``, robust in moving arguments), which TeX cannot
    hyphenate, so that a paragraph listing methods does not run into the margin."""
    return _IDENTIFIER_BREAK.sub(lambda m: m.group(0) + r"\hspace{0pt}", tex_text)


def joined(words) -> str:
    """'a', 'a and b', 'a, b and c'."""
    words = [str(w) for w in words]
    return " and ".join(words) if len(words) < 3 else ", ".join(words[:-1]) + " and " + words[-1]


def counts_by_group(passing: dict, total: int, noun: str, *, names: bool = True) -> str:
    """Per group (an arc, a scenario ...) how many of ``total`` pass, consecutive groups with the same passing
    set merged: ``counts_by_group({"360° arc": ["a", "b"], "180° arc": ["a", "b"], "45° arc": []}, 8, "arc")``
    -> '2 of 8 on the 360° and 180° arcs (a, b), none on the 45° arc'. ``noun``: the group's noun, pluralised
    with an s when groups merge. No semicolon: the abstract cuts a finding at its first '.' or ';'."""
    runs: list[tuple[list, list]] = []
    for group, ok in passing.items():
        ok = list(ok)
        if runs and runs[-1][1] == ok:
            runs[-1][0].append(group)
        else:
            runs.append(([group], ok))
    parts = []
    for groups, ok in runs:
        where = f"on the {joined(groups)} {noun}{'s' if len(groups) > 1 else ''}"
        if not ok:
            parts.append(f"none {where}")
        else:
            parts.append(f"{len(ok)} of {total} {where}" + (f" ({', '.join(map(str, ok))})" if names else ""))
    return ", ".join(parts)


_PDF_SPECIALS = {"\\": "/", "{": "(", "}": ")", "$": r"\$", "&": r"\&", "%": r"\%", "#": r"\#", "_": r"\_",
                 "~": "-", "^": "-"}


def pdf_text(s: str) -> str:
    """``s`` as plain text for a PDF bookmark (the second argument of ``\\texorpdfstring``): the characters TeX
    would read as commands or groups replaced or escaped, ``$`` maths delimiters dropped, every other
    character (10⁶, µm, σ) kept as Unicode, which hyperref writes into the bookmark as it is."""
    s = re.sub(r"\s+", " ", unicodedata.normalize("NFC", str(s)))
    s = re.sub(r"\$([^$\n]+)\$", lambda m: m.group(1) if safe_math(m.group(1)) else m.group(0), s)
    return "".join(_PDF_SPECIALS.get(ch, ch if (ch >= " " and unicodedata.category(ch)[0] not in "CZ") or ch == " "
                                     else "") for ch in s)


def heading_tex(s: str) -> str:
    """A heading (section, subsection, title) for LaTeX: the typeset text (``tex``) and, for hyperref's PDF
    bookmarks, the plain Unicode text (``pdf_text``): ``\\texorpdfstring{TeX}{text}``, so that a
    \\textsuperscript in '10⁶' neither warns 'Token not allowed in a PDF string' nor reads '106'."""
    typeset = tex(s)
    if typeset == s:
        return typeset
    return f"\\texorpdfstring{{{typeset}}}{{{pdf_text(s)}}}"
