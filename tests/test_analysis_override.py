"""docs/studies.md's claim: a kind that overrides ``analyse`` gets no default table or figure, and
``super().analyse()`` returns an empty ``Analysis`` (the defaults are the analysis step's, for a kind without its own)."""
import pandas as pd

from experiments import analysis
from experiments.study import Analysis, Study


class _Calls(Study):
    def analyse(self, rows, cfg, target, log):
        return super().analyse(rows, cfg, target, log)


def test_super_analyse_is_empty_and_an_overriding_kind_gets_no_default(tmp_path):
    rows = pd.DataFrame({"status": ["ok", "ok"], "method": ["circle.kasa"] * 2, "radius_error": [1e-3, 2e-3]})
    study = _Calls()
    assert study.own_analysis and not Study().own_analysis
    assert study.analyse(rows, {}, tmp_path, print) == Analysis()
    _, got = analysis.analyse(study, rows, {}, tmp_path, print)
    assert got.tables == [] and got.figures == [] and got.values == {"n_rows": 2, "n_ok": 2}
