"""A study kind of its own (the README's "Add a study" recipe): the TOML's ``[report] findings`` that its analysis's
findings replace is said to be unused (it was ignored silently), and the summary table the report shows for a kind
whose analysis gives no table names the units of its columns, as summary.md does (it had bare numbers)."""
import json

import pandas as pd

from experiments.run import run_study
from experiments.study import Analysis, Study
from study_kinds import plant, small_study

TOML = small_study("mine", "a study of my kind", "zz_own_findings", findings="{best_method} wins.")


class OwnFindings(Study):
    values = ("best_method",)

    def analyse(self, rows, cfg, target, log):
        best = rows.groupby("method")["radius_error"].apply(lambda s: (s ** 2).mean()).idxmin()
        return Analysis(values={"best_method": best}, findings=f"{best} has the smallest radius RMSE.")


def test_unused_findings_are_said_and_the_fallback_table_has_units(tmp_path, monkeypatch, capsys):
    plant(monkeypatch, "zz_own_findings", OwnFindings=OwnFindings)
    (tmp_path / "mine.toml").write_text(TOML, encoding="utf-8")
    target = run_study(str(tmp_path / "mine.toml"), tmp_path / "out", jobs=1, log=lambda *a: None)
    notes = [ln for ln in capsys.readouterr().err.splitlines() if "[report] findings is not used" in ln]
    assert len(notes) == 1 and "mine.toml" in notes[0] and "circle.kasa has the smallest radius RMSE" in notes[0]
    manifest = json.loads((target / "report.json").read_text(encoding="utf-8"))
    assert manifest["findings"] == "circle.kasa has the smallest radius RMSE."
    (table,) = manifest["tables"]
    columns = list(pd.read_csv(target / table["file"]).columns)
    summary_md = (target / "summary.md").read_text(encoding="utf-8")
    for name in ("radius_rmse", "center_rmse", "form_error_median"):
        labelled = [c for c in columns if c.startswith(name + " [")]
        assert labelled, (name, columns)
        unit = labelled[0][len(name) + 2:-1]
        assert unit and f"{name.replace('_', ' ')} [{unit}]" in summary_md, (labelled, summary_md[:400])
