"""NIST's Circle2d reference pairs as published (``cir2dN.ds``: a count line, then x y z; ``cir2dN.fit``: centre,
normal, diameter) become the files the ``nist`` data source reads (``python -m datasets.nist_circle2d``), so an outside
user can reproduce the nist_circle study; without FITBENCH_NIST_DIR the study says "(not set)" and how to make the
folder (it said "(got None)" and nothing else)."""
import json
import os
import subprocess
import sys
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest

from datasets import nist_circle2d
from datasets.sources import get_source
from experiments.provenance import REPO


def _nist_folder(folder: Path, number=1, centre=(12.5, -40.25), radius=7.0, y=3.14159):
    """One Circle2d pair in NIST's format: points in the plane y = const, so the set is (x, z)."""
    folder.mkdir(parents=True, exist_ok=True)
    t = np.linspace(0.2, 5.9, 9)
    x, z = centre[0] + radius * np.cos(t), centre[1] + radius * np.sin(t)
    lines = [f"{a:.5f} {y:.5f} {b:.5f}" for a, b in zip(x, z)]
    (folder / f"cir2d{number}.ds").write_text(f"{len(lines)}\n" + "\n".join(lines) + "\n", encoding="ascii")
    fit = ["12.500000000000000000", f"{y:.5f}", "-40.25", "0", "1", "0", "14.0000000000000000000"]
    (folder / f"cir2d{number}.fit").write_text("\n".join(fit) + "\n", encoding="ascii")
    return np.c_[np.round(x, 5), np.round(z, 5)]


def test_a_circle2d_pair_becomes_a_set_of_the_nist_source(tmp_path, monkeypatch):
    points = _nist_folder(tmp_path / "Circle2d", number=7)
    assert nist_circle2d.main([str(tmp_path / "Circle2d"), str(tmp_path / "out")]) == 0
    meta = json.loads((tmp_path / "out" / "nist_cir2d_07.json").read_text(encoding="ascii"))
    assert meta["n_points"] == 9 and meta["plane_axes"] == "x=x, y=z (constant y=3.14159)"
    assert meta["reference_least_squares"] == {"center": ["12.5", "-40.25"], "diameter": "14"}
    monkeypatch.setenv("FITBENCH_NIST_DIR", str(tmp_path / "out"))
    data, truth = get_source("nist").load(None, name="nist_cir2d_07")
    np.testing.assert_array_equal(np.asarray(data), points)
    assert truth["center"] == [12.5, -40.25] and truth["radius"] == 7.0


def test_a_fit_file_of_another_shape_is_one_line(tmp_path, capsys):
    _nist_folder(tmp_path / "Circle2d")
    (tmp_path / "Circle2d" / "cir2d1.fit").write_text("1\n2\n3\n4\n", encoding="ascii")
    assert nist_circle2d.main([str(tmp_path / "Circle2d"), str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cir2d1.fit: a circle's fit holds 7 numbers" in err[0], err
    assert not (tmp_path / "out").exists()


NIST = os.environ.get("FITBENCH_NIST_DIR")


@pytest.mark.skipif(not NIST or not Path(NIST).is_dir(),
                    reason="no converted NIST Circle2d sets to write back: FITBENCH_NIST_DIR is not set to their folder")
def test_the_converted_sets_written_back_in_nist_s_format_convert_to_the_same_bytes(tmp_path):
    """The sets of FITBENCH_NIST_DIR written back in NIST's Circle2d format (a count line, x y z with five decimals
    and the constant coordinate; the fit's 7 numbers, the diameter with a trailing zero) and converted again give
    the same bytes: they are what the converter makes of files in that format holding their numbers, nothing lost
    or added. NIST's own zip is not here (no network): this is no comparison with NIST's files, whose numbers it
    takes to be the ones the converted sets hold."""
    import re
    source = Path(NIST)
    sets = sorted(source.glob("nist_cir2d_*.json"))
    assert sets, f"FITBENCH_NIST_DIR={NIST} holds no nist_cir2d_NN.json (python -m datasets.nist_circle2d writes them)"
    for j in sets:
        meta = json.loads(j.read_text(encoding="ascii"))
        a, b, c, const = re.fullmatch(r"x=(\w), y=(\w) \(constant (\w)=(.*)\)", meta["plane_axes"]).groups()
        rows = []
        for line in j.with_suffix(".csv").read_text(encoding="ascii").splitlines()[1:]:
            v = dict(zip((a, b), map(float, line.split(","))), **{c: float(const)})
            rows.append(" ".join(f"{v[k]:.5f}" for k in "xyz"))
        n = int(j.stem.rsplit("_", 1)[1])
        (tmp_path / "Circle2d").mkdir(exist_ok=True)
        (tmp_path / "Circle2d" / f"cir2d{n}.ds").write_text(f"{len(rows)}\n" + "\n".join(rows) + "\n")
        ref = meta["reference_least_squares"]
        centre = {a: ref["center"][0], b: ref["center"][1], c: f"{Decimal(const):.5f}"}
        fit = [centre[k] for k in "xyz"] + [("1" if k == c else "0") for k in "xyz"] + [ref["diameter"] + "0"]
        (tmp_path / "Circle2d" / f"cir2d{n}.fit").write_text("\n".join(fit) + "\n")
    nist_circle2d.convert(tmp_path / "Circle2d", tmp_path / "out")
    for f in sorted(source.glob("nist_cir2d_*")):
        assert (tmp_path / "out" / f.name).read_bytes() == f.read_bytes(), f.name


def test_without_the_folder_the_study_says_not_set_and_how_to_make_it(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "FITBENCH_NIST_DIR"}
    run = subprocess.run([sys.executable, "-m", "experiments.run", "nist_circle", "--out", str(tmp_path / "o")],
                         cwd=REPO, env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    err = run.stderr.strip().splitlines()
    assert len(err) == 1 and "(not set)" in err[0] and "None" not in err[0], err
    assert "python -m datasets.nist_circle2d" in err[0], err


@pytest.mark.parametrize("field", ["x", "1.2.3", "nan", "inf"])
def test_a_point_that_is_not_a_number_names_the_file_and_line(tmp_path, capsys, field):
    """Before: "could not convert string to float: 'x'", naming neither the file nor the line (nan/inf passed)."""
    _nist_folder(tmp_path / "Circle2d")
    ds = tmp_path / "Circle2d" / "cir2d1.ds"
    lines = ds.read_text(encoding="ascii").splitlines()
    lines[4] = f"{lines[4].split()[0]} {field} {lines[4].split()[2]}"
    ds.write_text("\n".join(lines[:2]) + "\n\n" + "\n".join(lines[2:]) + "\n", encoding="ascii")   # a blank line too
    assert nist_circle2d.main([str(tmp_path / "Circle2d"), str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"datasets.nist_circle2d: error: cir2d1.ds, line 6: {field!r} is not a finite number "
                   f"(a line holds the x y z of one point)"], err
    assert not (tmp_path / "out").exists()
