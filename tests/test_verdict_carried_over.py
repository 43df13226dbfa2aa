"""The report counts apart the verdicts the last run made and those it carried over from an earlier verdict file: on a
machine without the NIST data, `python -m experiments.run` runs 10 studies, yet the abstract said "Reproduced: 11 of
11 studies", counting nist_circle, whose verdict came with the committed verify.json."""
import json

from experiments.report import _abstract
from experiments.verdict import carried_over, results_sha256, study_verdicts, verdict_markdown


def _folder(tmp_path, run_studies):
    out = tmp_path / "out"
    entries = []
    for name, date in (("alpha", "2026-11-26T11:00:00+00:00"), ("nist_like", "2026-11-20T09:59:40+00:00")):
        (out / name).mkdir(parents=True)
        (out / name / "results.csv").write_text(f"study,status\n{name},ok\n", encoding="utf-8")
        entries.append({"study": name, "agree": True, "date": date, "rows": 1, "columns": 1, "problems": [],
                        "results_sha256": results_sha256(out / name)})
    verdict = {"agree": True, "date": "2026-11-26T11:00:00+00:00", "studies": entries,
               "run": {"date": "2026-11-26T11:00:00+00:00", "studies": run_studies}}
    (out / "verify.json").write_text(json.dumps(verdict), encoding="utf-8")
    return out


def _abstract_of(out):
    names = ["alpha", "nist_like"]
    entries = [("S", 1, n, f"{n}: a study", {"n_rows": 1}, {}, None) for n in names]
    return _abstract(entries, study_verdicts(out, names), *carried_over(out))


def test_a_verdict_the_last_run_did_not_make_is_counted_apart(tmp_path):
    out = _folder(tmp_path, ["alpha"])
    abstract = _abstract_of(out)
    assert "Reproduced: 1 of 1 studies with a current verdict made by the last run (2026-11-26T11:00:00+00:00)." \
        in abstract, abstract
    assert ("Carried over from an earlier verdict, not reproduced by the last run: nist_like (agreed, "
            "2026-11-20T09:59:40+00:00).") in abstract, abstract
    line = " ".join(verdict_markdown(out))
    assert "1 of them checked by the last run (2026-11-26T11:00:00+00:00), 1 carried over" in line, line
    assert "nist_like (agrees, 2026-11-20T09:59:40+00:00)" in line.replace("\\_", "_"), line


def test_when_the_last_run_made_every_verdict_nothing_is_carried(tmp_path):
    out = _folder(tmp_path, ["alpha", "nist_like"])
    assert "Reproduced: 2 of 2 studies with a current verdict." in _abstract_of(out)
    assert "carried" not in " ".join(verdict_markdown(out)) + _abstract_of(out).lower()
