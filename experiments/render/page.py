"""The report as one document with two outputs, ``report.md`` and a self-contained ``report.html``.

The report is assembled as a list of parts (headings, prose, ready blocks such as tables, figures); each part
knows its Markdown and its HTML. Nothing is ever parsed back out of Markdown: a figure is embedded only because
the builder added it with the path of a file it wrote itself, so user text (titles, captions, findings, data-set
labels) can never name a file to read. User text goes into prose through :func:`md_escape` (every Markdown
special backslash-escaped, line breaks folded) and the prose becomes HTML through markdown-it-py with raw HTML
and images disabled; the page itself is the jinja2 template ``templates/report.html.j2`` with autoescaping,
so every user string is text in the HTML, attributes included.
"""
from __future__ import annotations

import base64
import re
from dataclasses import dataclass
from pathlib import Path

import jinja2
from markdown_it import MarkdownIt
from markupsafe import Markup, escape

from experiments.render.markdown import markdown_table, md_escape  # noqa: F401  (this module's API too)


def _markdown() -> MarkdownIt:
    md = MarkdownIt("commonmark", {"html": False, "linkify": False, "typographer": False})
    md.disable("image")          # the prose never shows an image: figures are parts of their own
    return md


_MD = _markdown()
TEMPLATES = Path(__file__).with_name("templates")


def html_template(name: str) -> jinja2.Template:
    """An HTML page template of ``templates/``, autoescaping every value (user text is text, attributes
    included); a missing value is an error, not an empty string."""
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATES)), autoescape=True,
                             undefined=jinja2.StrictUndefined)
    return env.get_template(name)


def prose_html(markdown: str) -> Markup:
    """Prose (the builder's Markdown with escaped user text) as HTML; raw HTML is shown as text."""
    return Markup(_MD.render(markdown))


@dataclass
class Part:
    kind: str            # heading | prose | block | figure
    md: str
    html: Markup


class Document:
    """Parts in order; ``markdown()`` and ``html()`` render all of them."""

    def __init__(self):
        self.parts: list[Part] = []

    def heading(self, level: int, text: str, ident: str = "", code: str = "") -> None:
        """A heading of user text; ``code`` (a study's name) is shown in code font; ``ident``: the anchor."""
        if ident and not re.fullmatch(r"[a-z0-9-]+", ident):
            raise ValueError(f"heading anchor {ident!r} must be lower-case letters, digits and hyphens")
        shown = (f" (`{code}`)" if "`" not in code else f" ({md_escape(code)})") if code else ""
        md = "#" * level + " " + md_escape(text) + shown + (f" {{#{ident}}}" if ident else "")
        html = Markup("<h{l}{i}>{t}{c}</h{l}>").format(
            l=level, i=Markup(' id="{}"').format(ident) if ident else "", t=text,
            c=Markup(" (<code>{}</code>)").format(code) if code else "")
        self.parts.append(Part("heading", md, html))

    def prose(self, markdown: str) -> None:
        """A paragraph (or list) in Markdown written by the builder, user text passed through ``md_escape``."""
        self.parts.append(Part("prose", markdown, prose_html(markdown)))

    def block(self, html: Markup, md: str) -> None:
        """Ready HTML (built with escaping, e.g. a table) and its Markdown form."""
        if not isinstance(html, Markup):
            raise TypeError("Document.block takes markupsafe.Markup built with escaping, not a plain string")
        self.parts.append(Part("block", md, html))

    def figure(self, png: Path, number: int, caption: str, rel: str) -> None:
        """Figure ``number``: ``png`` is a file the builder wrote (``rel``: its path relative to the report)."""
        data = base64.b64encode(Path(png).read_bytes()).decode("ascii")
        html = Markup('<figure id="figure-{n}"><img alt="Figure {n}: {c}" src="data:image/png;base64,{d}">'
                      "<figcaption>Figure {n}: {c}</figcaption></figure>").format(n=int(number), c=caption, d=data)
        md = f"![Figure {int(number)}: {md_escape(caption)}]({rel})"
        self.parts.append(Part("figure", md, html))

    def markdown(self) -> str:
        return "\n\n".join(p.md for p in self.parts) + "\n"

    def html(self, title: str) -> str:
        """The page (``templates/report.html.j2``, style sheet included)."""
        return html_template("report.html.j2").render(title=title, parts=self.parts)


def escape_html(text) -> Markup:
    return escape(text)
