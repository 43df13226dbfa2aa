"""After a run, its --out folder holds what the run made and claims only what it checked: no lock file is left, and a
run that compared no study records no agreement ("agree": true over zero studies is a vacuous claim)."""
import json
import os
import subprocess
import sys

from experiments import run as runner
from experiments.provenance import REPO
from experiments.verdict import verdict_markdown

STUDY = ('name = "mine"\ntitle = "a personal study"\nseed = 1\nrepetitions = 1\n[[datasets]]\nsource = "circle"\n'
         'params = { radius = 5.0, noise = 0.01, n = 12 }\n[[methods]]\nid = "circle.kasa"\n')


def test_a_run_leaves_no_lock_and_claims_no_agreement_over_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.toml").write_text(STUDY, encoding="utf-8")
    out = tmp_path / "out"
    assert runner.main(["mine.toml", "--out", str(out), "--jobs", "1", "--no-report"]) == 0, capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["mine", "verify.json"]
    verdict = json.loads((out / "verify.json").read_text(encoding="utf-8"))
    assert verdict["agree"] is None and verdict["studies"] == [] and verdict["run"]["studies"] == ["mine"]
    assert not any("agree" in line for line in verdict_markdown(out))


def test_a_run_that_opened_a_removed_lock_file_takes_the_new_one(tmp_path, monkeypatch):
    """The finishing run removes its lock file while it holds it: a run that opened that file just before locks a
    removed file, sees it, and locks the file now in the folder (else two runs could write at once)."""
    out = tmp_path / "out"
    out.mkdir()
    stale = open(out / runner.LOCK_NAME, "a+")     # what a starting run opened before the file was removed
    os.unlink(out / runner.LOCK_NAME)
    opened = []

    def first_the_stale_file(path, mode="r", *args, **kwargs):
        opened.append(path)
        return stale if len(opened) == 1 else open(path, mode, *args, **kwargs)
    monkeypatch.setattr(runner, "open", first_the_stale_file, raising=False)
    try:
        runner.lock_out(out)
        assert len(opened) == 2
        held = runner._LOCKS[-1]
        assert os.fstat(held.fileno()).st_ino == os.stat(out / runner.LOCK_NAME).st_ino
        other = subprocess.run([sys.executable, "-c", "from pathlib import Path; from experiments import run; "
                                f"run.lock_out(Path({str(out)!r}))"], cwd=REPO, capture_output=True, text=True)
        assert other.returncode != 0 and "in use by another experiments.run" in other.stderr
    finally:
        runner.release_locks()
        stale.close()
    assert not (out / runner.LOCK_NAME).exists()
