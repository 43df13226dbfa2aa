"""User text is text (the report's side of the platform boundary): titles, sections, captions, findings and
data-set labels never name a file the report reads, are escaped in HTML (attributes included), Markdown and
LaTeX, and the LaTeX compiles without shell escape whatever characters they hold. A hypothesis fuzz test over
Markdown/HTML/LaTeX specials, paths, FIFO names and Unicode asserts all three.

The studies here are written by hand (meta.json, results.csv, report.json, a table and a tiny PNG), so each
build takes a fraction of a second.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import sys
import threading
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from experiments import report
from experiments.render.latex import compile_pdf

PDFLATEX = shutil.which("pdflatex")
needs_pdflatex = pytest.mark.skipif(PDFLATEX is None, reason="pdflatex is not installed (Debian: apt-get install "
                                    "texlive-latex-base texlive-latex-recommended texlive-latex-extra texlive-science lmodern)")


def _png(path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig = plt.figure(figsize=(0.4, 0.3), dpi=50)
    fig.savefig(path)
    plt.close(fig)


def make_study(results: Path, name: str = "hostile", *, title="t", section="s", caption="c", findings="f",
               label="set1", figure="plot.png", verdict_sha: str | None = None) -> Path:
    """A finished study folder as the runner writes it, with the given user text."""
    folder = results / name
    (folder / "tables").mkdir(parents=True)
    rows = pd.DataFrame({"dataset": [label, label], "method": ["circle.kasa", "circle.pratt"], "status": ["ok", "ok"],
                         "radius": [1.0, 1.0000001]})
    rows.to_csv(folder / "results.csv", index=False)
    pd.DataFrame({"dataset": [label], "circle.kasa": [1.0], "circle.pratt": [1.5]}).to_csv(
        folder / "tables" / "table_1.csv", index=False)
    if figure:
        _png(folder / figure)
    digest = hashlib.sha256((folder / "results.csv").read_bytes()).hexdigest()
    (folder / "meta.json").write_text(json.dumps({"n_rows": 2, "status_counts": {"ok": 2}, "git_commit": "abc",
                                                  "date": "2026-01-01", "config_hash": "h", "results_sha256": digest}))
    manifest = {"title": title, "section": section, "order": 10, "findings": findings,
                "tables": [{"caption": caption, "file": "tables/table_1.csv", "unit": "mm", "digits": 3,
                            "colour": "lower_is_better"},
                           {"caption": caption, "file": "tables/table_1.csv", "unit": "mm", "digits": 3}],
                "figures": [{"caption": caption, "file": figure}] if figure else []}
    (folder / "report.json").write_text(json.dumps(manifest))
    if verdict_sha is not None:
        (results / "verify.json").write_text(json.dumps({"agree": True, "date": "2026-01-01", "studies": [
            {"study": name, "agree": True, "rows": 2, "columns": 1, "problems": [], "results_sha256": verdict_sha}]}))
    return folder


class _Text(HTMLParser):
    """The text of a page and every tag with its attributes (character references resolved)."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.text, self.tags = [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def handle_data(self, data):
        self.text.append(data)


def parse(html: str) -> _Text:
    p = _Text()
    p.feed(html)
    p.close()
    return p


def _norm(s: str) -> str:
    return re.sub(r"\s+", " ", s).strip()


ALLOWED_ATTRS = {"id", "class", "href", "src", "alt", "title", "style", "scope", "data-ratio", "data-value", "lang", "charset",
                 "name", "content", "colspan", "rowspan"}


def check_html(html: str, user: list[str], n_figures: int) -> None:
    page = parse(html)
    text = _norm(" ".join(page.text))
    for s in user:
        assert _norm(s) in text, f"user text {s!r} is not in the page as text"
    imgs = [a for t, a in page.tags if t == "img"]
    assert len(imgs) == n_figures and all(a["src"].startswith("data:image/png;base64,") for a in imgs)
    for tag, attrs in page.tags:
        assert tag not in ("iframe", "object", "embed", "link", "base", "form", "input"), tag
        assert set(attrs) <= ALLOWED_ATTRS | ({"type"} if tag == "style" else set()), (tag, attrs)
        assert attrs.get("type", "text/css") == "text/css", (tag, attrs)
        if "href" in attrs:
            assert re.fullmatch(r"#[a-z0-9-]+|explorer\.html", attrs["href"]), attrs
        if "id" in attrs:     # the builder's anchors, and pandas Styler's ids of a table (T_table-N) and its cells
            assert re.fullmatch(r"[a-z0-9-]+|T_table-\d+(_row\d+_col\d+)?", attrs["id"]), attrs
    # a table's own <style> (pandas Styler) holds only the colours of its cells, selected by their ids
    cell = r"#T_table-\d+_row\d+_col\d+"
    for css in re.findall(r"<style type=\"text/css\">(.*?)</style>", html, flags=re.S):
        assert re.fullmatch(rf"(\s*{cell}(,\s*{cell})*\s*\{{\s*background-color:\s*#[0-9a-f]{{6}};\s*"
                            rf"color:\s*#[0-9a-f]{{3}};\s*\}})*\s*", css), css[:300]
    assert sum(t == "script" for t, _ in page.tags) == 1        # the page's own load check, nothing from user text


class Opened:
    """Every path opened while active (an audit hook: io.open and os.open raise the 'open' event)."""
    active: list | None = None
    installed = False

    def __enter__(self):
        if not Opened.installed:
            sys.addaudithook(Opened._hook)
            Opened.installed = True
        Opened.active = []
        return Opened.active

    def __exit__(self, *exc):
        Opened.active = None

    @staticmethod
    def _hook(event, args):
        if event == "open" and Opened.active is not None and isinstance(args[0], (str, bytes, os.PathLike)):
            Opened.active.append(os.path.realpath(os.fsdecode(args[0])))


@pytest.fixture
def secrets(tmp_path):
    """A secret file, a FIFO and a missing path, outside any study folder."""
    secret = tmp_path / "secret.txt"
    secret.write_text("\\GenericError{}{SECRET-WAS-READ}{}{}SECRET-WAS-READ\n")
    fifo = tmp_path / "pipe.png"
    os.mkfifo(fifo)
    return {"secret": secret, "fifo": fifo, "missing": tmp_path / "missing.png"}


def build_in_thread(results: Path, out: Path, timeout: float = 60.0) -> None:
    """Build the report; a read of a FIFO would block: fail instead of hanging."""
    errors = []

    def target():
        try:
            report.build(results, out, log=lambda *a: None)
        except BaseException as exc:  # noqa: BLE001 - re-raised below
            errors.append(exc)
    t = threading.Thread(target=target, daemon=True)
    t.start()
    t.join(timeout)
    assert not t.is_alive(), "the report build blocked (a FIFO read?)"
    if errors:
        raise errors[0]


def hostile_texts(secrets) -> dict[str, str]:
    s, f, m = secrets["secret"], secrets["fifo"], secrets["missing"]
    return {"caption": f"x]({s}) ![y]({f}) ![z]({m}) <img src=x onerror=alert(1)> $\\input{{{s}}}$ ⌀ ✓",
            "findings": f"ok\n![y]({s})\n<!--block:zz-->\n<!--/block-->\n\\immediate\\write18{{touch pwned}} 東京 \u200f",
            "title": f'T"><script>alert(1)</script> $x$ [3pt] ![t]({f}) \\input{{{s}}} % # & _ ~ ^',
            "section": f"Sec <b>bold</b> ![s]({s}) {{#evil}}",
            "label": f'set"1 | ![l]({s}) &amp; <i>'}


def test_hostile_text_reads_no_file_and_stays_text(tmp_path, secrets):
    """Captions/findings naming files (a secret, a FIFO, a missing path) embed nothing, block nothing, fail
    nothing; `<figure id>` and every attribute come from the builder; a findings block marker is text."""
    texts = hostile_texts(secrets)
    results = tmp_path / "results"
    make_study(results, **texts, figure='a" onerror="alert(1).png')
    out = tmp_path / "paper"
    with Opened() as opened:
        build_in_thread(results, out)
    for key in ("secret", "fifo", "missing"):
        assert str(secrets[key].resolve()) not in opened, key
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "SECRET-WAS-READ" not in html and "SECRET-WAS-READ" not in (out / "report.md").read_text()
    check_html(html, list(texts.values()), n_figures=1)
    figures = [a for t, a in parse(html).tags if t == "figure"]
    assert [f["id"] for f in figures] == ["figure-1"]
    explorer = parse((out / "explorer.html").read_text(encoding="utf-8"))     # its tables: text, no markup
    assert _norm(texts["caption"]) in _norm(" ".join(explorer.text))
    assert not [t for t, _ in explorer.tags if t in ("img", "iframe", "object", "embed", "link", "base", "b", "i")]


def test_declared_figure_that_is_a_fifo_is_reported_not_read(tmp_path):
    results = tmp_path / "results"
    folder = make_study(results, figure=None)
    os.mkfifo(folder / "plot.png")
    manifest = json.loads((folder / "report.json").read_text())
    manifest["figures"] = [{"caption": "c", "file": "plot.png"}]
    (folder / "report.json").write_text(json.dumps(manifest))
    build_in_thread(results, tmp_path / "paper")
    assert "**Broken figure**: figure 'plot.png' is not a regular file" in (tmp_path / "paper" / "report.md").read_text()


def test_out_into_a_study_folder_keeps_its_files(tmp_path):
    """`--out results/STUDY` writes the report beside the study's own tables and deletes none of them."""
    results = tmp_path / "results"
    folder = make_study(results)
    before = {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()}
    for _ in range(2):                           # the second build deletes only what the first one wrote
        report.build(results, folder, log=lambda *a: None)
    assert all(p.read_bytes() == data for p, data in before.items())
    assert (folder / "tables" / "table-1.csv").is_file()


def test_a_stale_verdict_is_not_shown_as_agreement(tmp_path):
    results = tmp_path / "results"
    make_study(results, verdict_sha="0" * 64)          # a verdict about other numbers
    report.build(results, tmp_path / "paper", log=lambda *a: None)
    md = (tmp_path / "paper" / "report.md").read_text()
    assert "reproduces" not in md and "agree with these results" not in md
    assert "Reproducibility: out of date" in md
    folder = results / "hostile"
    (results / "verify.json").unlink()
    make_study(tmp_path / "r2", verdict_sha=hashlib.sha256((folder / "results.csv").read_bytes()).hexdigest())
    report.build(tmp_path / "r2", tmp_path / "paper2", log=lambda *a: None)
    assert "this run reproduces" in (tmp_path / "paper2" / "report.md").read_text()


# ------------------------------------------------------------------------------------------------ LaTeX


@needs_pdflatex
def test_hostile_text_compiles_without_shell_escape_and_reads_nothing(tmp_path, secrets):
    texts = hostile_texts(secrets)
    results = tmp_path / "results"
    make_study(results, **texts)
    out = tmp_path / "paper"
    report.build(results, out, log=lambda *a: None)
    env_before = os.environ.get("shell_escape")
    os.environ["shell_escape"] = "t"      # even where the TeX installation enables \write18
    try:
        result = compile_pdf((out / "report.tex").read_text(encoding="utf-8"), out, name="report", runs=1)
    finally:
        if env_before is None:
            os.environ.pop("shell_escape")
        else:
            os.environ["shell_escape"] = env_before
    assert result["ok"], result["errors"][:3] or result["log"][-1500:]
    assert result["inputs"] and not [f for f in result["inputs"] if "secret" in f or "pipe" in f]
    assert "SECRET-WAS-READ" not in result["log"] and not (out / "pwned").exists()


@needs_pdflatex
def test_compile_pdf_never_allows_shell_escape(tmp_path, monkeypatch):
    monkeypatch.setenv("shell_escape", "t")
    source = "\\documentclass{article}\\begin{document}\\immediate\\write18{touch pwned}x\\end{document}\n"
    result = compile_pdf(source, tmp_path)
    assert result["ok"] and not (tmp_path / "pwned").exists()


@needs_pdflatex
def test_every_character_the_escaper_passes_through_compiles(tmp_path):
    """The Latin letters kept as they are, the mapped symbols and an unknown script all set with pdflatex."""
    from experiments.render.latex import standalone_document
    from experiments.render.text import _LATIN, _UNICODE, tex
    text = "".join(sorted(_LATIN)) + " " + "".join(_UNICODE) + " 東京 \u200f ⌀ ✓ \U0001F600"
    result = compile_pdf(standalone_document([tex(text)]), tmp_path)
    assert result["ok"], result["errors"][:3]
    assert not [w for w in result["log"].splitlines() if "Missing character" in w]
    # superscript digits are set as superscripts, never as a code point or a circumflex
    assert tex("N = 10⁶, 10⁻³ mm²") == r"N = 10\textsuperscript{6}, 10\textsuperscript{--}\textsuperscript{3} mm\textsuperscript{2}"


def test_maths_outside_the_declared_subset_is_text():
    from experiments.render.text import safe_math, tex
    for ok in (r"\kappa_2", r"\delta = 10\,e_\mathrm{max}", r"\sigma = 0.01\,R", r"\frac{a}{b}", r"\le 1"):
        assert safe_math(ok) and tex(f"${ok}$") == f"${ok}$"
    for bad in (r"\input{/etc/passwd}", r"x^^5cinput", r"\def\x{1}", r"x_", r"x_a_b", r"\frac{a}", r"\write18{ls}",
                r"\csname input\endcsname", r"a}{b", r"\text{\input{x}}", "#1", "x & y", "%"):
        assert not safe_math(bad), bad
        assert "\\input" not in tex(f"${bad}$") or "textbackslash" in tex(f"${bad}$")


# ------------------------------------------------------------------------------------------------ fuzz

SPECIALS = list("\\{}$&#^_%~[]()<>!*`|\"'=-+.:;/@\n\t ") + ["<!--block:zz-->", "<!--/block-->", "](", "![",
                                                                "$\\input{", "\\write18", "{#id}", "&amp;",
                                                                "⌀", "✓", "東京", "\u200f", "µ", "é", "Ω", "--"]


def _pieces(secrets):
    paths = [str(secrets[k]) for k in secrets] + ["/etc/passwd", "../../x.png", "~/.ssh/id_rsa"]
    return st.lists(st.one_of(st.sampled_from(SPECIALS + paths), st.text(
        st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00\r"), max_size=4)),
        min_size=1, max_size=12).map("".join)


@pytest.mark.slow
def test_fuzz_user_text_is_text_and_reads_no_file(tmp_path_factory):
    secrets_dir = tmp_path_factory.mktemp("secrets")
    secret = secrets_dir / "secret.txt"
    secret.write_text("SECRET-WAS-READ")
    fifo = secrets_dir / "pipe.png"
    os.mkfifo(fifo)
    sec = {"secret": secret, "fifo": fifo, "missing": secrets_dir / "missing.png"}
    text = _pieces(sec).filter(lambda s: _norm(s) != "")

    @settings(max_examples=15, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
    @given(title=text, section=text, caption=text, findings=text, label=text)
    def run(title, section, caption, findings, label):
        root = tmp_path_factory.mktemp("fuzz")
        make_study(root / "results", title=title, section=section, caption=caption, findings=findings, label=label)
        with Opened() as opened:
            build_in_thread(root / "results", root / "paper")
        assert not {str(p.resolve()) for p in sec.values()} & set(opened)
        html = (root / "paper" / "report.html").read_text(encoding="utf-8")
        assert "SECRET-WAS-READ" not in html
        check_html(html, [title, section, caption, findings, label], n_figures=1)
        if PDFLATEX:
            result = compile_pdf((root / "paper" / "report.tex").read_text(encoding="utf-8"), root / "paper",
                                 name="report")
            assert result["ok"], (result["errors"][:3], result["log"][-800:])
            assert "SECRET-WAS-READ" not in result["log"] and not [f for f in result["inputs"] if "secrets" in f]
        shutil.rmtree(root)

    run()
