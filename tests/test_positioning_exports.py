"""Real positioning exports: trailers after the table, the column names of laser software, a target written
-0,0000, FANUC IS-C. Before: a trailer (blank line, 'Environment compensation: automatic', 'End of data') was
refused as 'line 22: missing field(s)' with no hint; 'Actual position [mm]', 'Error (µm)', 'Dir', 'Richtung'
were refused; the -0,0000 target printed as -0.000 / -0 mm; the CLI wrote FANUC tables in IS-B units only."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

import methods
from cli_calls import cli, one_error_line
from compensation_controllers import read_fanuc, remeasure
from datasets.positioning import axis_test


def axis(seed=3):
    return axis_test(rng=np.random.default_rng(seed), travel=(-1000.0, 0.0), reversal=-0.004,
                     pitch=(0.0, 0.030, -0.045, 0.022), repeatability=0.0004)


def wide(data, trailer="", decimal_comma=True):
    """A Renishaw-like wide export of a Z axis tested 0 -> -1000 mm (targets written -0,0000 first), µm."""
    rows = []
    for i in np.argsort(-data.targets):
        cells = [f"{data.targets[i] if data.targets[i] else -0.0:.4f}"]
        for j in range(data.runs):
            cells += [f"{data.up[i, j] * 1e3:.3f}", f"{data.down[i, j] * 1e3:.3f}"]
        rows.append(";".join(c.replace(".", ",") if decimal_comma else c for c in cells))
    head = ";".join(["Target (mm)"] + [f"Run {r} {d} (µm)" for r in range(1, data.runs + 1) for d in "+-"])
    return head + "\n" + "\n".join(rows) + "\n" + trailer


def test_a_trailer_after_a_blank_line_is_left_out_and_named(tmp_path):
    data, _ = axis()
    (tmp_path / "plain.csv").write_text(wide(data))
    (tmp_path / "trail.csv").write_text(wide(data, "\nEnvironment compensation: automatic\nEnd of data\n"))
    ref = json.loads(cli("positioning", tmp_path / "plain.csv", "--json").stdout)
    out = cli("positioning", tmp_path / "trail.csv", "--json")
    assert out.returncode == 0, out.stderr
    assert "lines 14-15 after the blank line below the table are not data rows" in out.stderr
    assert "'Environment compensation: automatic'" in out.stderr
    got = json.loads(out.stdout)
    assert all(got[k] == ref[k] for k in ("A", "E", "M", "R", "B_mean"))


def test_a_trailer_without_a_blank_line_is_refused_saying_what_to_do(tmp_path):
    data, _ = axis()
    (tmp_path / "t.csv").write_text(wide(data, "End of data\n"))
    one_error_line(cli("positioning", tmp_path / "t.csv"), "line 13: 'End of data' is not a data row",
                   "delete the lines after the table")


@pytest.mark.parametrize("actual, deviation, direction", [("Actual position [mm]", "Error (µm)", "Dir"),
                                                          ("Actual [mm]", "Deviation (µm)", "Richtung")])
def test_column_names_of_real_exports(tmp_path, actual, deviation, direction):
    data, _ = axis()
    ref = methods.fit("positioning.iso230_2", data).figures
    rows = [(t, d, j + 1, getattr(data, key)[i, j]) for key, d in (("up", "+"), ("down", "-"))
            for i, t in enumerate(data.targets) for j in range(data.runs)]
    (tmp_path / "act.csv").write_text(f"Target position [mm];{direction};Run;{actual}\n" + "".join(
        f"{t:.4f};{d};{r};{t + e:.7f}\n".replace(".", ",") for t, d, r, e in rows))
    (tmp_path / "err.csv").write_text(f"Target (mm),{direction},Run,{deviation}\n" + "".join(
        f"{t:.4f},{d},{r},{e * 1e3:.4f}\n" for t, d, r, e in rows))
    for f in ("act.csv", "err.csv"):
        out = cli("positioning", tmp_path / f, "--json")
        assert out.returncode == 0, out.stderr
        got = json.loads(out.stdout)
        for k in ("A", "E", "M", "R", "B_mean"):
            assert got[k] == pytest.approx(ref[k], abs=2e-7), (f, k)
    # a wide export with a direction column named Dir / Richtung
    lines = [f"Position;{direction};" + ";".join(f"Lauf {r}" for r in range(1, data.runs + 1))]
    for key, d in (("up", "up"), ("down", "down")):
        lines += [f"{t:.4f};{d};" + ";".join(f"{v:.7f}" for v in getattr(data, key)[i]) for i, t in enumerate(data.targets)]
    (tmp_path / "wd.csv").write_text("\n".join(lines) + "\n")
    got = json.loads(cli("positioning", tmp_path / "wd.csv", "--json").stdout)
    assert got["B_mean"] == pytest.approx(ref["B_mean"], abs=2e-7)


def test_a_target_written_minus_zero_prints_as_zero(tmp_path):
    data, _ = axis()
    (tmp_path / "z.csv").write_text(wide(data))
    out = cli("positioning", tmp_path / "z.csv", "--compensation", "csv", tmp_path / "t.csv")
    assert out.returncode == 0, out.stderr
    assert "-0.000 " not in out.stdout and re.search(r"^\s+0\.000\s", out.stdout, re.M)
    assert "(-0 " not in out.stdout and "to -0 " not in out.stdout
    assert "measured travel -1000 to 0 mm" in (tmp_path / "t.csv").read_text()


def test_fanuc_is_c_from_the_command_line(tmp_path):
    data, truth = axis()
    (tmp_path / "z.csv").write_text(wide(data))
    out = cli("positioning", tmp_path / "z.csv", "--compensation", "fanuc-pitch", tmp_path / "t.tap",
              "--fanuc-increment", "0.0001")
    assert out.returncode == 0, out.stderr
    text = (tmp_path / "t.tap").read_text()
    step = float(re.search(r"every ([\d.]+) mm", out.stdout).group(1))
    assert "IN 0.0001 MM" in text and f"3624 = {round(step / 0.0001)} " in text
    encoder, _ = read_fanuc(text, detection_unit_mm=0.0001)
    before = methods.fit("positioning.iso230_2", data).figures
    after = methods.fit("positioning.iso230_2", remeasure(data, truth, encoder, np.random.default_rng(9))).figures
    assert after["M"] <= 0.5 * before["M"], (before["M"], after["M"])


def space_aligned(tmp_path):
    """(the ';' export's lines, its lines aligned with spaces, as written to ``tmp_path/ws.txt``) of :func:`axis`."""
    data, _ = axis()
    semi = wide(data, decimal_comma=False).splitlines()
    aligned = ["    ".join(f"{c:>14}" for c in ln.split(";")) for ln in semi]
    (tmp_path / "ws.txt").write_text("\n".join(aligned) + "\n")
    return semi, aligned


def test_a_space_aligned_table_whose_names_contain_spaces(tmp_path):
    """A wide export aligned with spaces, header 'Target (mm)    Run 1 + (µm) ...': read by splitting the header at
    runs of spaces (before: 'line 2: missing field(s); if line 1 is an instrument's preamble, give --skip-rows 1');
    when that does not give the rows' field count either, one line says why."""
    semi, aligned = space_aligned(tmp_path)
    (tmp_path / "semi.csv").write_text("\n".join(semi) + "\n")
    got = json.loads(cli("positioning", tmp_path / "ws.txt", "--json").stdout)
    ref = json.loads(cli("positioning", tmp_path / "semi.csv", "--json").stdout)
    assert all(got[k] == ref[k] for k in ("A", "E", "M", "R", "B_mean"))
    bad = aligned[:]
    bad[0] = bad[0].replace("Run 1 +", "Run  1 +")                            # one name split in two
    (tmp_path / "bad.txt").write_text("\n".join(bad) + "\n")
    out = cli("positioning", tmp_path / "bad.txt")
    one_error_line(out, "its names contain spaces", "separate the columns with tabs or ';'")
    assert "--skip-rows" not in out.stderr
    comma = tmp_path / "c.csv"                                # a ','-table missing a field: not a spaces matter
    comma.write_text("Target (mm),Direction,Run,Deviation (um)\n0,+,1,\n100,+,1,\n")
    one_error_line(cli("positioning", comma), "line 2: missing field(s)")


def test_a_space_aligned_table_with_spaces_in_its_names_and_a_trailer(tmp_path):
    """Both at once: the header split at runs of spaces is decided on the table's rows, not on the trailer after the
    blank line below it (it was refused: 'line 2: missing field(s); if line 1 is an instrument's preamble, ...')."""
    _, aligned = space_aligned(tmp_path)
    (tmp_path / "trail.txt").write_text("\n".join(aligned) + "\n\nOperator: X\n")
    ref = json.loads(cli("positioning", tmp_path / "ws.txt", "--json").stdout)
    out = cli("positioning", tmp_path / "trail.txt", "--json")
    assert out.returncode == 0, out.stderr
    assert f"line {len(aligned) + 2} after the blank line below the table is not a data row" in out.stderr
    got = json.loads(out.stdout)
    assert all(got[k] == ref[k] for k in ("A", "E", "M", "R", "B_mean"))
