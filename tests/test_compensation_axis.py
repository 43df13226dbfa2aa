"""The axis a controller table is for. Before: ``--compensation siemens-eec`` without ``--axis`` wrote
``$AA_ENC_COMP[0,N,X1]`` and ``MD32450 ... of X1`` for a Z axis whose export says ``Axis;Z`` above the table,
exit 0: loaded as written, Z's pitch error and backlash went into X1."""
from __future__ import annotations

import numpy as np

from cli_calls import cli, one_error_line
from datasets.positioning import axis_test


def z_export(path):
    """A laser export of a Z axis: 4 preamble lines naming the axis, a blank line, a wide table in µm."""
    data, _ = axis_test(rng=np.random.default_rng(4), reversal=-0.003)
    head = ";".join(["Target (mm)"] + [f"Run {r} {d} (µm)" for r in range(1, data.runs + 1) for d in "+-"])
    inter = np.empty((len(data.targets), 2 * data.runs))
    inter[:, 0::2], inter[:, 1::2] = data.up * 1e3, data.down * 1e3
    body = "\n".join(";".join(f"{v:.4f}" for v in np.r_[t, row]) for t, row in zip(data.targets, inter))
    path.write_text("Laser Linear Data Export\nMachine;VTC 1\nAxis;Z\nDate;25.11.2026\n\n" + head + "\n" + body + "\n")
    return path


def test_siemens_needs_the_axis_and_names_what_the_file_says(tmp_path):
    f = z_export(tmp_path / "z.csv")
    out = cli("positioning", f, "--skip-rows", 5, "--compensation", "siemens-eec", tmp_path / "z.mpf")
    one_error_line(out, "--axis is not given", "give --axis NAME", "line 3 of", "'Axis;Z'")
    assert not (tmp_path / "z.mpf").exists()
    out = cli("positioning", f, "--skip-rows", 5, "--compensation", "siemens-eec", tmp_path / "z.mpf", "--axis", "Z1")
    text = (tmp_path / "z.mpf").read_text()
    assert out.returncode == 0 and "$AA_ENC_COMP[0,0,Z1]" in text and "X1" not in text


def test_other_formats_take_the_axis_from_the_file_or_say_it_is_not_given(tmp_path):
    f = z_export(tmp_path / "z.csv")
    out = cli("positioning", f, "--skip-rows", 5, "--compensation", "fanuc-pitch", tmp_path / "z.tap")
    assert out.returncode == 0 and "compensation table for axis 'Z', from line 3" in out.stdout
    assert "AXIS Z VALUES" in (tmp_path / "z.tap").read_text()
    plain = tmp_path / "p.csv"
    plain.write_text("\n".join(f.read_text().splitlines()[5:]) + "\n")
    out = cli("positioning", plain, "--compensation", "csv", tmp_path / "t.csv", "--compensation", "fanuc-pitch",
              tmp_path / "t.tap")
    assert out.returncode == 0, out.stderr
    assert "table, axis not given," in (tmp_path / "t.csv").read_text()
    assert "AXIS NOT GIVEN" in (tmp_path / "t.tap").read_text() and "X1" not in (tmp_path / "t.csv").read_text()


def test_the_api_writers_need_the_axis_as_the_command_line_does():
    """write_siemens_eec / write_fanuc_pitch without an axis wrote the table for X1 / X whatever axis was tested;
    now they refuse it in one line (a ValueError subclass of the package), and write the axis given."""
    import pytest

    import methods
    from fitbench.compensation import CompensationError, compensation_table, write_fanuc_pitch, write_siemens_eec
    from methods import InvalidInputError
    data, _ = axis_test(rng=np.random.default_rng(4), reversal=-0.003)
    table = compensation_table(methods.fit("positioning.gls_polynomial", data), data)
    assert issubclass(CompensationError, InvalidInputError) and issubclass(InvalidInputError, ValueError)
    for call in (lambda: write_siemens_eec(table), lambda: write_siemens_eec(table, axis=None)):
        with pytest.raises(CompensationError, match=r"^siemens-eec: .*no axis is given: give axis=NAME") as err:
            call()
        assert "\n" not in str(err.value)
    with pytest.raises(CompensationError, match=r"^fanuc-pitch: no axis is given: give axis=NAME") as err:
        write_fanuc_pitch(table)
    assert "\n" not in str(err.value)
    for write in (write_siemens_eec, write_fanuc_pitch):
        with pytest.raises(InvalidInputError, match="not a valid axis name"):
            write(table, axis="Z 1")
    sie = write_siemens_eec(table, axis="Z1")
    assert "$AA_ENC_COMP[0,0,Z1]" in sie and "X1" not in sie
    assert "AXIS Z VALUES" in write_fanuc_pitch(table, axis="Z")
    assert "AXIS NOT GIVEN VALUES" in write_fanuc_pitch(table, axis=None)   # as without --axis
