"""The target column of a positioning table under other names, and the refusals when it is not found or its
values jitter. Before: a wide export whose first column is 'Nominal position (mm)', 'Commanded (mm)' or 'Ziel [mm]'
was refused with the long table's columns ('missing column 'target' (need target, direction, run, and actual or
deviation)'), which a wide export does not have, without saying which names are read; a long table whose targets
carry the readout's last digit (0.000 / -0.001 / 0.001) was refused as 'target -0.001 has 0 run(s) in the up
direction'. Figures checked against ISO 230-2's definitions computed here (k = 2)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from positioning_tables import TARGETS, iso_a_um, runs


def wide(path, first, dev):
    head = ";".join([first] + [f"Run {r} {d} (µm)" for r in (1, 2, 3) for d in "+-"])
    rows = [";".join([f"{t:.4f}"] + [f"{dev[d][i, r]:.3f}" for r in range(3) for d in "+-"])
            for i, t in enumerate(TARGETS)]
    path.write_text(head + "\n" + "\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize("first", ["Nominal position (mm)", "Commanded (mm)", "Ziel [mm]"])
def test_other_names_of_the_target_column_are_read(tmp_path, first):
    dev = runs(seed=6)
    out = cli("positioning", wide(tmp_path / "w.csv", first, dev), "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)


def test_a_wide_export_without_a_target_name_is_told_so_in_its_terms(tmp_path):
    dev = runs(seed=6)
    path = wide(tmp_path / "p.csv", "Point", dev)
    out = cli("positioning", path)
    one_error_line(out, "no target column in this wide export", "'Point' is not a name fitbench reads as the target",
                   "Nominal", "Soll", "rename it 'Target (mm)'", '--column "target=Point"')
    assert "need target, direction, run" not in out.stderr
    chosen = cli("positioning", path, "--column", "target=Point", "--json")
    assert chosen.returncode == 0, chosen.stderr
    got = json.loads(chosen.stdout)
    assert got["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)
    assert "the target positions read from column 0 'Point', as --column target=Point says" in got["notes"]


def test_a_long_table_without_a_target_name_lists_the_names(tmp_path):
    path = tmp_path / "l.csv"
    path.write_text("Point,Direction,Run,Deviation (um)\n" + "".join(
        f"{t},{d},{r},{0.1 * r}\n" for t in (0, 100, 200) for d in "+-" for r in (1, 2)))
    one_error_line(cli("positioning", path), "no target column", "Target, Position", "--column target=NAME")


def test_targets_with_readout_jitter_are_said_to_be_read_as_different_targets(tmp_path):
    dev = runs(seed=6)
    jitter = np.random.default_rng(1).choice([-0.001, 0.0, 0.001], size=(len(TARGETS), 3, 2))
    path = tmp_path / "j.csv"
    path.write_text("Target [mm],Direction,Run,Deviation [um]\n" + "".join(
        f"{t + jitter[i, r, k]:.3f},{d},{r + 1},{dev[d][i, r]:.3f}\n"
        for k, d in enumerate("+-") for r in range(3) for i, t in enumerate(TARGETS)))
    one_error_line(cli("positioning", path), "lie within 0.002 mm of each other", "read as different targets",
                   "round the target column")
    rounded = tmp_path / "r.csv"
    rounded.write_text("Target [mm],Direction,Run,Deviation [um]\n" + "".join(
        f"{t:.1f},{d},{r + 1},{dev[d][i, r]:.3f}\n" for d in "+-" for r in range(3) for i, t in enumerate(TARGETS)))
    out = cli("positioning", rounded, "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9)


@pytest.mark.parametrize("up, down", [("Fwd", "Bwd"), ("Forward", "Backward"), ("Hin", "Zurück"), ("Up", "Dn"),
                                      ("Increasing", "Decreasing")])
def test_direction_and_run_order_words_of_run_columns(tmp_path, up, down):
    """Before: 'column 'Run 1 Bwd (µm)' is neither the target, a direction nor a run' (the words were not read, and
    the message did not list those that are)."""
    dev = runs(seed=6)
    head = ";".join(["Target (mm)"] + [f"Run {r} {w} (µm)" for r in (1, 2, 3) for w in (up, down)])
    rows = [";".join([f"{t:.4f}"] + [f"{dev[d][i, r]:.3f}" for r in range(3) for d in "+-"])
            for i, t in enumerate(TARGETS)]
    (tmp_path / "w.csv").write_text(head + "\n" + "\n".join(rows) + "\n")
    out = cli("positioning", tmp_path / "w.csv", "--json")
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert got["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-9) and got["B_mean"] < 0   # ↑ below ↓ as written
    (tmp_path / "x.csv").write_text(head.replace(f"Run 1 {up}", "Run 1 Vor") + "\n" + "\n".join(rows) + "\n")
    one_error_line(cli("positioning", tmp_path / "x.csv"), "'Run 1 Vor (µm)' is neither", "up/down (dn)",
                   "forward/reverse (fwd/rev/bwd, backward, return, hin/rück/zurück")


@pytest.mark.parametrize("forward, reverse", [("Forward", "Backward"), ("Fwd", "Bwd"), ("Vorwärts", "Rückwärts"),
                                              ("Hin", "Zurück"), ("Forward", "Return")])
def test_run_order_words_in_a_long_tables_direction_column_name_the_run_order(tmp_path, forward, reverse):
    """Backward, Bwd, Zurück, Rückwärts, Return were 'direction 'Backward' is not one of +, -, up, down' while
    Forward and Reverse got the run-order explanation (review16 V8): the same mistake, one message."""
    path = tmp_path / "l.csv"
    path.write_text("Target (mm),Direction,Run,Deviation (µm)\n" + "".join(
        f"{t:.1f},{w},{r},0.{r}\n" for w in (reverse, forward) for r in (1, 2) for t in TARGETS))
    one_error_line(cli("positioning", path), f"direction {reverse!r} names the run order", "write + or -")


@pytest.mark.parametrize("target, run", [("Target / mm", "Run {r} {d} / µm"), ("Target/mm", "Run {r} {d}/um"),
                                         ("Target in mm", "Run {r} {d} in µm"), ("Position in mm", "Run {r} {d} in nm")])
def test_din_1313_unit_forms_of_a_wide_export_are_read(tmp_path, target, run):
    """DIN 1313 writes a unit after '/' or 'in' ('Run 1 + / µm', 'Position in mm'): a wide export named so was
    refused ('column 'Run 1 + / µm' is neither the target, a direction nor a run'; with 'in', 'the table has the
    length column(s) 'Target in mm'', blaming the target). Its deviations are read in the header's unit: A equals
    ISO 230-2's from the runs, computed here."""
    dev = runs(seed=6)
    scale = 1e3 if run.endswith("nm") else 1.0
    head = ";".join([target] + [run.format(r=r, d=d) for r in (1, 2, 3) for d in "+-"])
    rows = [";".join([f"{t:.4f}"] + [f"{dev[d][i, r] * scale:.3f}" for r in range(3) for d in "+-"])
            for i, t in enumerate(TARGETS)]
    path = tmp_path / "din.csv"
    path.write_text(head + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    out = cli("positioning", path, "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["A"] * 1e3 == pytest.approx(iso_a_um(dev), abs=1e-6)


@pytest.mark.parametrize("run, words", [("Run {r} {d} in cm", "carries the unit 'cm'"),
                                        ("Run {r} {d} in mrad", "angle unit"),
                                        ("Run {r} {d} in X", "is neither the target, a direction nor a run"),
                                        ("Run {r} {d} in s", "is neither the target, a direction nor a run")])
def test_a_word_after_in_that_is_no_unit_read_is_refused(tmp_path, run, words):
    """After 'in' a unit fitbench does not read (cm, mrad) is refused as in brackets, and a word that is no unit
    ('in X', 'in s') makes no run column: each was read as a run in mm, exit 0 (A 0.850 µm for deviations in cm)."""
    dev = runs(seed=6)
    head = ";".join(["Target in mm"] + [run.format(r=r, d=d) for r in (1, 2, 3) for d in "+-"])
    rows = [";".join([f"{t:.4f}"] + [f"{dev[d][i, r]:.3f}" for r in range(3) for d in "+-"])
            for i, t in enumerate(TARGETS)]
    path = tmp_path / "in.csv"
    path.write_text(head + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    one_error_line(cli("positioning", path), words)
