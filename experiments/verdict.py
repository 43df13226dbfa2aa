"""The verdict of the last ``python -m experiments.verify`` run, as the report reads it.

``experiments.verify`` writes ``RESULTS/verify.json``; this module only reads it, so that the report does not
depend on the command that runs studies (issue 17: "the report shows the verdict of the last verify run").
"""
from __future__ import annotations

import json
from pathlib import Path

VERDICT_FILE = "verify.json"


def last_verdict(results: Path) -> dict | None:
    """The verdict of the last ``experiments.verify`` against ``results`` (None when there is none or it is unreadable)."""
    try:
        verdict = json.loads((Path(results) / VERDICT_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return verdict if isinstance(verdict, dict) and "agree" in verdict else None


def verdict_markdown(results: Path) -> list[str]:
    """Lines for the report: the last verdict in one sentence, with the studies that differ."""
    v = last_verdict(results)
    if v is None:
        return ["No reproducibility verdict yet: run `python -m experiments.verify`."]
    studies = v.get("studies", [])
    differ = [s.get("study", "?") for s in studies if not s.get("agree")]
    when = v.get("date", "?")
    if not differ:
        return [f"Reproducibility: `python -m experiments.verify` on {when}: all {len(studies)} studies agree with "
                f"these results within the declared tolerances."]
    return [f"Reproducibility: `python -m experiments.verify` on {when}: {len(differ)} of {len(studies)} studies "
            f"differ beyond the declared tolerances ({', '.join(differ)}); see `verify.json`."]
