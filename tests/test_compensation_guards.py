"""What keeps a wrong controller table out of the machine (``fitbench positioning --compensation``): a table
from deviations the reader finds implausible (µm read as mm), or with values or a backlash beyond what a
machine axis has, is refused unless the deviations' unit is given explicitly."""
from __future__ import annotations

import numpy as np
import pytest

import methods
from datasets.positioning import axis_test, to_frame
from fitbench.compensation import (BACKLASH_LIMIT_MM, WRITERS, CompensationError, magnitude_problem,
                                   compensation_table, write_tables)
from cli_calls import cli, one_error_line


def um_file(path, header="deviation", **kw):
    """A long ISO 230-2 table whose deviations are in µm (a laser export's), the unit not in ``header``."""
    kw = {"travel": (-400.0, 600.0), "pitch": (0.0, 0.015, -0.004, 0.002), "reversal": -0.004,
          "repeatability": 0.0004, **kw}
    data, _ = axis_test(rng=np.random.default_rng(7), **kw)
    frame = to_frame(data, actual=False)
    frame["deviation"] *= 1e3
    frame.rename(columns={"deviation": header}).to_csv(path, index=False)
    return data


@pytest.mark.parametrize("fmt", list(WRITERS))
def test_micrometres_read_as_millimetres_write_no_controller_file(tmp_path, fmt):
    """The reader warns that the deviations are implausible (µm read as mm): the table (±11 mm values, a
    3.9 mm backlash) used to be written anyway, exit 0. Now one line, exit 2, no file."""
    um_file(tmp_path / "a.csv")
    out = cli("positioning", tmp_path / "a.csv", "--compensation", fmt, tmp_path / "t.txt")
    one_error_line(out, "not writing", "t.txt", "implausible", "--deviation-unit um", "--deviation-unit mm to confirm")
    assert not (tmp_path / "t.txt").exists() and out.stdout == ""


def test_the_stated_unit_writes_the_table(tmp_path):
    """With --deviation-unit um the same file gives a µm-level table and no refusal; the header's unit does
    the same."""
    data = um_file(tmp_path / "a.csv")
    out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "um", "--compensation", "csv", tmp_path / "t.csv")
    assert out.returncode == 0 and out.stderr == "", out.stderr
    assert (tmp_path / "t.csv").exists()
    um_file(tmp_path / "b.csv", header="deviation [um]")
    out = cli("positioning", tmp_path / "b.csv", "--compensation", "csv", tmp_path / "u.csv")
    assert out.returncode == 0 and out.stderr == "", out.stderr
    rows = [[l for l in (tmp_path / n).read_text().splitlines() if not l.startswith("#")] for n in ("t.csv", "u.csv")]
    assert rows[0] == rows[1] and len(rows[0]) > 2
    comp = np.loadtxt(rows[0][1:], delimiter=",", usecols=4)
    assert 0 < np.max(np.abs(comp)) < 0.05 > np.max(np.abs(data.up))   # mm: the µm-level pitch error


def test_confirming_mm_writes_with_a_warning(tmp_path):
    """--deviation-unit mm is the user's word that the values are mm: the table is written, and a warning says
    what it holds."""
    um_file(tmp_path / "a.csv")
    out = cli("positioning", tmp_path / "a.csv", "--deviation-unit", "mm", "--axis", "X1", "--compensation", "siemens-eec",
              tmp_path / "t.mpf")
    assert out.returncode == 0 and (tmp_path / "t.mpf").exists()
    assert "warning: the compensation table holds values up to" in out.stderr and "backlash of" in out.stderr


def test_a_backlash_beyond_the_bound_is_refused_without_the_unit(tmp_path):
    """No reader warning (the deviations are small) but a 0.8 mm reversal value: the backlash entry is beyond
    what a drive has, refused unless the unit is confirmed; a normal 4 µm backlash passes."""
    data, _ = axis_test(rng=np.random.default_rng(3), reversal=-0.8, repeatability=0.0005)
    res = methods.fit("positioning.gls_polynomial", data)
    assert "backlash of 0.8" in magnitude_problem(compensation_table(res, data))
    written = []
    with pytest.raises(CompensationError, match=r"not writing t\.mpf: .*backlash of 0\.8\d* mm \(more than "
                                                rf"{BACKLASH_LIMIT_MM:g} mm\)"):
        write_tables(res, data, [("siemens-eec", "t.mpf")], write=lambda p, t: written.append(p), axis="X1")
    assert written == []
    told = []
    write_tables(res, data, [("siemens-eec", "t.mpf")], write=lambda p, t: written.append(p), axis="X1", unit_confirmed=True,
                 on_confirmed=told.append)
    assert written == ["t.mpf"] and "backlash" in told[0]
    ok, _ = axis_test(rng=np.random.default_rng(3), reversal=-0.004, repeatability=0.0005)
    assert magnitude_problem(compensation_table(methods.fit("positioning.gls_polynomial", ok), ok)) is None
