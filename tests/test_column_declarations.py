"""The row columns the families declare (name, unit, check, tolerance, error against the truth) and the tolerances
``python -m experiments.verify`` applies are pinned in ``tests/data/column_declarations.json``: moving a declaration
(from one module to another, from a hand-kept list to a family's class) must not change one of them.

A deliberate change of a tolerance or a column is made in the code and in the pinned table together, with the
reason in the commit (the table is the reviewer's view of what changed):
``python -c "from tests.test_column_declarations import write_table; write_table()"``.
"""
from __future__ import annotations

import json
from pathlib import Path

TABLE = Path(__file__).resolve().parent / "data" / "column_declarations.json"


def _tolerance(t):
    return None if t is None else {"rtol": t.rtol, "atol": t.atol, "why": t.why}


def _builtin_classes():
    from methods import results
    return [c for c in results.result_classes() if c.__module__.split(".")[0] == "methods"]


def current_table() -> dict:
    """The declarations of the built-in families and of verify, as plain JSON values."""
    from experiments import engine, metrics, studies, summary
    from methods import results
    builtin_columns = {}
    for cls in _builtin_classes():
        for col in cls.COLUMNS:
            builtin_columns.setdefault(col.name, col)
    columns = results.row_columns()
    families = sorted({c.__dict__["FAMILY"] for c in _builtin_classes() if c.__dict__.get("FAMILY")})
    return {
        "family_columns": {name: {"quantity": col.quantity, "unit": col.unit, "check": col.check,
                                  "truth_error": col.truth_error, "tolerance": _tolerance(col.tolerance),
                                  **({"components": list(col.components)} if col.components else {})}
                           for name, col in ((n, columns[n]) for n in builtin_columns)},
        "truth_error_columns": [c for c in results.truth_error_columns() if c in builtin_columns],
        "summary_error_columns": [c for c in summary.ERROR_COLUMNS if c in builtin_columns],
        "engine_result_columns": sorted(c for c in engine.result_columns()
                                        if c in builtin_columns or c not in columns),
        "verify_tolerances": {name: _tolerance(t) for name, t in sorted({**metrics.TOLERANCES,
                                                                         **studies.tolerances()}.items())
                              if name in builtin_columns or name not in columns},
        "verify_default_tolerance": _tolerance(metrics.DEFAULT_TOLERANCE),
        "family_contracts": {f: results.contract(f).__name__ for f in families},
    }


def write_table() -> None:
    TABLE.parent.mkdir(exist_ok=True)
    parts = []
    for key, value in current_table().items():  # one line per column: a change reads as one line of the diff
        if isinstance(value, dict):
            body = ",\n".join(f"  {json.dumps(k)}: {json.dumps(v, ensure_ascii=False)}" for k, v in value.items())
            parts.append(f" {json.dumps(key)}: {{\n{body}\n }}")
        else:
            parts.append(f" {json.dumps(key)}: {json.dumps(value, ensure_ascii=False)}")
    TABLE.write_text("{\n" + ",\n".join(parts) + "\n}\n", encoding="utf-8")


def test_the_declared_columns_and_tolerances_are_the_pinned_ones():
    pinned = json.loads(TABLE.read_text(encoding="utf-8"))
    now = json.loads(json.dumps(current_table()))  # tuples as lists, as in the file
    for key in pinned:
        assert now[key] == pinned[key], key
    assert set(now) == set(pinned)

