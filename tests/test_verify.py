"""Experiments.verify compares a run with committed results column by column, with the tolerances
declared with the metrics (experiments.metrics.TOLERANCES)."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import quick_run_on
from experiments import codekeys, run as runner
from experiments import verify
from experiments.metrics import TOLERANCES, tolerance

REPO = Path(__file__).resolve().parents[1]

STUDY = '''name = "vstudy"
title = "verify test study"
kind = "grid"
seed = 5
repetitions = 2

[[datasets]]
generator = "circle"
params = { center = [1.0, 2.0], radius = 5.0, noise = 0.005, n = 12 }

[[methods]]
id = "circle.kasa"
[[methods]]
id = "circle.gauss_newton"
'''


@pytest.fixture(scope="module")
def committed(tmp_path_factory):
    root = tmp_path_factory.mktemp("verify")
    cfg = root / "vstudy.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    assert runner.main([str(cfg), "--jobs", "1", "--out", str(root / "committed")]) == 0
    return root / "committed"


def copy_run(committed: Path, tmp_path: Path) -> Path:
    fresh = tmp_path / "fresh"
    shutil.copytree(committed, fresh)
    (fresh / verify.VERDICT_FILE).unlink(missing_ok=True)
    return fresh


def edit(folder: Path, row: int, column: str, change) -> str:
    path = folder / "vstudy" / "results.csv"
    df = pd.read_csv(path, dtype=str, keep_default_na=False)
    df.loc[row, column] = change(df.loc[row, column])
    df.to_csv(path, index=False)
    return df.loc[row, "method"]


def test_identical_run_agrees_and_writes_verdict(committed, tmp_path, capsys):
    fresh = copy_run(committed, tmp_path)
    assert verify.main(["--results", str(committed), "--against", str(fresh), "--write-verdict"]) == 0
    assert capsys.readouterr().out.startswith("vstudy: agree")
    assert verify.last_verdict(committed)["agree"] is True
    assert "agree" in verify.verdict_markdown(committed)[0]


def test_values_within_tolerance_pass(committed, tmp_path, capsys):
    fresh = copy_run(committed, tmp_path)
    tol = TOLERANCES["radius"]
    edit(fresh, 1, "radius", lambda v: repr(float(v) * (1 + tol.rtol / 10)))
    edit(fresh, 2, "center_error", lambda v: repr(float(v) + TOLERANCES["center_error"].atol / 10))
    assert verify.main(["--results", str(committed), "--against", str(fresh)]) == 0, capsys.readouterr().out


@pytest.mark.parametrize("column,change", [
    ("radius", lambda v: repr(float(v) * (1 + 1e3 * TOLERANCES["radius"].rtol))),
    ("status", lambda v: "not converged"),
    ("iterations", lambda v: str(int(v) + 1)),
])
def test_perturbation_beyond_tolerance_fails_naming_study_column_row(committed, tmp_path, capsys, column, change):
    fresh = copy_run(committed, tmp_path)
    method = edit(fresh, 3, column, change)  # row 3: repetition 1, circle.gauss_newton
    assert verify.main(["--results", str(committed), "--against", str(fresh), "--write-verdict"]) == 1
    out = capsys.readouterr().out
    assert out.splitlines()[0].startswith("vstudy: DIFFER")
    bad = [ln for ln in out.splitlines() if ln.startswith("vstudy ")]
    assert len(bad) == 1 and f" {column} " in bad[0] and f"method={method}" in bad[0] and "repetition=1" in bad[0]
    verdict = json.loads((committed / verify.VERDICT_FILE).read_text())
    assert verdict["agree"] is False and verdict["studies"][0]["problems"][0]["column"] == column


def test_results_written_with_17_digits_match_rows_of_the_shortest_text(committed, tmp_path, capsys):
    """results.csv of an earlier format wrote every float with %.17g (noise 0.005 as 0.0050000000000000001): its rows
    are the same identities as this format's (0.005), so it verifies against a run of this format."""
    old = copy_run(committed, tmp_path)
    path = old / "vstudy" / "results.csv"
    df = pd.read_csv(path, dtype=str, keep_default_na=False)
    floats = [c for c in df.columns if c.startswith("data_") and df[c].str.contains(".", regex=False).all()
              and pd.to_numeric(df[c], errors="coerce").notna().all()]
    assert "data_noise" in floats
    for c in floats + ["radius", "center_error"]:
        df[c] = [f"{float(v):.17g}" for v in df[c]]
    assert (df["data_noise"] == "0.005").sum() == 0  # the identity's text differs
    df.to_csv(path, index=False)
    assert verify.main(["--results", str(old), "--against", str(committed)]) == 0, capsys.readouterr().out
    assert capsys.readouterr().out.startswith("vstudy: agree")


def test_missing_row_is_a_difference(committed, tmp_path, capsys):
    fresh = copy_run(committed, tmp_path)
    path = fresh / "vstudy" / "results.csv"
    df = pd.read_csv(path, dtype=str, keep_default_na=False)
    df.drop(index=0).to_csv(path, index=False)
    assert verify.main(["--results", str(committed), "--against", str(fresh)]) == 1
    assert "row missing in this run" in capsys.readouterr().out


def test_bad_input_exits_2_in_one_line(committed, tmp_path, capsys):
    fresh = copy_run(committed, tmp_path)
    cases = [["--results", str(tmp_path / "nope"), "--against", str(fresh)],
             ["--results", str(committed), "--against", str(tmp_path / "nope")],
             ["unknown_study", "--results", str(committed), "--against", str(fresh)],
             ["--results", str(committed), "--against", str(fresh), "--quick"]]  # a full run is not a quick one
    (tmp_path / "broken" / "vstudy").mkdir(parents=True)
    (tmp_path / "broken" / "vstudy" / "results.csv").write_bytes(b"\xff\xfe\x00garbage")
    cases.append(["--results", str(committed), "--against", str(tmp_path / "broken")])
    for args in cases:
        assert verify.main(args) == 2, args
        err = capsys.readouterr().err.strip()
        assert err.startswith("experiments.verify: error:") and "\n" not in err, err


def test_timing_and_message_are_not_compared_every_metric_declares_a_justified_tolerance():
    assert tolerance("time_median_s") is None and tolerance("message") is None
    assert tolerance("status").rtol == 0 == tolerance("status").atol
    for column, tol in TOLERANCES.items():
        assert tol is None or (tol.rtol >= 0 and tol.atol >= 0 and len(tol.why) > 20), column


def test_committed_quick_results_exist_for_the_ci_verify_step():
    """CI runs `python -m experiments.verify --quick --against <fresh quick run> --results results/quick`: the
    committed quick results must be there (generated with `python -m experiments.run --quick --out results/quick`)."""
    quick = REPO / "results" / "quick"
    assert quick.is_dir(), ("results/quick/ is missing: generate it with python -m experiments.run --quick "
                            "--out results/quick and commit it (the CI verify step compares with it)")
    defaults = [n for n in runner.configs.available() if runner.configs.load(n).get("default")]
    for name in defaults:
        meta = json.loads((quick / name / "meta.json").read_text())
        assert meta["quick"] is True and (quick / name / "results.csv").is_file(), name


def test_rows_that_did_not_converge_in_both_runs_compare_status_and_counts_only(committed, tmp_path, capsys):
    """Where both runs say "not converged", the values are where an iteration stopped (rounding moves them):
    they are not compared, and verify says how many it left out; the counts still are."""
    base = copy_run(committed, tmp_path / "a")
    edit(base, 3, "status", lambda v: "not converged")
    fresh = copy_run(base, tmp_path / "b")
    edit(fresh, 3, "radius", lambda v: repr(float(v) * 1.5))
    assert verify.main(["--results", str(base), "--against", str(fresh)]) == 0, capsys.readouterr().out
    out = capsys.readouterr().out
    assert "of rows that did not converge in both runs not compared" in out
    edit(fresh, 3, "iterations", lambda v: str(int(v) + 1))
    assert verify.main(["--results", str(base), "--against", str(fresh)]) == 1
    assert " iterations " in capsys.readouterr().out


def _drop(folder: Path, columns) -> None:
    path = folder / "vstudy" / "results.csv"
    df = pd.read_csv(path, dtype=str, keep_default_na=False)
    df.drop(columns=list(columns)).to_csv(path, index=False)


METRICS = ["radius", "center_x", "center_y", "form_error", "center_error", "radius_error", "iterations"]


@pytest.mark.parametrize("side", ["committed", "fresh"])
@pytest.mark.parametrize("columns", [["radius"], ["radius", "center_x", "form_error"], METRICS])
def test_a_missing_column_is_a_difference(committed, tmp_path, capsys, side, columns):
    """Results that lost columns (some or every metric) never agree, whichever side lost them."""
    base = copy_run(committed, tmp_path / "a")
    fresh = copy_run(committed, tmp_path / "b")
    _drop(base if side == "committed" else fresh, columns)
    assert verify.main(["--results", str(base), "--against", str(fresh), "--write-verdict"]) == 1
    out = capsys.readouterr().out
    assert out.startswith("vstudy: DIFFER")
    named = {p["column"] for p in json.loads((base / verify.VERDICT_FILE).read_text())["studies"][0]["problems"]}
    assert set(columns) <= named


@pytest.mark.parametrize("side", ["--results", "--against"])
def test_header_only_results_is_bad_input_in_one_line(committed, tmp_path, capsys, side):
    base = copy_run(committed, tmp_path / "a")
    fresh = copy_run(committed, tmp_path / "b")
    path = (base if side == "--results" else fresh) / "vstudy" / "results.csv"
    path.write_text(path.read_text().splitlines()[0] + "\n")
    assert verify.main(["--results", str(base), "--against", str(fresh)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("experiments.verify: error:") and "no rows" in err and "\n" not in err


def test_verdict_names_the_results_it_judged_and_goes_out_of_date(committed, tmp_path, capsys):
    """After the study is rerun with other numbers, the old verdict is no longer shown as agreement."""
    from experiments.verdict import study_verdicts
    base = copy_run(committed, tmp_path / "a")
    fresh = copy_run(committed, tmp_path / "b")
    assert verify.main(["--results", str(base), "--against", str(fresh), "--write-verdict"]) == 0
    entry = json.loads((base / verify.VERDICT_FILE).read_text())["studies"][0]
    assert entry["results_sha256"] == verify.results_sha256(base / "vstudy")
    assert "all 1 verified study agrees" in verify.verdict_markdown(base)[0]
    assert study_verdicts(base, ["vstudy"])["vstudy"][0][0] == "Reproducibility"
    edit(base, 0, "radius", lambda v: repr(float(v) * 2))      # the study's results changed since
    assert "agree" not in verify.verdict_markdown(base)[0]
    label, sentence = study_verdicts(base, ["vstudy"])["vstudy"][0]
    assert label == "Reproducibility: out of date" and "changed since" in sentence


def test_every_run_ends_with_a_verdict_the_report_shows(tmp_path, capsys):
    """experiments.run compares each fresh study with the results it replaces (or the committed ones) and the
    report states per study that it reproduces them or which columns differ; a study the run did not include
    is said to be older than the run."""
    for name in ("vstudy", "vother"):
        (tmp_path / f"{name}.toml").write_text(STUDY.replace('name = "vstudy"', f'name = "{name}"'), encoding="utf-8")
    out = tmp_path / "out"
    args = ["--jobs", "1", "--out", str(out)]

    def run(*names):
        return runner.main([*names, *args])   # main releases its --out lock when it returns
    assert run(str(tmp_path / "vstudy.toml"), str(tmp_path / "vother.toml")) == 0
    assert "verify: vstudy: no committed results to compare with" in capsys.readouterr().out
    assert run(str(tmp_path / "vstudy.toml")) == 0                          # a rerun: compared with the first
    assert "verify: vstudy: reproduces the previous results" in capsys.readouterr().out
    md = (out / "paper" / "report.md").read_text(encoding="utf-8")
    section = md.split("(`vstudy`)")[1].split("### ")[0]
    assert "**Reproducibility.** Verdict" in section and "this run reproduces the previous results" in section
    other = md.split("(`vother`)")[1].split("### ")[0]
    assert "**Older results.** These results are older than the last run" in other and "this run reproduces" not in other
    edit(out, 0, "radius", lambda v: repr(float(v) * 2))                     # what the next run is compared with
    assert run(str(tmp_path / "vstudy.toml")) == 0
    assert "verify: vstudy: DIFFERS from the previous results" in capsys.readouterr().out
    section = (out / "paper" / "report.md").read_text(encoding="utf-8").split("(`vstudy`)")[1].split("### ")[0]
    assert "**Reproducibility: differs.**" in section and "radius" in section


@pytest.mark.system  # every default study's quick grid, as .ci/run's last step does
def test_a_quick_run_of_the_default_studies_reports_a_verdict_for_each(tmp_path_factory):
    """`python -m experiments.run --quick` from the repository compares every default study with the committed
    results/quick and the report carries one verdict per default study (CI runs the same command). The run is the
    simulated AVX2 machine's of tests/test_cpu_independence.py (conftest.quick_run_on: one run for both tests)."""
    out = quick_run_on(tmp_path_factory, "avx2_fma")
    stdout = (out.parent / "stdout.txt").read_text(encoding="utf-8")
    defaults = [n for n in runner.configs.available() if runner.configs.load(n).get("default")]
    md = (out / "paper" / "report.md").read_text(encoding="utf-8")
    for name in defaults:
        assert f"verify: {name}: " in stdout, name
        section = md.split(f"(`{name}`)")[1].split("### ")[0]
        assert "**Reproducibility" in section and "the committed tables (results/quick/" in section, name


def _nist_results(tmp_path: Path) -> Path:
    """A --results folder holding a (full-grid) nist_circle study, whose data need FITBENCH_NIST_DIR."""
    results = tmp_path / "results"
    (results / "nist_circle").mkdir(parents=True)
    (results / "nist_circle" / "results.csv").write_text("dataset,method\n")
    (results / "nist_circle" / "meta.json").write_text(json.dumps({"quick": False}))
    return results


def test_a_named_study_whose_data_are_missing_is_refused_before_anything_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("FITBENCH_NIST_DIR", raising=False)
    assert verify.main(["nist_circle", "--results", str(_nist_results(tmp_path))]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "FITBENCH_NIST_DIR" in err


def test_an_implied_study_whose_data_are_missing_is_named_and_left_out(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("FITBENCH_NIST_DIR", raising=False)
    assert verify.main(["--results", str(_nist_results(tmp_path))]) == 2
    out, err = capsys.readouterr()
    assert out.startswith("nist_circle: not checked here:") and "FITBENCH_NIST_DIR" in out
    assert "no study of --results can run here" in err


def test_run_checks_every_study_is_ready_before_the_first_row(tmp_path, monkeypatch, capsys):
    """A run of two studies, the second needing data not available here: refused in one line before the first
    study runs (it used to run the first study, then stop)."""
    monkeypatch.delenv("FITBENCH_NIST_DIR", raising=False)
    cfg = tmp_path / "vstudy.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    out = tmp_path / "out"
    assert runner.main([str(cfg), "nist_circle", "--jobs", "1", "--out", str(out), "--no-report"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "FITBENCH_NIST_DIR" in err
    assert not (out / "vstudy").exists()


def test_the_verdict_names_no_folder_of_this_machine(committed, tmp_path):
    fresh = copy_run(committed, tmp_path)
    verdict = verify.verify(["vstudy"], committed, fresh, log=lambda *a: None)
    text = json.dumps(verdict)
    assert str(tmp_path) not in text and verdict["against"].endswith("fresh")


def test_a_check_writes_nothing_unless_asked_and_names_folders_plainly(committed, tmp_path, monkeypatch, capsys):
    """`experiments.verify --results DIR --against RUN` rewrote DIR/verify.json (a tracked file of the committed
    results) and recorded "main/results", a path with its first parts cut: a check leaves both folders as they
    were; --write-verdict records the verdict in DIR, naming a folder inside the current one by its relative
    path and one outside it by `.../` and its last two parts (no folder of this machine)."""
    base = copy_run(committed, tmp_path / "ref")
    fresh = copy_run(committed, tmp_path / "run")
    before = {p: p.read_bytes() for folder in (base, fresh) for p in folder.rglob("*") if p.is_file()}
    assert verify.main(["--results", str(base), "--against", str(fresh)]) == 0
    after = {p: p.read_bytes() for folder in (base, fresh) for p in folder.rglob("*") if p.is_file()}
    assert after == before and "vstudy: agree" in capsys.readouterr().out
    monkeypatch.chdir(tmp_path / "ref")                       # base inside the current folder, fresh outside
    assert verify.main(["--results", str(base), "--against", str(fresh), "--write-verdict"]) == 0
    verdict = json.loads((base / verify.VERDICT_FILE).read_text(encoding="utf-8"))
    assert str(tmp_path) not in json.dumps(verdict) and not (fresh / verify.VERDICT_FILE).exists()
    assert (verdict["results"], verdict["against"]) == ("fresh", ".../run/fresh")
    assert verdict["studies"][0]["reference"] == "the run in .../fresh/vstudy"


def test_a_quick_run_without_out_writes_beside_the_full_results_never_into_them(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = tmp_path / "vstudy.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    assert runner.main([str(cfg), "--quick", "--jobs", "1", "--no-report"]) == 0
    # a study of one's own (its TOML outside experiments/configs/) goes to results/user/, quick: results/user/quick/
    assert (tmp_path / "results" / "user" / "quick" / "vstudy" / "results.csv").is_file()
    assert not (tmp_path / "results" / "user" / "vstudy").exists() and not (tmp_path / "results" / "vstudy").exists()


@pytest.mark.parametrize("study", ["convergence", "noise", "roundness", "circular_test"])
def test_a_table_compared_with_itself_gives_the_full_comparisons_verdict_cheaply(study):
    """A re-run whose results.csv is byte for byte its reference is judged from its header and its method and status
    columns: the same rows, compared columns and values of rows that did not converge in both as the full comparison
    (the committed quick results hold rows that did not converge)."""
    from experiments import compare
    root = REPO / "results" / "quick"
    df = compare._read(root, study, "--results")
    assert compare.self_comparison(study, root) == compare.compare_study(study, df, df.copy())


def test_a_difference_is_judged_and_named_by_the_tolerance_of_its_rows_method(monkeypatch):
    """Tolerances are looked up once per distinct method of a table, never listed per row (self_comparison built
    and dropped a list of one per row and column: ~20 ms of its 40,000-row verdict), and the worst row of a
    column that differs is named with its own method's tolerance."""
    from experiments import compare, metrics
    from methods.result_base import Tolerance

    monkeypatch.setitem(metrics.CHAOTIC, ("vstudy", "circle.nelder_mead", "radius"), Tolerance(1e-3, 0.0, "test"))
    methods = ["circle.kasa", "circle.nelder_mead"] * 20_000
    committed = pd.DataFrame({"study": "vstudy", "dataset": "d", "repetition": [str(k) for k in range(len(methods))],
                              "method": methods, "status": "ok", "radius": "299.0"})
    kinds = compare._method_kinds(committed["method"])
    tol_of, keep, skipped, (rtol, atol) = compare._compared_rows("vstudy", "radius", kinds, np.zeros(len(methods), bool))
    assert len(tol_of) == 2 and keep.all() and skipped == 0
    assert set(rtol[kinds[1] == kinds[0].index("circle.nelder_mead")]) == {1e-3}
    fresh = committed.copy()
    fresh.loc[1, "radius"] = "302.0"                             # a Nelder-Mead row: 3 mm, 10 x its 1e-3 (0.3 mm)
    fresh.loc[2, "radius"] = "299.000001"                        # a Kasa row: 1 nm, 3 x its 1e-9 (0.3 nm)
    got = compare.compare_study("vstudy", committed, fresh)
    (problem,) = got["problems"]
    assert problem["n_rows"] == 2 and problem["problem"] == "outside rtol=0.001, atol=0"   # the worst: Nelder-Mead's
    assert problem["worst"][0]["row"].startswith("dataset=d, repetition=1, method=circle.nelder_mead")
    fresh.loc[1, "radius"] = "299.0"
    (problem,) = compare.compare_study("vstudy", committed, fresh)["problems"]
    kasa = compare.tolerance("radius", "vstudy", "circle.kasa")
    assert problem["n_rows"] == 1 and problem["problem"] == f"outside rtol={kasa.rtol:g}, atol={kasa.atol:g}"
    assert kasa.rtol != 1e-3 and problem["worst"][0]["row"].startswith("dataset=d, repetition=2, method=circle.kasa")


def test_the_runs_verdicts_are_committed_with_the_results_and_name_no_folder_of_this_machine(tmp_path, monkeypatch):
    """The verdicts a run earned (RESULTS/verify.json) are outputs of that run, committed with its results, so that
    `python -m experiments.report` on a fresh checkout keeps each study's "Reproducibility. Verdict ..." line
    (git ignored the file: every verdict was dropped). The file names no folder of this machine, even for an
    absolute --out."""
    import subprocess
    for rel in ("results/verify.json", "results/quick/verify.json"):
        ignored = subprocess.run(["git", "check-ignore", "--no-index", "-q", rel], cwd=REPO)
        assert ignored.returncode == 1, f"{rel} is ignored by git"
    cfg = tmp_path / "vstudy.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    out = tmp_path / "deep" / "out"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    for _ in range(2):   # the second run is compared with the first's results in --out
        assert runner.main([str(cfg), "--jobs", "1", "--out", str(out), "--no-report"]) == 0
    text = (out / verify.VERDICT_FILE).read_text(encoding="utf-8")
    assert json.loads(text)["studies"][0]["agree"] is True
    assert str(tmp_path) not in text


def test_the_reports_hints_give_the_command_that_regenerates_these_results(tmp_path, monkeypatch, capsys):
    """After `experiments.run vstudy --quick --out DIR`, the report's hint for a study of DIR the run did not
    include reruns it into DIR with its quick grid (it said `python -m experiments.run vother`, which runs the
    full grid into results/), and an out-of-date verdict is checked again with --quick --results DIR."""
    for name in ("vstudy", "vother"):
        (tmp_path / f"{name}.toml").write_text(STUDY.replace('name = "vstudy"', f'name = "{name}"'), encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "mine"

    def run(*names, report=True):
        code = runner.main([*(str(tmp_path / f"{n}.toml") for n in names), "--quick", "--jobs", "1", "--out", "mine",
                            *([] if report else ["--no-report"])])
        return code
    assert run("vstudy", "vother", report=False) == 0
    assert run("vstudy") == 0
    md = (out / "paper" / "report.md").read_text(encoding="utf-8")
    other = md.split("(`vother`)")[1].split("### ")[0]
    assert "rerun it with python -m experiments.run vother.toml --quick --out mine." in other   # its TOML, not its name
    edit(out, 0, "radius", lambda v: repr(float(v) * 2))
    from experiments.verdict import study_verdicts
    lines = dict(study_verdicts(out, ["vstudy"], quick={"vstudy": True}, shown="mine")["vstudy"])
    assert "run python -m experiments.verify vstudy --quick --results mine --write-verdict again" in lines["Reproducibility: out of date"]
    # the grid's default folder is not named: results/quick/ for a quick run
    default = tmp_path / "results" / "quick"
    shutil.copytree(out, default)
    older = dict(study_verdicts(default, ["vother"], quick={"vother": True}, shown="results/quick")["vother"])
    assert older["Older results"].endswith("rerun it with python -m experiments.run vother --quick.")


def test_an_unknown_study_is_named_unknown_with_the_known_ones(committed, tmp_path, capsys):
    """`experiments.verify nosuch --against DIR` said "run python -m experiments.run nosuch ... first", a study
    that does not exist: it is unknown, and the studies of --results and the known ones are listed."""
    fresh = copy_run(committed, tmp_path)
    assert verify.main(["nosuch", "--results", str(committed), "--against", str(fresh)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown study 'nosuch'" in err
    assert "vstudy" in err and "published" in err and "experiments.run nosuch" not in err


def test_previous_results_of_another_config_or_data_are_not_compared(tmp_path, capsys):
    """Other repetitions, another seed (in the study or with --seed) or an edited data file give other rows by design:
    the run says in one line that the previous results are not compared and records no verdict for the study (it
    said "DIFFERS ... in: (rows)" and the report "Reproducibility: differs"); a run of the same config and data as
    the previous one is compared as before, whatever changed in between."""
    data = tmp_path / "trace.csv"
    rng = np.random.default_rng(3)
    t = rng.uniform(0.0, 2.0 * np.pi, 20)
    pd.DataFrame({"X": 5.0 * np.cos(t) + 1.0, "Y": 5.0 * np.sin(t) - 2.0}).to_csv(data, index=False)
    study = STUDY + '''
[[datasets]]
file = "trace.csv"
'''
    cfg = tmp_path / "vstudy.toml"
    out = tmp_path / "out"

    def run(text, *more, report=False):
        cfg.write_text(text, encoding="utf-8")
        code = runner.main([str(cfg), "--jobs", "1", "--out", str(out), *more, *([] if report else ["--no-report"])])
        assert code == 0
        return [line for line in capsys.readouterr().out.splitlines() if line.startswith("verify:")]

    def no_verdict():
        studies = json.loads((out / verify.VERDICT_FILE).read_text(encoding="utf-8"))["studies"]
        return not [s for s in studies if s["study"] == "vstudy"]

    run(study)
    for text, more, changed in ((study.replace("repetitions = 2", "repetitions = 3"), (), "repetitions 2, now 3"),
                                (study, (), "repetitions 3, now 2"),
                                (study.replace("seed = 5", "seed = 9"), (), "seed 5, now 9"),
                                (study, ("--seed", "8"), "seed 9, now 8")):
        lines = run(text, *more)
        assert len(lines) == 1 and "DIFFERS" not in lines[0], lines
        assert lines[0].startswith("verify: vstudy: not compared: the previous results in ") and changed in lines[0]
        assert no_verdict()
    lines = run(study, "--seed", "8")                       # the previous run had --seed 8 too: compared
    assert len(lines) == 1 and "verify: vstudy: reproduces the previous results" in lines[0]
    run(study)
    data.write_text(data.read_text(encoding="utf-8") + "6.0,-2.0\n", encoding="utf-8")   # one point more
    codekeys.reset_caches()   # this process hashed the data file once for its row keys: hash it again, as a new run does
    lines = run(study, report=True)
    assert len(lines) == 1 and "not compared" in lines[0] and "data file datasets[1] trace.csv changed" in lines[0]
    assert no_verdict()
    md = (out / "paper" / "report.md").read_text(encoding="utf-8")
    assert "differ" not in md.lower(), [l for l in md.splitlines() if "differ" in l.lower()]
    lines = run(study)
    assert len(lines) == 1 and "verify: vstudy: reproduces the previous results" in lines[0]


def test_verify_refuses_runs_of_another_config_in_one_line(committed, tmp_path, capsys):
    """experiments.verify --against a run of another seed (or repetitions, or data) said DIFFER with every row
    missing: it says in one line that the two runs are of other configs, exit 2, and writes no verdict."""
    fresh = copy_run(committed, tmp_path)
    meta_path = fresh / "vstudy" / "meta.json"
    meta = json.loads(meta_path.read_text(encoding="utf-8"))
    meta["inputs"]["config"]["seed"] = 8           # as `experiments.run vstudy --seed 8` records it
    meta_path.write_text(json.dumps(meta), encoding="utf-8")
    verdict = committed / verify.VERDICT_FILE
    before = verdict.read_bytes() if verdict.exists() else None
    assert verify.main(["--results", str(committed), "--against", str(fresh), "--write-verdict"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "another config or data" in err and "seed 5, now 8" in err, err
    assert (verdict.read_bytes() if verdict.exists() else None) == before     # no verdict written
    del meta["inputs"]                               # a run written before meta.json recorded its inputs: its config
    meta["config"]["seed"] = 8
    meta_path.write_text(json.dumps(meta), encoding="utf-8")
    assert verify.main(["--results", str(committed), "--against", str(fresh)]) == 2
    assert "seed 5, now 8" in capsys.readouterr().err


def test_the_run_s_verdict_of_unchanged_tables_is_kept_and_judged_again_when_a_key_changes(tmp_path):
    """A re-run of an up-to-date study judged the same two tables again (reading results.csv, 0.1 s of a 0.8 s re-run
    of 40,000 rows): the verdict is kept when the fresh table, the reference and the study's fingerprint (its config
    and the code that analyses and judges it) are those it was made of, and made again when any of them changed."""
    cfg = tmp_path / "vstudy.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    args = [str(cfg), "--jobs", "1", "--no-report", "--out", str(tmp_path / "out")]
    assert runner.main(args) == 0
    assert runner.main(args) == 0  # judged against the previous run's table
    first = json.loads((tmp_path / "out" / verify.VERDICT_FILE).read_text())["studies"][0]
    assert first["agree"] and first["fingerprint"] and first["reference_sha256"] == first["results_sha256"]
    assert runner.main(args) == 0
    kept = json.loads((tmp_path / "out" / verify.VERDICT_FILE).read_text())["studies"][0]
    assert kept == first  # the same verdict, its date included: not judged again
    tampered = json.loads((tmp_path / "out" / verify.VERDICT_FILE).read_text())
    tampered["studies"][0]["fingerprint"] = "0" * 32  # as if the code that judges had changed
    tampered["studies"][0]["date"] = "2000-01-01T00:00:00+00:00"
    (tmp_path / "out" / verify.VERDICT_FILE).write_text(json.dumps(tampered))
    assert runner.main(args) == 0
    again = json.loads((tmp_path / "out" / verify.VERDICT_FILE).read_text())["studies"][0]
    assert again["date"] != "2000-01-01T00:00:00+00:00" and again["fingerprint"] == first["fingerprint"]


def _set_kernels(folder: Path, backend: str) -> None:
    path = folder / "vstudy" / "meta.json"
    meta = json.loads(path.read_text())
    meta["environment"]["kernels"] = backend
    path.write_text(json.dumps(meta))


def test_differences_the_other_kernel_backend_explains_are_named_apart_never_within_one_backend(committed, tmp_path,
                                                                                                 capsys):
    """Results committed with the compiled kernels, checked with FITBENCH_KERNELS=numpy: an iterative method near its
    stopping test may stop an iteration later or flip its status (the convergence study's run-away starts). verify
    says so and lists those values apart; with one backend on both sides the same edit stays a difference, and a
    value of a row with one status in both runs, or of a closed-form method, stays one whatever the backends."""
    fresh = copy_run(committed, tmp_path / "a")
    assert edit(fresh, 3, "iterations", lambda v: str(int(v) + 1)) == "circle.gauss_newton"
    assert verify.main(["--results", str(committed), "--against", str(fresh)]) == 1      # one backend: differs
    assert capsys.readouterr().out.startswith("vstudy: DIFFER")
    _set_kernels(fresh, "numpy")
    assert verify.main(["--results", str(committed), "--against", str(fresh), "--write-verdict"]) == 0
    out = capsys.readouterr().out
    first = out.splitlines()[0]
    assert first.startswith("vstudy: agree except where the kernel backends part") and "compiled" in first \
        and "numpy" in first and "circle.gauss_newton" in first and "(iterations)" in first, out
    assert "Differences the other kernel backend explains" in out and " iterations " in out
    entry = json.loads((committed / verify.VERDICT_FILE).read_text())["studies"][0]
    assert entry["kernels"] == {"committed": "compiled", "this_run": "numpy"} and entry["kernel_rows"] == 1
    from experiments.verdict import study_verdicts
    sentence = study_verdicts(committed, ["vstudy"])["vstudy"][0][1]
    assert "except where the kernel backends part" in sentence and "iterations" in sentence
    # a status flip: every value of that row is where the iteration stopped in one run
    edit(fresh, 3, "status", lambda v: "not converged")
    edit(fresh, 3, "radius", lambda v: repr(float(v) * 3))
    assert verify.main(["--results", str(committed), "--against", str(fresh)]) == 0, capsys.readouterr().out
    capsys.readouterr()
    # real differences stay differences: a value of a row that is ok in both runs, and any column of a closed form
    for row, column in ((1, "radius"), (0, "iterations")):
        other = copy_run(committed, tmp_path / f"b{row}")
        _set_kernels(other, "numpy")
        change = (lambda v: repr(float(v) * 1.001)) if column == "radius" else (lambda v: str(int(float(v or 0)) + 1))
        method = edit(other, row, column, change)
        assert (method == "circle.gauss_newton") == (column == "radius")
        assert verify.main(["--results", str(committed), "--against", str(other)]) == 1
        out = capsys.readouterr().out
        assert out.startswith("vstudy: DIFFER") and f" {column} " in out.split("Differences the other")[0]


def test_the_report_of_a_users_study_names_no_folder_of_this_machine_its_own_command_and_what_a_verdict_compared(
        tmp_path, capsys):
    """A user's TOML study run into its own folder: the report names that folder without the machine's path, gives
    the command that reruns THAT study, and after the study's code changed (its fingerprint) a difference from the
    previous run is said to be a change, not a failure to reproduce."""
    toml = tmp_path / "vuser.toml"
    toml.write_text(STUDY.replace('name = "vstudy"', 'name = "vuser"'), encoding="utf-8")
    out = tmp_path / "my results"
    assert runner.main([str(toml), "--jobs", "1", "--out", str(out)]) == 0
    md = (out / "paper" / "report.md").read_text(encoding="utf-8")
    header = md.splitlines()[2]
    assert str(tmp_path) not in md and "`.../my results`" in header, header
    assert "`python -m experiments.run vuser.toml --out 'my results'`" in header and "default studies" not in header
    # the plugin author edits the study's code: the previous results were computed by other code
    meta_path = out / "vuser" / "meta.json"
    meta = json.loads(meta_path.read_text())
    meta["fingerprint"] = "0" * 32
    meta_path.write_text(json.dumps(meta))
    edit_path = out / "vuser" / "results.csv"
    df = pd.read_csv(edit_path, dtype=str, keep_default_na=False)
    df.loc[0, "radius"] = repr(float(df.loc[0, "radius"]) * 2)
    df.to_csv(edit_path, index=False)
    capsys.readouterr()
    assert runner.main([str(toml), "--jobs", "1", "--out", str(out)]) == 0
    assert "computed by other code or config" in capsys.readouterr().out
    md = (out / "paper" / "report.md").read_text(encoding="utf-8")
    abstract = md.split("**Abstract.**")[1].split("\n")[0]
    assert "Reproduced: 0 of 1" not in md and "Changed since the results compared with" in abstract, abstract
    section = md.split("(`vuser`)")[1]
    assert "**Changed since the compared results.**" in section and "not a reproducibility check" in section
    assert "differ beyond the declared tolerances" not in md


def test_a_helper_module_among_the_study_kinds_does_not_stop_verify(committed, tmp_path, capsys, monkeypatch):
    """A module of experiments/studies/ that is not a study (a helper of one kind, without the leading underscore that
    keeps it out of the kinds) stopped verify of every study; it is now no kind, and loading it as one says how to
    name a helper."""
    import sys
    import types

    from experiments import studies
    kinds = studies.kinds()
    helper = types.ModuleType("experiments.studies.zz_helper")
    helper.V = 5.0
    monkeypatch.setitem(sys.modules, "experiments.studies.zz_helper", helper)
    monkeypatch.setattr(studies, "kinds", lambda: [*kinds, "zz_helper"])
    monkeypatch.setattr(studies, "_TOLERANCES", {})
    fresh = copy_run(committed, tmp_path)
    assert verify.main(["--results", str(committed), "--against", str(fresh)]) == 0, capsys.readouterr()
    with pytest.raises(studies.StudyKindError, match="leading underscore"):
        studies.study_of("zz_helper")


def test_a_fifo_for_meta_json_does_not_block_verify(committed, tmp_path, capsys):
    """A FIFO in place of a run's meta.json (a file only the run writes) is no meta.json to verify with, never a read
    that waits forever."""
    import os
    fresh = copy_run(committed, tmp_path)
    meta = fresh / "vstudy" / "meta.json"
    meta.unlink()
    os.mkfifo(meta)
    assert verify.main(["--results", str(committed), "--against", str(fresh)]) == 0
    assert capsys.readouterr().out.startswith("vstudy: agree")
