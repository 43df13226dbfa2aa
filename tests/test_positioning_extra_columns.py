"""Columns a wide positioning export writes beside its runs that are clearly not runs: a point number counting the
targets (``Point``, ``Target No.``, ``Target number``, as laser software numbers its targets) and environment
readings (``Air temp (°C)``, ``Pressure (hPa)``, ``Humidity (%)``) are not read and are named in a ``not read:``
note, as the long table names its unread columns; the figures are those of the same file without them (ISO 230-2's
A computed here by its definition). A column that could be a run with a typo in its name, a length column under an
environment word, or a point-number name over values that do not count the targets is still refused, saying what
to do. Before: every such column was refused ('column 'Point' is neither the target, a direction nor a run'),
with no action and no way out (``--column target=...`` did not help)."""
from __future__ import annotations

import json

import pytest

from cli_calls import cli, one_error_line
from positioning_tables import TARGETS, iso_a_um, runs

RUN_NAMES = [f"Run {r} {d} (µm)" for r in (1, 2, 3) for d in "+-"]


def wide(path, dev, before=(), after=(), names=RUN_NAMES):
    """A wide export of ``dev`` with the columns ``before`` / ``after`` ((name, [cell per target]), ...) around the
    target and run columns."""
    head = [n for n, _ in before] + ["Target (mm)"] + list(names) + [n for n, _ in after]
    rows = [[c[i] for _, c in before] + [f"{t:.3f}"] + [f"{dev[d][i, r]:.3f}" for r in range(3) for d in "+-"]
            + [c[i] for _, c in after] for i, t in enumerate(TARGETS)]
    path.write_text("\n".join(";".join(r) for r in [head] + rows) + "\n")
    return path


def figures(path, *more):
    out = cli("positioning", path, "--json", *more)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


COUNT = [str(i + 1) for i in range(len(TARGETS))]


@pytest.mark.parametrize("before, after, unread", [
    ([("Point", COUNT)], [], "column 0 'Point'"),
    ([("Target No.", COUNT)], [], "column 0 'Target No.'"),
    ([("Target number", [str(i) for i in range(len(TARGETS))])], [], "column 0 'Target number'"),
    ([("Point", COUNT[::-1])], [], "column 0 'Point'"),
    ([], [("Air temp (°C)", ["20.12"] * 5), ("Material temp (°C)", ["20.31"] * 5)],
     "column 7 'Air temp (°C)', column 8 'Material temp (°C)'"),
    ([("Nr.", COUNT)], [("Pressure (hPa)", ["1013.2"] * 5), ("Humidity (%)", ["45"] * 5),
                        ("Air temperature", ["20.1"] * 5)],
     "column 0 'Nr.', column 8 'Pressure (hPa)', column 9 'Humidity (%)', column 10 'Air temperature'"),
])
def test_columns_that_are_not_runs_are_named_and_not_read(tmp_path, before, after, unread):
    dev = runs(seed=12)
    plain = figures(wide(tmp_path / "plain.csv", dev))
    got = figures(wide(tmp_path / "extra.csv", dev, before, after))
    assert got["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)
    for name in ("A", "E", "R", "B", "M", "B_mean", "A_up", "A_down", "R_up", "R_down"):
        assert got[name] == plain[name], name
    assert f"not read: {unread}" in got["notes"]
    text = cli("positioning", tmp_path / "extra.csv")
    assert text.returncode == 0, text.stderr
    assert f"note: not read: {unread}" in text.stdout + text.stderr


def test_a_point_column_beside_a_direction_column_counts_the_targets_of_each_direction(tmp_path):
    dev = runs(seed=12)
    head = "Point;Target (mm);Direction;Run 1 (µm);Run 2 (µm);Run 3 (µm)"
    rows = [f"{k + 1};{TARGETS[i]:.3f};{d};" + ";".join(f"{dev[d][i, r]:.3f}" for r in range(3))
            for d in "+-" for k, i in enumerate(range(len(TARGETS)) if d == "+" else reversed(range(len(TARGETS))))]
    path = tmp_path / "wd.csv"
    path.write_text("\n".join([head] + rows) + "\n")
    got = figures(path)
    assert got["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)
    assert "not read: column 0 'Point'" in got["notes"]


def test_the_wide_export_of_the_docs_with_a_point_number_and_temperatures(tmp_path):
    """docs/examples/positioning.csv with a point number first and two temperatures last gives its A, 8.498 µm."""
    from pathlib import Path
    lines = (Path(__file__).resolve().parents[1] / "docs/examples/positioning.csv").read_text().splitlines()
    path = tmp_path / "docs_extra.csv"
    path.write_text("\n".join([f"Point;{lines[0]};Air temp (°C);Material temp (°C)"]
                              + [f"{k};{line};20.1;20.3" for k, line in enumerate(lines[1:], 1)]) + "\n")
    assert figures(path)["A"] * 1e3 == pytest.approx(8.498, abs=5e-4)


@pytest.mark.parametrize("before, after, words", [
    ([], [("Rnu 4 + (µm)", ["1.0"] * 5)], ["column 'Rnu 4 + (µm)' is neither the target, a direction nor a run",
                                           "name it as a run", "else delete the column"]),
    ([], [("Temp (µm)", ["1.0"] * 5)], ["column 'Temp (µm)' is neither the target, a direction nor a run"]),
    ([], [("Runn 4 -", ["1.0"] * 5)], ["column 'Runn 4 -' is neither"]),
    ([("Point", ["-1.2", "0.4", "2.2", "-0.7", "1.9"])], [],
     ["column 0 'Point' has a point number's name, but its values (-1.2, 0.4, 2.2, -0.7, ...) do not count the 5 "
      "targets", "delete the column"]),
    ([("Point", ["1", "2", "2", "4", "5"])], [], ["column 0 'Point' has a point number's name"]),
    ([("Point (µm)", COUNT)], [], ["column 'Point (µm)' is neither"]),
])
def test_a_column_that_may_hold_deviations_is_still_refused(tmp_path, before, after, words):
    one_error_line(cli("positioning", wide(tmp_path / "bad.csv", runs(seed=12), before, after)), *words)
