"""FITBENCH_NIST_DIR naming a folder without the converted Circle2d sets (NIST's raw download, any other folder) is
refused in one line before any row, as an unset or missing folder is; it ran 0 rows and crashed in the analysis."""
import pytest

from experiments.run import main as run_main

GOOD = ('{"name": "nist_cir2d_01", "reference_least_squares": {"center": ["1.5", "2.5"], "diameter": "4.0"}}')


@pytest.mark.parametrize("files, words", [
    ({}, "holds no nist_cir2d_*.json"),
    ({"Circle2d_01.txt": "raw NIST data\n"}, "holds no nist_cir2d_*.json"),
    ({"nist_cir2d_01.json": GOOD}, "holds nist_cir2d_01.json without nist_cir2d_01.csv"),
    ({"nist_cir2d_01.json": "{}", "nist_cir2d_01.csv": "x,y\n1,2\n"}, "KeyError"),
    ({"nist_cir2d_01.json": GOOD.replace('"4.0"', '"four"'), "nist_cir2d_01.csv": "x,y\n1,2\n"}, "InvalidOperation"),
])
def test_a_folder_without_converted_sets_is_refused_before_any_row(tmp_path, monkeypatch, capsys, files, words):
    folder = tmp_path / "nist"
    folder.mkdir()
    for name, text in files.items():
        (folder / name).write_text(text, encoding="utf-8")
    monkeypatch.setenv("FITBENCH_NIST_DIR", str(folder))
    out = tmp_path / "out"
    assert run_main(["nist_circle", "--jobs", "1", "--out", str(out), "--no-report"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0] and "python -m datasets.nist_circle2d" in err[0], err
    assert not (out / "nist_circle").exists()
