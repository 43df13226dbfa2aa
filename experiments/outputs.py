"""A study's output files, each written atomically (a kill never leaves half a file): its ``report.json`` (the
manifest the report renders: section, tables, figures, values, findings) with one CSV per table, the CSV files and
figures its analysis saves, and the clean-up of what an interrupted write left behind."""
from __future__ import annotations

import io
from pathlib import Path

import pandas as pd

from experiments.findings import render_findings
from experiments.jsontext import json_text
from experiments.provenance import write_atomic
from experiments.study import Analysis, Table

#: the report section of a study whose TOML names none (``[report] section``)
DEFAULT_SECTION = "Other studies"


def save_csv(df: pd.DataFrame, path: Path, **kwargs) -> None:
    """``df.to_csv(path, **kwargs)``, written atomically."""
    buf = io.StringIO()
    df.to_csv(buf, **kwargs)
    write_atomic(path, buf.getvalue())


def remove_leftover_tmp(folder: Path) -> None:
    """Remove ``*.tmp`` files an interrupted atomic write left behind."""
    if folder.is_dir():
        for pattern in (".*.tmp", ".*.tmp.*"):
            for p in folder.rglob(pattern):
                p.unlink(missing_ok=True)


def write_manifest(target: Path, cfg: dict, analysis: Analysis, summary: pd.DataFrame) -> None:
    """``report.json`` and ``tables/*.csv``: everything the report renders for this study."""
    tables_dir = target / "tables"
    if tables_dir.is_dir():  # never mix the tables of two runs
        for p in tables_dir.glob("*.csv"):
            p.unlink()
    tables = analysis.tables or [Table(caption=f"Summary of {cfg['name']}: one row per data set and method "
                                               "(runs, share ok, medians, bias and RMSE against the truth)",
                                       data=summary)]
    entries = []
    for k, t in enumerate(tables):
        buf = io.StringIO()
        t.data.to_csv(buf, index=False, float_format="%.10g")
        name = f"tables/table_{k + 1}.csv"
        write_atomic(target / name, buf.getvalue())
        entries.append({"caption": t.caption, "file": name, "unit": t.unit, "digits": t.digits,
                        **({"colour": t.colour} if t.colour else {}),
                        **({"decimals": dict(t.decimals)} if t.decimals else {}),
                        **({"exact": list(t.exact)} if t.exact else {})})
    rep = cfg.get("report", {})
    findings = analysis.findings
    if not findings and rep.get("findings"):
        try:
            findings = render_findings(rep["findings"], analysis.values)
        except ValueError as exc:
            findings = f"(findings template not filled: {cfg.where}: report.findings: {exc})"
    manifest = {"title": cfg["title"], "section": rep.get("section", DEFAULT_SECTION), "order": rep.get("order", 1000),
                "quick": cfg.quick, "tables": entries,
                "figures": [{"caption": f.caption, "file": f.file} for f in analysis.figures],
                "values": analysis.values, "findings": findings}
    write_atomic(target / "report.json", json_text(manifest, indent=1) + "\n")
