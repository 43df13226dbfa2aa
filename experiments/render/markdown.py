"""Markdown text of user strings and tables (:func:`md_escape`, :func:`markdown_table`): what the summaries and the
report's page (:mod:`experiments.render.page`) both write, without the page's HTML machinery (jinja2, markdown-it)."""
from __future__ import annotations

import re

_MD_SPECIAL = re.compile(r"[\\`*\[\]<>!|&~{}#]|(?<![A-Za-z0-9])_|_(?![A-Za-z0-9])")


def md_escape(text) -> str:
    """``text`` as literal Markdown text: the characters that could start a link, an image, HTML, code,
    emphasis, an entity or a table cell backslash-escaped (CommonMark lets any ASCII punctuation be escaped;
    an underscore inside a word cannot open emphasis and stays as it is), whitespace and line breaks folded
    into one space (so user text never starts a line, hence never a heading, list or block)."""
    return _MD_SPECIAL.sub(lambda m: "\\" + m.group(0), re.sub(r"\s+", " ", str(text))).strip()


def md_code(text) -> str:
    """``text`` as a Markdown code span showing it literally (a command to copy): no backslash escape (a code span
    shows backslashes as they are), a fence of one backtick more than the longest run of backticks in it, padded
    with a space where it starts or ends with a backtick or a space (CommonMark 0.31, 6.1 "Code spans"); a line
    break (or another whitespace character) becomes a space, and runs of spaces are kept (a path may hold two)."""
    text = re.sub(r"[^\S ]", " ", str(text))
    fence = "`" * (max(map(len, re.findall(r"`+", text)), default=0) + 1)
    pad = " " if text[:1] in ("`", " ") or text[-1:] in ("`", " ") else ""
    return f"{fence}{pad}{text}{pad}{fence}"


def markdown_table(df, floatfmt: str = ".7g", *, escape: bool = True, formats: dict | None = None) -> str:
    """``df`` as a GitHub (pipe) Markdown table by pandas' ``DataFrame.to_markdown`` (tabulate): floats in
    ``floatfmt`` (NaN empty) or, for a column ``formats`` names, by its function (value -> text), every other cell
    and the headers as text, ``md_escape``d unless ``escape`` is false (a table of the builder's own words); number
    columns right-aligned."""
    import numpy as np
    import pandas as pd
    text = md_escape if escape else str

    def cell(v) -> str:
        if isinstance(v, (float, np.floating)):
            return "" if v != v else format(v, floatfmt)
        return text(v)
    own = [(formats or {}).get(c) for c in df.columns]
    shown = pd.DataFrame([[f(v) if f else cell(v) for f, v in zip(own, row)] for row in df.itertuples(index=False)],
                         columns=range(df.shape[1]))
    align = ["right" if pd.api.types.is_numeric_dtype(t) and not pd.api.types.is_bool_dtype(t) else "left"
             for t in df.dtypes]
    return shown.to_markdown(index=False, headers=[text(c) for c in df.columns], tablefmt="pipe",
                             disable_numparse=True, colalign=align)
