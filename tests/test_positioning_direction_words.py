"""A long positioning table whose directions the reader does not take (``1``/``2``, as some laser software numbers
them) is refused in one line that lists every spelling the reader takes and says what to write; each listed
spelling reads (the deviations of each direction as written). Before: 'direction '1' is not one of +, -, up, down',
which left out ↑/↓, pos/neg and the others the reader takes, and gave no way out."""
from __future__ import annotations

import re

import numpy as np

from cli_calls import cli, one_error_line
from datasets.io.positioning import read_positioning
from positioning_tables import TARGETS, runs


def long_table(path, dev, up, down):
    path.write_text("Target (mm),Direction,Run,Deviation (µm)\n" + "".join(
        f"{t:.3f},{w},{r + 1},{dev[d][i, r]:.3f}\n" for d, w in (("+", up), ("-", down))
        for r in range(3) for i, t in enumerate(TARGETS)), encoding="utf-8")
    return path


def test_numbered_directions_are_refused_listing_what_is_read(tmp_path):
    out = cli("positioning", long_table(tmp_path / "n.csv", runs(seed=9), "1", "2"))
    one_error_line(out, "line 2: direction '1' is not a direction fitbench reads",
                   "a number does not say which way the axis moved", "write + for the runs that approached the "
                   "targets in the + direction", "and - for those in the - direction", absent=["is not one of"])
    listed = re.search(r"\(also read: ([^)]*)\) and - for those in the - direction \(([^)]*)\)", out.stderr)
    assert listed, out.stderr
    up = ["+"] + listed.group(1).split(", ")
    down = ["-"] + listed.group(2).split(", ")
    for word in ("up", "↑", "pos", "positive", "increasing"):
        assert word in up
    for word in ("down", "dn", "↓", "neg", "negative", "decreasing"):
        assert word in down
    dev = runs(seed=9)
    for u, d in zip(up + up[-2:-1], down):              # every listed spelling (the lists differ by one in length)
        for case in (str.lower, str.upper):
            data = read_positioning(long_table(tmp_path / "w.csv", dev, case(u), case(d)))
            np.testing.assert_allclose(data.up * 1e3, dev["+"], atol=1e-9, err_msg=u)
            np.testing.assert_allclose(data.down * 1e3, dev["-"], atol=1e-9, err_msg=d)


def test_other_unknown_directions_get_the_list_without_the_number_remark(tmp_path):
    out = cli("positioning", long_table(tmp_path / "x.csv", runs(seed=9), "plus", "minus"))
    one_error_line(out, "direction 'plus' is not a direction fitbench reads: write +", "↑", "↓",
                   absent=["a number does not say"])
