"""Checks of an HTML report rendered by headless Chromium (reusable: point ``check_html_report`` at any
report.html).

Chromium loads the page with a small script appended (a copy of the page is written next to the original, so
relative image paths still resolve); after the load event the script writes a JSON verdict into the DOM,
and ``--dump-dom`` returns it: every <img> with its naturalWidth, the figure/table captions, the table of
contents' links and whether each anchor target exists.
"""
from __future__ import annotations

import json
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

from conftest import REPO, run_once_per_session

CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--virtual-time-budget=10000"]

PROBE = r"""<script>
window.addEventListener('load', function () {
  var imgs = Array.prototype.map.call(document.images, function (im) {
    return {src: (im.getAttribute('src') || '').slice(0, 80), ok: im.complete && im.naturalWidth > 0,
            w: im.naturalWidth};
  });
  var caps = Array.prototype.map.call(document.querySelectorAll('figcaption, caption'), function (c) {
    return {tag: c.tagName.toLowerCase(), text: c.textContent.trim().slice(0, 120)};
  });
  var toc = document.querySelector('nav#toc, nav.toc, #toc');
  var links = toc ? Array.prototype.map.call(toc.querySelectorAll('a[href^="#"]'), function (a) {
    var id = decodeURIComponent(a.getAttribute('href').slice(1));
    return {href: id, text: a.textContent.trim(), target: !!document.getElementById(id)};
  }) : null;
  var out = document.createElement('pre');
  out.id = '__report_check__';
  out.textContent = JSON.stringify({images: imgs, captions: caps, toc: links, title: document.title});
  document.body.appendChild(out);
});
</script>"""


#: the studies that declare rankings: the report of their quick run is what tests/test_report_paper.py and
#: tests/test_explorer.py check
RANKED_STUDIES = ("published", "noise", "scaling")


def ranked_quick_run(tmp_path_factory) -> Path:
    """The results folder (its report in ``paper/``) of ``python -m experiments.run published noise scaling --quick``,
    run once per test session for the report and explorer tests; read only."""
    return run_once_per_session(tmp_path_factory, "ranked-quick", [*RANKED_STUDIES, "--quick"], cwd=REPO)


def chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")


def _run(args, timeout=90):
    with tempfile.TemporaryDirectory(prefix="chromium-profile-") as profile:
        return subprocess.run([chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args],
                              capture_output=True, text=True, timeout=timeout)


def probe(html_path: Path) -> dict:
    """Load ``html_path`` in headless Chromium and return the probe's JSON (images, captions, toc)."""
    html_path = Path(html_path).resolve()
    text = html_path.read_text(encoding="utf-8")
    probed = html_path.with_name(f".probe-{html_path.name}")
    probed.write_text(text.replace("</body>", PROBE + "</body>") if "</body>" in text else text + PROBE,
                      encoding="utf-8")
    try:
        proc = _run(["--dump-dom", probed.as_uri()])
    finally:
        probed.unlink(missing_ok=True)
    m = re.search(r'<pre id="__report_check__">(.*?)</pre>', proc.stdout, flags=re.S)
    if not m:
        raise RuntimeError(f"Chromium returned no probe result (exit {proc.returncode}): {proc.stderr[-500:]}")
    import html as _html
    return json.loads(_html.unescape(m.group(1)))


def check_html_report(html_path: Path, *, min_figures: int = 1, min_tables: int = 1) -> list[str]:
    """Problems found in the rendered report (empty list: it passed). Checks: every <img> loads
    (naturalWidth > 0); figure captions are numbered 'Figure 1', 'Figure 2', ... and table captions
    'Table 1', ... in order; a table of contents (nav#toc) exists and each of its links has a target."""
    r = probe(html_path)
    problems = []
    bad = [i["src"] for i in r["images"] if not i["ok"]]
    if bad:
        problems.append(f"{len(bad)} of {len(r['images'])} images do not load: {bad[:3]}")
    for tag, word, minimum in (("figcaption", "Figure", min_figures), ("caption", "Table", min_tables)):
        caps = [c["text"] for c in r["captions"] if c["tag"] == tag]
        nums = [int(m.group(1)) if (m := re.match(rf"{word} (\d+)[.:]", c)) else None for c in caps]
        if len(caps) < minimum:
            problems.append(f"{len(caps)} {word.lower()} captions, expected at least {minimum}")
        if None in nums:
            problems.append(f"unnumbered {word.lower()} caption(s): {[c for c, n in zip(caps, nums) if n is None][:3]}")
        elif nums != list(range(1, len(nums) + 1)):
            problems.append(f"{word} numbers are not 1..{len(nums)} in order: {nums}")
    if r["toc"] is None:
        problems.append("no table of contents (nav#toc)")
    elif not r["toc"]:
        problems.append("the table of contents has no links")
    else:
        dead = [lnk["href"] for lnk in r["toc"] if not lnk["target"]]
        if dead:
            problems.append(f"table-of-contents links without a target: {dead[:5]}")
    return problems


def screenshot(html_path: Path, png: Path, *, width: int = 1200, height: int = 1600, scroll_to: str | None = None):
    """A PNG screenshot of the report; with ``scroll_to`` (an element id) the page starts at that element
    (everything above it is hidden in a temporary copy: scrolling is unreliable in headless screenshots)."""
    html_path = Path(html_path).resolve()
    target = html_path
    if scroll_to:
        text = html_path.read_text(encoding="utf-8")
        target = html_path.with_name(f".shot-{html_path.name}")
        js = ("<script>(function(){var e=document.getElementById('" + scroll_to + "');"
              "if(!e){return;}while(e.parentElement&&e.parentElement!==document.body){e=e.parentElement;}"
              "var p=e.previousElementSibling;while(p){p.style.display='none';p=p.previousElementSibling;}})();"
              "</script>")
        target.write_text(text.replace("</body>", js + "</body>"), encoding="utf-8")
    try:
        proc = _run([f"--screenshot={Path(png).resolve()}", f"--window-size={width},{height}",
                     "--hide-scrollbars", target.as_uri()])
    finally:
        if target != html_path:
            target.unlink(missing_ok=True)
    if not Path(png).exists():
        raise RuntimeError(f"Chromium wrote no screenshot (exit {proc.returncode}): {proc.stderr[-500:]}")
    return Path(png)
