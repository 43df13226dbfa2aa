"""LaTeX table fragments that compile and fit a one-column A4 page (2.5 cm margins, 16 cm text width).

``latex_table(df, columns, caption=..., label=...)`` returns a ``table`` (or ``longtable``) fragment written by
pandas' ``Styler.to_latex``: booktabs rules, siunitx ``S`` columns for numbers (``table-format`` measured here
from the formatted data, exponents as ``4.07e8`` which siunitx prints as 4.07 × 10⁸), ``p{}`` columns for long
text (widths and font size chosen here so that the table fits), units in the headers as ``\\si{}``, repeated
leading keys as group heading rows. Captions and headers may contain ``$...$`` maths. The preamble the
fragments need is ``PREAMBLE`` (the ``paper/report.tex`` template includes it).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from pandas.io.formats.style import Styler

from experiments.render.text import escape_text, human_unit, si_unit, tex

TEXT_WIDTH_PT = 455.24              #: 16 cm in TeX points
FIT_BUDGET_PT = 0.93 * TEXT_WIDTH_PT  #: what the width estimate may use (it is only an estimate)
PREAMBLE = r"""\usepackage[T1]{fontenc}
\usepackage[utf8]{inputenc}
\usepackage{lmodern}
\usepackage[a4paper,margin=2.5cm]{geometry}
\usepackage{amsmath}
\usepackage{amssymb}
\usepackage{booktabs}
\usepackage{multirow}
\usepackage{longtable}
\usepackage{array}
\usepackage{graphicx}
\usepackage{caption}
\usepackage{siunitx}
\sisetup{group-digits=none, table-number-alignment=center, exponent-product=\times,
         round-mode=none, detect-weight=true}
\captionsetup{font=small, labelfont=bf}
"""
KINDS = ("text", "number", "integer", "auto")
#: average glyph width relative to the font size (Latin Modern, mixed text) used to estimate widths
_EM_PER_CHAR = 0.5
_SIZES = (("small", 9.0), ("footnotesize", 8.0), ("scriptsize", 7.0))


class TableTooWide(ValueError):
    """The table cannot fit the text width at the smallest allowed font: split it or draw a figure."""


@dataclass
class Column:
    """How one DataFrame column is shown. ``digits``: significant digits of numbers (default 3);
    ``decimals`` fixes the decimals instead; ``exponent`` forces (True) or forbids (False) 4.07e8 form
    (default: chosen from the data's range); ``exact``: each number as given (0.029807 stays 0.029807,
    without padding zeros that would claim digits the source does not have); ``width``: a ``p{}`` width for text
    (e.g. '4cm'); ``group``: the column's values as heading rows above each run of equal values, not as a column;
    ``missing``: what an empty cell shows (explain it in ``notes``)."""
    name: str
    header: str | None = None
    unit: str | None = None
    kind: str = "auto"
    digits: int = 3
    decimals: int | None = None
    exponent: bool | None = None
    width: str | None = None
    group: bool = False
    missing: str = "--"
    exact: bool = False          #: print each number as given (shortest round-trip form, e.g. published values)

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"column {self.name!r}: kind must be one of {', '.join(KINDS)}, got {self.kind!r}")


@dataclass
class _Formatted:
    cells: list[str]
    spec: str
    header: str
    est_chars: int
    numeric: bool = False
    notes: list[str] = field(default_factory=list)


def _is_number_column(s: pd.Series) -> bool:
    return pd.api.types.is_numeric_dtype(s) and not pd.api.types.is_bool_dtype(s)


def _header_lines(col: Column, max_chars: int = 11) -> list[str]:
    """The header's words packed into lines of at most ``max_chars`` characters (maths kept whole), and the
    unit on a line of its own: a narrow number column keeps a narrow header."""
    text = col.header if col.header is not None else col.name.replace("_", " ")
    words = re.findall(r"\$[^$]+\$|\S+", text)
    lines: list[str] = []
    for w in words:
        if lines and len(_plain(lines[-1])) + 1 + len(_plain(w)) <= max_chars:
            lines[-1] += " " + w
        else:
            lines.append(w)
    return lines or [""]


def _plain(s: str) -> str:
    """Approximate printed text of a header piece (maths counted by its letters)."""
    return re.sub(r"\\[a-zA-Z]+|[{}$_^]", "", s)


def _header(col: Column, stacked: bool) -> tuple[str, int]:
    """(LaTeX header, its width in characters)."""
    lines = _header_lines(col) if stacked else [col.header if col.header is not None else col.name.replace("_", " ")]
    cells = [tex(x) for x in lines] + ([f"[{si_unit(col.unit)}]"] if col.unit else [])
    width = max([len(_plain(x)) for x in lines] + ([len(human_unit(col.unit)) + 2] if col.unit else []))
    if len(cells) == 1:
        return cells[0], width
    return "\\begin{tabular}[b]{@{}c@{}}" + r" \\ {}".join(cells) + "\\end{tabular}", width


def _format_numbers(values: np.ndarray, col: Column) -> tuple[list[str | None], str, bool]:
    """Number strings siunitx parses, and the table-format that fits them all."""
    finite = values[np.isfinite(values)]
    integer = col.kind == "integer" or (col.kind == "auto" and len(finite) and np.all(finite == np.round(finite))
                                        and np.max(np.abs(finite)) < 1e9 and col.decimals is None)
    if integer:
        strs = [None if not np.isfinite(v) else f"{int(round(v))}" for v in values]
    elif col.exact:
        strs = [None if not np.isfinite(v) else np.format_float_positional(float(v), trim="-") for v in values]
    elif col.decimals is not None and not col.exponent:
        strs = [None if not np.isfinite(v) else f"{v:.{col.decimals}f}" for v in values]
    else:
        strs = [None if not np.isfinite(v) else _number_str(v, col.digits, col.exponent) for v in values]
    strs = [None if s is None else (s[1:] if s.startswith("-") and float(s) == 0 else s) for s in strs]
    fmt = _table_format([s for s in strs if s is not None])
    return strs, fmt, integer


def _number_str(v: float, digits: int, exponent: bool | None) -> str:
    """``digits`` significant digits; 4.07e8 form when forced or when |v| >= 1e5 or 0 < |v| < 1e-3."""
    a = abs(v)
    if exponent or (exponent is None and a != 0 and (a >= 1e5 or a < 1e-3)):
        return _exp_str(v, digits)
    if a == 0:
        return "0"
    dec = max(0, digits - 1 - math.floor(math.log10(a)))
    return f"{v:.{dec}f}"


def _exp_str(v: float, digits: int) -> str:
    if v == 0:
        return "0"
    m, e = f"{v:.{max(digits - 1, 0)}e}".split("e")
    return f"{m}e{int(e)}"


def _format_chars(fmt: str) -> int:
    """Printed width of a siunitx table-format in digit widths (an exponent prints as ×10^k: ~6 + k, measured
    on the scaling table's 2.248 × 10^-1 cells)."""
    mant, _, exp = fmt.partition("e")
    i, _, d = mant.lstrip("-").partition(".")
    n = int(i) + int(d or 0) + (1 if int(d or 0) else 0) + (1 if mant.startswith("-") else 0)
    return n + (6 + int(exp.lstrip("-")) if exp else 0)


def _table_format(strs: list[str]) -> str:
    sign = any(s.startswith("-") for s in strs)
    ints, decs, exps, esign = 1, 0, 0, False
    for s in strs:
        body = s.lstrip("-+")
        mant, _, exp = body.partition("e")
        i, _, d = mant.partition(".")
        ints, decs = max(ints, len(i)), max(decs, len(d))
        if exp:
            esign |= exp.startswith("-")
            exps = max(exps, len(exp.lstrip("-+")))
    out = ("-" if sign else "") + f"{ints}.{decs}"
    if exps:
        out += "e" + ("-" if esign else "") + str(exps)
    return out


def _format_column(df: pd.DataFrame, col: Column) -> _Formatted:
    s = df[col.name]
    numeric = col.kind in ("number", "integer") or (col.kind == "auto" and _is_number_column(s))
    if numeric:
        values = pd.to_numeric(s, errors="coerce").to_numpy(float)
        strs, fmt, _ = _format_numbers(values, col)
        cells = [f"{{{tex(col.missing)}}}" if v is None else v for v in strs]
        chars = max(_format_chars(fmt), len(col.missing))
        header, hchars = _header(col, stacked=True)
        return _Formatted(cells, f"S[table-format={fmt}]", header, max(chars, hchars), numeric=True)   # braced by Styler
    texts = ["" if (v is None or (isinstance(v, float) and math.isnan(v))) else str(v) for v in s]
    cells = [tex(t) if t else tex(col.missing) for t in texts]
    chars = max([len(t) for t in texts] + [1])
    header, hchars = _header(col, stacked=bool(col.width) or chars < 14)
    if col.width:
        return _Formatted(cells, f">{{\\raggedright\\arraybackslash}}p{{{col.width}}}", header,
                          _chars_of_width(col.width))
    return _Formatted(cells, "l", header, max(chars, hchars))


def _chars_of_width(width: str, size_pt: float = 9.0) -> int:
    num = float("".join(ch for ch in width if ch.isdigit() or ch == "."))
    pt = num * {"cm": 28.45, "mm": 2.845, "in": 72.27, "pt": 1.0, "em": size_pt}.get(width.lstrip("0123456789."), 28.45)
    return int(pt / (size_pt * _EM_PER_CHAR))


def estimated_width_pt(chars: list[int], size_pt: float) -> float:
    """A rough width of a tabular: characters x glyph width + 2 x 6 pt of padding per column."""
    return sum(c * size_pt * _EM_PER_CHAR + 12.0 for c in chars)


def _fit_text_widths(df, columns, size_pt):
    """Give unwrapped long text columns a p{} width so that the estimated table width fits the page."""
    fixed = []
    for c in columns:
        f = _format_column(df, c)
        fixed.append((c, f))
    total = estimated_width_pt([f.est_chars for _, f in fixed], size_pt)
    if total <= FIT_BUDGET_PT:
        return columns
    wrappable = [(c, f) for c, f in fixed if not f.numeric and c.width is None and f.est_chars > 12]
    longest_word = {c.name: max([len(w) for v in df[c.name] for w in str(v).split()] + [4])
                    for c, _ in wrappable}
    if not wrappable:
        return columns
    spare = FIT_BUDGET_PT - estimated_width_pt([f.est_chars for c, f in fixed if (c, f) not in wrappable], size_pt)
    spare -= 12.0 * len(wrappable)
    share = max(spare / len(wrappable), 3.0 * 28.45 / 2)       # never narrower than 1.5 cm
    out = []
    for c in columns:
        if any(c is w for w, _ in wrappable):
            pt = max(share, longest_word[c.name] * size_pt * _EM_PER_CHAR * 1.25)   # an unbreakable word fits
            c = Column(**{**c.__dict__, "width": f"{pt / 28.45:.2f}cm"})
        out.append(c)
    return out


def latex_table(df: pd.DataFrame, columns: list[Column] | None = None, *, caption: str, label: str,
                notes: list[str] | None = None, size: str | None = None, long: bool | None = None,
                max_rows: int = 35) -> str:
    """A booktabs table fragment for ``df``, serialised by pandas' ``Styler.to_latex`` (``siunitx=True``,
    ``hrules=True``) from the cells and column format this module chooses.

    ``columns``: the ``Column`` of each shown column, in order (default: every column, kinds from dtypes); the
    values of the ``group`` columns are not a column but an italic heading row above each group of rows.
    ``size``: 'small', 'footnotesize' or 'scriptsize' (default: the largest whose estimated width fits).
    ``long``: a ``longtable`` split over pages (default: when more than ``max_rows`` printed rows, heading
    rows included).
    ``notes``: lines under the table (e.g. what an empty cell means).
    """
    if columns is None:
        columns = [Column(str(c)) for c in df.columns]
    missing = [c.name for c in columns if c.name not in df.columns]
    if missing:
        raise ValueError(f"latex_table {label!r}: no column(s) {missing} in the table (it has {list(df.columns)})")
    df = df.reset_index(drop=True)
    sizes = [s for s in _SIZES if size is None or s[0] == size]
    if not sizes:
        raise ValueError(f"size must be one of {[s for s, _ in _SIZES]}, got {size!r}")
    for size_name, size_pt in sizes:
        fitted = _fit_text_widths(df, [c for c in columns if not c.group], size_pt)
        fmts = [_format_column(df, c) for c in fitted]
        if estimated_width_pt([f.est_chars for f in fmts], size_pt) <= FIT_BUDGET_PT:
            break
    else:
        raise TableTooWide(f"table {label!r} is about {estimated_width_pt([f.est_chars for f in fmts], size_pt):.0f} pt "
                           f"wide at \\{size_name} (the page has {TEXT_WIDTH_PT:.0f} pt): split its columns into two "
                           "tables, shorten its headers or draw it as a figure")
    groups = [c.name for c in columns if c.group]
    keys = [tuple(k) for k in df[groups].itertuples(index=False)] if groups else []
    starts = {i: k for i, k in enumerate(keys) if i == 0 or k != keys[i - 1]}   # rows that open a group
    long = len(df) + len(starts) > max_rows if long is None else long
    cells = pd.DataFrame({j: f.cells for j, f in enumerate(fmts)})
    styler = Styler(cells).hide(axis="index").format_index(lambda j: fmts[j].header, axis=1)
    spec = "@{}" + "".join(f.spec for f in fmts) + "@{}"
    width_pt = min(estimated_width_pt([f.est_chars for f in fmts], size_pt), FIT_BUDGET_PT) - 12.0
    note_text = "\n".join(tex(n) for n in notes or [])
    if long:
        body = styler.to_latex(column_format=spec, hrules=True, siunitx=True, environment="longtable",
                               caption=tex(caption), label=f"tab:{label}")
        body = _group_rows(_continued(body, tex(caption), len(fmts)), r"\endlastfoot", starts, len(fmts), width_pt)
        lines = [f"\\begingroup\\{size_name}", body.rstrip()]
        if note_text:
            lines += [r"\vspace{-0.5\baselineskip}", r"\noindent\begin{minipage}{\linewidth}\footnotesize", note_text,
                      r"\end{minipage}\par\medskip"]
        return "\n".join(lines + [r"\endgroup", ""])
    body = styler.to_latex(column_format=spec, hrules=True, siunitx=True)
    lines = [r"\begin{table}[htbp]", r"\centering", f"\\{size_name}",
             f"\\caption{{{tex(caption)}}}\\label{{tab:{label}}}",
             _group_rows(body, r"\midrule", starts, len(fmts), width_pt).rstrip()]
    if note_text:
        lines += [r"\par\smallskip", r"\noindent\begin{minipage}{\linewidth}\footnotesize", note_text, r"\end{minipage}"]
    return "\n".join(lines + [r"\end{table}", ""])


def _group_rows(latex: str, head_end: str, starts: dict, ncol: int, width_pt: float) -> str:
    """Styler's table with a heading row (the group columns' values, italic, across the table) above each row
    that opens a group, and a little space between groups: what ``Styler`` cannot write. Styler writes one
    line per body row, after the line ``head_end``."""
    if not starts:
        return latex
    lines = latex.split("\n")
    first = lines.index(head_end) + 1
    out = lines[:first]
    for i, line in enumerate(lines[first:], start=0):
        if i in starts:
            if not line.endswith(" \\\\"):
                raise RuntimeError(f"pandas' Styler wrote row {i} over more than one line: {line!r}")
            out += ([r"\addlinespace"] if i else []) + [
                f"\\multicolumn{{{ncol}}}{{@{{}}>{{\\raggedright\\arraybackslash}}p{{{width_pt:.0f}pt}}@{{}}}}"
                f"{{\\itshape {'; '.join(tex(k) for k in starts[i])}}} \\\\"]
        out.append(line)
    return "\n".join(out)


def _continued(longtable: str, caption: str, ncol: int) -> str:
    """Styler's longtable with this report's continuation lines: "Table N (continued)" above the repeated head
    (Styler repeats the whole caption) and "continued on the next page" below a broken page."""
    marks = {f"\\caption[]{{{caption}}} \\\\\n": f"\\multicolumn{{{ncol}}}{{@{{}}l}}{{\\itshape Table \\thetable{{}} (continued)}} \\\\\n",
             f"\\multicolumn{{{ncol}}}{{r}}{{Continued on next page}} \\\\\n":
             f"\\multicolumn{{{ncol}}}{{@{{}}r}}{{\\itshape continued on the next page}} \\\\\n"}
    for old, new in marks.items():
        if longtable.count(old) != 1:
            raise RuntimeError(f"pandas' Styler longtable has changed: no line {old.strip()!r} to replace")
        longtable = longtable.replace(old, new)
    return longtable


def standalone_document(fragments: list[str], *, title: str | None = None) -> str:
    """A complete A4 document around table fragments (for tests and quick previews)."""
    parts = [r"\documentclass[10pt]{article}", PREAMBLE, r"\begin{document}"]
    if title:
        parts.append(f"\\section*{{{escape_text(title)}}}")
    parts += [f + "\n\\clearpage" for f in fragments]
    parts.append(r"\end{document}")
    return "\n".join(parts) + "\n"


__all__ = ["Column", "TableTooWide", "compile_pdf", "PREAMBLE", "TEXT_WIDTH_PT", "latex_table", "standalone_document", "human_unit"]


def compile_pdf(tex_source: str, workdir, *, name: str = "doc", pdflatex: str = "pdflatex",
                runs: int = 1, timeout: float = 120.0) -> dict:
    """Compile ``tex_source`` with pdflatex in ``workdir``, always with ``-no-shell-escape`` (no
    ``\\write18``, whatever the TeX installation's default); return ``{"ok", "log", "overfull", "errors",
    "warnings", "pdf"}`` where ``overfull`` lists ``(kind, points, line text)`` of every overfull
    \\hbox/\\vbox in the log, ``warnings`` every "LaTeX Warning" line (e.g. "Float too large") and ``inputs``
    every file TeX read (``-recorder``)."""
    import re
    import subprocess
    from pathlib import Path
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    from methods.files import write_atomic
    write_atomic(workdir / f"{name}.tex", tex_source, fsync=False)
    proc = None
    for _ in range(runs):
        proc = subprocess.run([pdflatex, "-no-shell-escape", "-recorder", "-interaction=nonstopmode", "-halt-on-error",
                               f"{name}.tex"], cwd=workdir, capture_output=True, timeout=timeout,
                              stdin=subprocess.DEVNULL)
    log = (workdir / f"{name}.log").read_text(encoding="latin-1") if (workdir / f"{name}.log").exists() else ""
    overfull = [(m.group(1), float(m.group(2)), m.group(0)) for m in
                re.finditer(r"Overfull \\([hv])box \(([0-9.]+)pt too (?:wide|high)\)[^\n]*", log)]
    errors = re.findall(r"^! .*$", log, flags=re.M)
    fls = workdir / f"{name}.fls"
    inputs = sorted({line[6:] for line in fls.read_text(encoding="utf-8", errors="replace").splitlines()
                     if line.startswith("INPUT ")}) if fls.exists() else []
    warnings = re.findall(r"^(?:LaTeX|Package \w+) Warning: .*$", log, flags=re.M)
    return {"ok": proc.returncode == 0 and (workdir / f"{name}.pdf").exists(), "log": log, "overfull": overfull,
            "errors": errors, "warnings": warnings, "inputs": inputs, "pdf": workdir / f"{name}.pdf"}
