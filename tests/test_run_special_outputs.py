"""A file the run reads and writes in ``--out`` that is not a regular file is refused in one line, exit 2, before
anything is read or locked: a FIFO at ``OUT/STUDY/meta.json`` or ``OUT/verify.json`` blocked the run forever (the
previous run's fingerprint and verdict are read from them), a ``rows.sqlite`` folder or symlink to a device got
"free the space"."""
import os
import sys

import pytest

from conftest import run_python
from experiments.run import main as run_main

STUDY = ('name = "special_out"\ntitle = "special files in --out"\nseed = 1\nrepetitions = 1\n[[datasets]]\n'
         'source = "circle"\nparams = { radius = 5.0, noise = 0.01, n = 12 }\n[[methods]]\nid = "circle.kasa"\n')

posix_only = pytest.mark.skipif(sys.platform == "win32" or not hasattr(os, "mkfifo"), reason="no FIFOs here")


@pytest.fixture
def study(tmp_path):
    toml = tmp_path / "special_out.toml"
    toml.write_text(STUDY, encoding="utf-8")
    return toml


def _one_line(err: str, path, kind: str) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0] == (f"experiments.run: error: {path}: is {kind}, not a regular file; the run reads and writes "
                        f"this file: remove it, or give another --out"), err


@posix_only
@pytest.mark.parametrize("where", ["special_out/meta.json", "verify.json"])
def test_a_fifo_where_the_run_reads_is_one_line_not_a_hang(study, tmp_path, where):
    out = tmp_path / "out"
    (out / "special_out").mkdir(parents=True)
    os.mkfifo(out / where)
    proc = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "1", "--no-report", timeout=60)
    assert proc.returncode == 2
    _one_line(proc.stderr, out / where, "a FIFO (named pipe)")
    assert not (out / "special_out" / "results.csv").exists()


@pytest.mark.parametrize("where, make, kind", [
    ("special_out/rows.sqlite", "folder", "a folder"),
    ("special_out/rows.sqlite", "device link", "a character device"),
    ("special_out/summary.csv", "folder", "a folder")])
def test_a_special_file_in_the_study_s_folder_is_one_line(study, tmp_path, capsys, where, make, kind):
    out = tmp_path / "out"
    (out / "special_out").mkdir(parents=True)
    if make == "folder":
        (out / where).mkdir()
    else:
        if not os.path.exists("/dev/zero"):
            pytest.skip("no /dev/zero here")
        (out / where).symlink_to("/dev/zero")
    assert run_main([str(study), "--out", str(out), "--jobs", "1", "--no-report"]) == 2
    _one_line(capsys.readouterr().err, out / where, kind)


def test_a_study_folder_that_is_a_file_is_one_line(study, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "special_out").write_text("not a folder")
    assert run_main([str(study), "--out", str(out), "--jobs", "1", "--no-report"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"experiments.run: error: {out / 'special_out'}: is not a folder; the run writes the outputs of "
                   f"study 'special_out' in it: remove it, or give another --out"], err


@posix_only
def test_the_report_of_a_folder_whose_verify_json_is_a_fifo_does_not_hang(tmp_path):
    """The report reads the folder's verdict (verify.json): a FIFO there is no verdict, not a wait for a writer."""
    results = tmp_path / "results"
    (results / "half").mkdir(parents=True)
    (results / "half" / "rows.sqlite").write_bytes(b"")   # an unfinished study: the folder holds one
    os.mkfifo(results / "verify.json")
    proc = run_python("-m", "experiments.report", "--results", results, "--out", tmp_path / "paper", timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "paper" / "report.md").is_file()
