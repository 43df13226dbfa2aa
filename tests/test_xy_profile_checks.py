"""x, y profiles held to the checks angle + deviation files already get (review16 V3, V5).

An x, y trace recorded over more than one revolution (0 .. 371.9° in steps of 0.10003°: no angle repeated) was
evaluated as one profile, RONt 4.3873 µm 'ok'; it is refused naming the lines to keep, its polar angles taken about
the points' circle. An x, y file in mm read as µm (a 10 mm part: radius 0.01 mm, RONt 0.0041 µm 'ok', fit form error
4.6e-06 mm) said nothing; the span of the points' distances from their circle below 10 nm is warned about, naming mm."""
from __future__ import annotations

import numpy as np
import pytest

from cli_calls import cli, one_error_line


def xy_file(path, deg, dev_um, radius=10.0, header="X [mm],Y [mm]", digits=7):
    t = np.radians(deg)
    r = radius + dev_um * 1e-3
    path.write_text(header + "\n" + "".join(f"{x:.{digits}f},{y:.{digits}f}\n" for x, y in zip(r * np.cos(t),
                                                                                              r * np.sin(t))))
    return path


def overlapping(start=0.0, sign=1.0):
    """A trace over 371.9° (time-sampled: steps of 0.10003°) with 3-lobing and 0.8 µm of drift."""
    deg = np.arange(3719) * 0.10003
    dev = 2.0 * np.cos(np.radians(3 * deg)) + 0.8 * deg / deg[-1]
    return start + sign * deg, dev, np.flatnonzero(deg >= 360.0)


@pytest.mark.parametrize("start, sign", [(0.0, 1.0), (180.0, 1.0), (0.0, -1.0)])
def test_an_xy_trace_over_more_than_one_revolution_is_refused_naming_the_lines(tmp_path, start, sign):
    deg, dev, past = overlapping(start, sign)
    p = xy_file(tmp_path / "ov.csv", deg, dev)
    one_error_line(cli("roundness", p), f"ov.csv: the profile covers {np.ptp(deg):.6g}° (the points' polar angles "
                   f"about their circle's centre), more than one revolution ({past.size} points at or beyond 360° from "
                   f"the first, lines {past[0] + 2}-{past[-1] + 2}); a roundness profile is one revolution "
                   f"(ISO 12181-1): keep lines 2-{past[0] + 1}")
    code, out, err = cli("fit", "circle.gauss_newton", p)          # a fit still takes a multi-revolution trace
    assert code == 0, err
    first = xy_file(tmp_path / "first.csv", deg[:past[0]], dev[:past[0]])
    code, out, err = cli("roundness", first)
    assert code == 0 and "RONt" in out, err


def test_an_xy_file_in_mm_read_as_micrometres_is_warned_about(tmp_path):
    deg = np.arange(3600) * 0.1
    p = xy_file(tmp_path / "part.csv", deg, 2.0 * np.cos(np.radians(3 * deg)), header="x,y")
    span_um = 4.0 * 1e-3                                   # 4 µm of form read as µm: 4 nm, about a radius of 0.01 mm
    for args in (("roundness", p), ("fit", "circle.minimum_zone", p)):
        code, out, err = cli(*args, "--unit", "um")
        assert code == 0, err
        line = next(ln for ln in err.splitlines() if "distances from the centre" in ln)
        said = float(line.split(" span ")[1].split(" µm")[0])
        assert said == pytest.approx(span_um, rel=0.01), line
        assert line.startswith("fitbench: warning: the points' distances from the centre of their circle in ")
        assert "part.csv span " in line
        assert ("about a radius of 0.01 mm (read as µm, as --unit says): below the 10 nm a roundness instrument, a CMM "
                "or a ballbar resolves, not a measured profile; is the file in mm? (give --unit mm)") in line
        assert "Traceback" not in err
        assert "distances from the centre" not in cli(*args).stderr                    # read in mm: a 4 µm form
    header = xy_file(tmp_path / "hdr.csv", deg, 2.0 * np.cos(np.radians(3 * deg)), header="x [um],y [um]")
    assert "(read as µm, as the header of 'x [um]' and 'y [um]' says)" in cli("fit", "circle.kasa", header).stderr
    assert "correct the header to [mm]" in cli("fit", "circle.kasa", header).stderr


def test_an_exact_circle_written_rounded_is_not_warned_about(tmp_path):
    """An exact circle's distances span a step or two of the numbers' rounding (6 decimals): a made-up profile, not
    a unit mistake, whatever unit it is read in."""
    deg = np.arange(360) * 1.0
    p = xy_file(tmp_path / "exact.csv", deg, np.zeros(deg.size), header="x,y", digits=6)
    for unit in ("um", "mm"):
        assert "distances from the centre" not in cli("fit", "circle.kasa", p, "--unit", unit).stderr
