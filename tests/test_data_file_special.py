"""A study's ``file = ...`` data set that exists but is not a regular file (a device such as /dev/zero, a FIFO, a
folder) is refused in one line saying what it is, before any row runs, without blocking; "no data file ... is
relative to the TOML" is said only when nothing is there (it was said of /dev/zero, an absolute path that exists)."""
import os
import sys

import pytest

from experiments.run import main as run_main


def _study(folder, file):
    toml = folder / "special.toml"
    toml.write_text(f'name = "special"\ntitle = "a special data file"\nseed = 1\nrepetitions = 1\n[[datasets]]\n'
                    f'file = "{file}"\n[[methods]]\nid = "circle.kasa"\n', encoding="utf-8")
    return toml


@pytest.mark.parametrize("kind", ["character device", "FIFO", "folder", "missing"])
def test_a_data_file_that_is_not_a_regular_file_is_one_line(tmp_path, capsys, kind):
    if kind == "character device":
        if not os.path.exists("/dev/zero"):
            pytest.skip("no /dev/zero on this system")
        file, said = "/dev/zero", "/dev/zero: is a character device, not a regular file; read a regular file"
    elif kind == "FIFO":
        if not hasattr(os, "mkfifo") or sys.platform == "win32":
            pytest.skip("no FIFOs on this system")
        os.mkfifo(tmp_path / "points.csv")
        file, said = "points.csv", f"{tmp_path / 'points.csv'}: is a FIFO (named pipe), not a regular file"
    elif kind == "folder":
        (tmp_path / "points").mkdir()
        file, said = "points", f"{tmp_path / 'points'}: is a folder, not a regular file"
    else:
        file, said = "points.csv", f"no data file {tmp_path / 'points.csv'} (file = 'points.csv' is relative to the TOML)"
    out = tmp_path / "out"
    assert run_main([str(_study(tmp_path, file)), "--jobs", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("experiments.run: error: special.toml datasets[0]: "), err
    assert said in err[0], err
    assert "no data file" not in err[0] or kind == "missing"
