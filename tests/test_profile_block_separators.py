"""Two profiles in one file separated by a comment line or a line of separators only (review16 V2).

A blank line between two blocks of points is refused since the blocks check landed; a comment line between them
(``# second diameter``, as CMM and form-tester exports label each feature) was skipped like any comment and the two
diameters were evaluated as one profile (RONt 3.01 µm 'ok'); a line holding only the separator (``,``) was refused
as ``'' is not a number``, not named as what it is."""
from __future__ import annotations

import numpy as np

from cli_calls import cli, one_error_line
from profile_lines import circle_lines


def two_profiles(tmp_path, name, between):
    a, b = circle_lines(10.0), circle_lines(10.02, phase=0.5)
    p = tmp_path / name
    p.write_text("X [mm],Y [mm]\n" + "\n".join(a) + "\n" + between + "\n".join(b) + "\n")
    return p, len(a), len(b)


def test_a_comment_line_between_two_profiles_ends_a_block(tmp_path):
    p, na, nb = two_profiles(tmp_path, "comment.csv", "# second diameter\n")
    blocks = f"(lines 2-{na + 1}, {na + 3}-{na + nb + 2})"
    for args in (("roundness", p), ("fit", "circle.minimum_zone", p)):
        one_error_line(cli(*args), "comment.csv: 2 blocks of points separated by comment lines "
                                   f"('# second diameter', line {na + 2}) {blocks}", "save each block in its own file")


def test_a_line_of_separators_only_between_two_profiles_ends_a_block(tmp_path):
    p, na, nb = two_profiles(tmp_path, "commas.csv", ",\n")
    one_error_line(cli("roundness", p), "commas.csv: 2 blocks of points separated by lines of separators only "
                                        f"(lines 2-{na + 1}, {na + 3}-{na + nb + 2})")


def test_comments_around_the_data_make_no_block(tmp_path):
    """Comment lines above the header, between the header and the data and after the last point: one profile."""
    a = circle_lines(10.0)
    p = tmp_path / "one.csv"
    p.write_text("# part 17\n# operator: A\nX [mm],Y [mm]\n# first diameter\n" + "\n".join(a) + "\n# end\n")
    code, out, err = cli("roundness", p)
    assert code == 0 and "RONt" in out, err


def test_an_instrument_s_summary_after_a_blank_line_is_not_a_second_block(tmp_path):
    """Lines of text after the points ('RONt [µm];4,0813', an instrument's summary) are not a block of points: the
    refusal names the line that is not a number, not '2 blocks of points ... save each block in its own file'."""
    from cli_calls import cli, one_error_line
    t = np.linspace(0.0, 360.0, 360, endpoint=False)
    lines = "".join(f"{a:.3f};{2.0 * np.cos(3 * np.radians(a)):.4f}\n".replace(".", ",") for a in t)
    path = tmp_path / "summary.csv"
    path.write_text("Angle [deg];Deviation [um]\n" + lines + "\nRONt [µm];4,0813\nRONp [µm];2,0\n", encoding="utf-8")
    called = cli("roundness", path)
    one_error_line(called, "line 363", "'RONt [µm]' is not a number")
    assert "blocks" not in called.stderr


def test_a_comment_line_where_the_angle_goes_on_still_ends_a_block(tmp_path):
    """A comment line between points whose angle goes on is not taken for a remark inside one profile: across it the
    values may jump, and the file then holds two things (two sections of a shaft 0.2 mm apart in radius, two bores of
    other centres, a probe re-seated with a new zero 12 µm off), which evaluated as one profile gave RONt 175.7, 73.7 and
    11.3 µm 'ok' (the form is 3 µm). Refused as two blocks, as blank and separator lines are."""
    deg = np.arange(360.0)
    lobes = 0.0015 * np.cos(3 * np.radians(deg))
    halves = ["angle_deg,radius_mm", "# section A (z = 10 mm)"]
    halves += [f"{a:.1f},{20.0 + (0.2 if a >= 180 else 0.0) + d:.6f}" for a, d in zip(deg, lobes)]
    halves.insert(2 + 180, "# section B (z = 40 mm)")
    reseat = ["angle_deg,deviation_um"] + [f"{a:.1f},{1000 * d + (12.0 if a >= 200 else 0.0):.4f}"
                                           for a, d in zip(deg, lobes)]
    reseat.insert(1 + 200, "# probe re-seated")
    t = np.radians(deg)
    centre = np.where(deg >= 200, 0.05, 0.0)[:, None] * [1.0, 0.0]
    r = np.where(deg >= 200, 20.03, 20.0) + lobes
    bores = ["x,y"] + [f"{x:.6f},{y:.6f}" for x, y in np.c_[r * np.cos(t), r * np.sin(t)] + centre]
    bores.insert(1 + 200, "# bore 2")
    for name, lines, extra in (("halves.csv", halves, ()), ("reseat.csv", reseat, ("--nominal-radius", "20")),
                               ("bores.csv", bores, ())):
        p = tmp_path / name
        p.write_text("\n".join(lines) + "\n")
        one_error_line(cli("roundness", p, *extra), f"{name}: 2 blocks of points separated by comment lines",
                       "save each block in its own file")
