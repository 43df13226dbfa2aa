"""docs/experiments.md's list of the default studies quotes no stale result: a finding it quotes is, word for word,
the one the committed results hold (their ``report.json``, what the report prints), and every default study it
lists has its section in the committed report, where the page sends the reader for the numbers. (It quoted the
roundness findings of an older run: "(52 rows) ... LSCI 6.9 %" where the committed results say 77 rows and
6.5 %.)"""
import json
import re

from conftest import REPO

from experiments import config as configs


def _studies_section() -> str:
    text = (REPO / "docs" / "experiments.md").read_text(encoding="utf-8")
    return text.split("The default studies (`results/`", 1)[1].split("`nist_circle` (not default", 1)[0]


def _flat(text: str) -> str:
    return " ".join(text.split())


def test_a_quoted_finding_is_the_committed_one():
    findings = {p.parent.name: _flat(json.loads(p.read_text(encoding="utf-8")).get("findings") or "")
                for p in (REPO / "results").glob("*/report.json")}
    for quote in re.findall(r'"([A-Z][^"]{30,})"', _studies_section()):   # a quoted sentence
        assert any(_flat(quote) in f for f in findings.values()), \
            f"docs/experiments.md quotes a finding no committed study holds: {quote[:120]!r}"


def test_every_default_study_is_listed_and_has_its_section_in_the_committed_report():
    section = _studies_section()
    report = (REPO / "paper" / "report.md").read_text(encoding="utf-8")
    for name in configs.available():
        if configs.load(name).get("default"):
            assert f"* `{name}`:" in section, f"docs/experiments.md does not list the default study {name}"
            assert re.search(rf"^### .*\(`{name}`\) \{{#study-", report, re.M), f"paper/report.md has no section {name}"
