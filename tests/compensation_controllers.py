"""Simulated controllers for the compensation tests, written from the manuals independently of the writers.

Each ``read_*`` is a strict parser of its format's grammar (any other line, a gap in the point numbers, a
``-0.000000``, a field out of range or a STEP that does not give MAX is an AssertionError) and returns a
function ``encoder(P, direction)``: where the controller puts the axis' measuring system when P is
commanded, by the manual's rule. ``remeasure`` then repeats the ISO 230-2 test on the simulated machine.
"""
from __future__ import annotations

import re
from decimal import Decimal

import numpy as np

from methods.positioning.data import PositioningData

NUMBER = r"-?\d+\.\d{6}"
BACKLASH = re.compile(r"enter the backlash as -B = (-?\d+\.\d{3}) um")


def _value(text: str) -> Decimal:
    assert re.fullmatch(NUMBER, text), f"not a 6-decimal number: {text!r}"
    assert text != "-0.000000", "negative zero"
    return Decimal(text)


def _backlash(header: str) -> float:
    """The backlash entry the header asks for (mm), 0 when it asks for none."""
    m = BACKLASH.search(header)
    return float(m.group(1)) * 1e-3 if m else 0.0


def _with_backlash(position, beta):
    """The controller's backlash compensation beta (SINUMERIK MD32450: positive when the encoder leads
    the machine part, i.e. the axis travels too little after a reversal): half of it on each approach."""
    def encoder(P, direction):
        return position(P) + (0.5 * beta if direction == "up" else -0.5 * beta)
    return encoder


def read_siemens(text: str):
    """SINUMERIK K3 LEC table: %_N_AX_EEC_INI, ';' comments, CHANDATA(1), $AA_ENC_COMP[0,N,AX]=v for
    N = 0, 1, ..., STEP / MIN / MAX / IS_MODULO, M17. Applied: the compensation value c (linear between
    points, the end values beyond MIN / MAX) modifies the actual value, a positive c moving the axis in
    the negative direction: the encoder settles where e + c(e) = P."""
    assert text.endswith("\n") and "\r" not in text
    lines = text[:-1].split("\n")
    assert lines[0] == "%_N_AX_EEC_INI" and lines[-1] == "M17", lines[:1] + lines[-1:]
    i = 1
    header = []
    while lines[i].startswith(";"):
        header.append(lines[i])
        i += 1
    assert lines[i] == "CHANDATA(1)", lines[i]
    i += 1
    values, axis = [], None
    while (m := re.fullmatch(r"\$AA_ENC_COMP\[0,(\d+),([A-Za-z][A-Za-z0-9_]{0,31})\]=(\S+)", lines[i])):
        assert int(m.group(1)) == len(values), "point numbers must run 0, 1, 2, ..."
        assert axis in (None, m.group(2))
        axis = m.group(2)
        values.append(_value(m.group(3)))
        i += 1
    rest = {}
    for key in ("STEP", "MIN", "MAX", "IS_MODULO"):
        m = re.fullmatch(rf"\$AA_ENC_COMP_{key}\[0,{axis}\]=(\S+)", lines[i])
        assert m, lines[i]
        rest[key] = m.group(1)
        i += 1
    assert i == len(lines) - 1, "nothing after the table but M17"
    assert rest["IS_MODULO"] == "0"
    step, lo, hi = (_value(rest[k]) for k in ("STEP", "MIN", "MAX"))
    n = len(values)
    assert 2 <= n <= 200 and step > 0
    assert lo + step * (n - 1) == hi, "MIN + STEP (n - 1) must be MAX as printed"
    grid = np.array([float(lo + step * k) for k in range(n)])
    c = np.array([float(v) for v in values])

    def position(P):
        e = np.asarray(P, float).copy()
        for _ in range(4):                       # e + c(e) = P (np.interp holds the end values beyond the table)
            e = P - np.interp(e, grid, c)
        return e
    return _with_backlash(position, _backlash("\n".join(header))), {"grid": grid, "values": c, "axis": axis}


FANUC_BIDIRECTIONAL = re.compile(r"\(SET 3605 BIT 0 = 1 BIDIRECTIONAL PITCH ERROR COMPENSATION, 3626 = (\d+), "
                                 r"3627 = (-?\d+) IN UNITS OF ([0-9.]+) (MM|IN);[^()]*\)")
FANUC_SET = re.compile(r"\(SET 3620 = (\d+) REFERENCE POSITION AT (-?\d+\.\d{6}) MM, 3621 = (\d+), 3622 = (\d+), "
                       r"3623 = (\d+), 3624 = (\d+) I\.E\. (\d+\.\d{6}) MM(?:, \d+\.\d{6} IN,)? IN UNITS OF ([0-9.]+) "
                       r"(MM|IN);[^()]*\)")


def read_fanuc(text: str, detection_unit_mm: float = 0.001, machine_reference_mm: float | None = None,
               increment_mm: float | None = None):
    """FANUC parameter tape of pitch-error data: '%', comments '(...)' of upper-case ASCII without
    parentheses inside, 'N<10000 + number> P<integer>' for consecutive numbers 0 ... 1023, '%'. The
    parameters 3620-3624 and the reference position are those the operator sets from the SET comment.
    Applied: the increments (x detection unit x 3623) are summed from the reference position, point
    3620 + k holding the change over (R + (k-1) d, R + k d]; the compensation is output with the command
    (encoder = P + C(P)), stepwise: the increment of a point is output when the axis reaches the end of
    its section seen from R. ``machine_reference_mm``: where the machine's reference position really is (the
    controller anchors the table there whatever the tape's comment says); default: the position the comment names.
    ``increment_mm``: the machine's least input increment, the unit of 3624 (an inch machine's 0.0001 in = 0.00254
    mm, whatever the tape's comment says); default: the unit the comment names.

    Bidirectional pitch-error compensation (technical report A-77810E: 3605#0 = 1, 3626 the most negative point of
    the table for travel in the negative direction, 3627 the absolute compensation at the reference position for the
    direction opposite to the reference return), when the tape's SET 3605 comment asks for it: the table for travel
    in the negative direction is the points 3626 ... 3626 + (3622 - 3621), with the sections of the positive one, its
    increments summed from 3627 at the reference position; each direction's table is applied when the axis
    approaches in that direction. The reference return's direction is the one whose table holds 0 at R (the comment
    says which)."""
    assert text.endswith("\n") and "\r" not in text
    lines = text[:-1].split("\n")
    assert lines[0] == "%" and lines[-1] == "%"
    params, bidir, header, points = None, None, [], []
    for line in lines[1:-1]:
        if line.startswith("("):
            assert re.fullmatch(r"\([A-Z0-9 .,:;=+\-/*]*\)", line), line
            if line.startswith("(SET 3620"):
                params = FANUC_SET.fullmatch(line)
            if line.startswith("(SET 3605"):
                bidir = FANUC_BIDIRECTIONAL.fullmatch(line)
                assert bidir, line
            header.append(line)
            continue
        m = re.fullmatch(r"N1(\d{4}) P(-?\d+)", line)
        assert m, line
        no, v = int(m.group(1)), int(m.group(2))
        assert 0 <= no <= 1023 and -128 <= v <= 127, line
        assert not points or no == points[-1][0] + 1, "point numbers must be consecutive"
        points.append((no, v))
    assert params and points
    ref_no, r_mm, p21, p22, mag, p24 = (int(params.group(1)), float(params.group(2)), int(params.group(3)),
                                        int(params.group(4)), int(params.group(5)), int(params.group(6)))
    inc_mm = float(params.group(8)) * (25.4 if params.group(9) == "IN" else 1.0)
    if increment_mm is not None:
        inc_mm = float(increment_mm)
    if machine_reference_mm is not None:
        r_mm = float(machine_reference_mm)
    n = p22 - p21 + 1
    p26 = int(bidir.group(1)) if bidir else None
    if bidir:                      # the negative direction's block after (or before) the positive one, no overlap
        assert p26 > p22 or p26 + n - 1 < p21, "the two blocks must not overlap"
        assert {p[0] for p in points} == set(range(p21, p22 + 1)) | set(range(p26, p26 + n)), "both blocks, whole"
        assert float(bidir.group(3)) > 0 and bidir.group(4) == params.group(9)
    else:
        assert p21 == points[0][0] and p22 == points[-1][0]
    assert p21 <= ref_no < p22
    assert 1 <= mag <= 100 and 1 <= p24 <= 99_999_999
    d = p24 * inc_mm
    unit = detection_unit_mm * mag
    nos = np.array([p[0] for p in points])
    vals = np.array([p[1] for p in points], float) * unit

    def table(first: int, at_reference: float):
        """The absolute compensation of the block first ... first + n - 1 (laid out as 3621 ... 3622) at every grid
        index it covers, and those indices."""
        sel = (nos >= first) & (nos < first + n)
        k_of = nos[sel] - first + p21 - ref_no                 # point ref + k covers (R + (k-1) d, R + k d]
        v = vals[sel]
        ks = np.arange(k_of[0] - 1, k_of[-1] + 1)              # grid indices with an absolute value
        absolute = np.full(ks.size, at_reference)
        for j, k in enumerate(ks):
            if k > 0:
                absolute[j] += v[(k_of >= 1) & (k_of <= k)].sum()
            elif k < 0:
                absolute[j] -= v[(k_of >= k + 1) & (k_of <= 0)].sum()
        return ks, absolute

    def applied(ks, absolute):
        def compensation(P):
            t = (np.asarray(P, float) - r_mm) / d
            k = np.trunc(t + np.sign(t) * 1e-9)                # the last grid point reached from R
            k = np.clip(k, ks[0], ks[-1])
            return absolute[(k - ks[0]).astype(int)]
        return compensation

    head = "\n".join(header).lower().replace("  ", " ")
    m = re.search(r"enter the backlash as -b = (-?\d+\.\d{3}) um", head)
    beta = float(m.group(1)) * 1e-3 if m else 0.0
    if not bidir:
        ks, absolute = table(p21, 0.0)
        compensation = applied(ks, absolute)

        def position(P):
            return np.asarray(P, float) + compensation(P)
        return _with_backlash(position, beta), {"reference_number": ref_no, "magnification": mag, "p3624": p24,
                                                "numbers": nos, "values": vals}
    assert "set 1851 = 0" in head and not m, "a tape per direction holds the reversal: no backlash"
    p27 = int(bidir.group(2)) * detection_unit_mm          # detection units (the tape has 3623 = 1)
    assert mag == 1
    returns_up = "reference return in the positive direction" in head
    assert returns_up or "reference return in the negative direction" in head
    comp = {"up": applied(*table(p21, 0.0 if returns_up else p27)),
            "down": applied(*table(p26, p27 if returns_up else 0.0))}

    def encoder(P, direction):
        return np.asarray(P, float) + comp[direction](P)
    return encoder, {"reference_number": ref_no, "magnification": mag, "p3624": p24, "numbers": nos, "values": vals,
                     "p3626": p26, "p3627": int(bidir.group(2))}


def read_csv(text: str, per_direction: bool = False):
    """The generic CSV: '# ' header lines, the column line, rows of 6-decimal numbers (the up / down
    columns may be empty), equally spaced positions. Applied: compensation_mm is added to the commanded
    position (linear between rows, the end values beyond), with the backlash the header asks for.
    ``per_direction``: a controller taking a table per direction applies compensation_up_mm in travel in the positive
    direction and compensation_down_mm in the negative, with no backlash (the header says so)."""
    assert text.endswith("\n")
    lines = text[:-1].split("\n")
    header = [l for l in lines if l.startswith("# ")]
    body = lines[len(header):]
    assert lines[:len(header)] == header, "header lines come first"
    columns = "position_mm,deviation_mm,deviation_up_mm,deviation_down_mm,compensation_mm"
    assert body[0] in (columns, columns + ",compensation_up_mm,compensation_down_mm"), body[0]
    width = body[0].count(",") + 1
    assert width == 7 or not per_direction, "no per-direction columns"
    rows = []
    for line in body[1:]:
        cells = line.split(",")
        assert len(cells) == width, line
        rows.append([_value(c) if (c or k not in (2, 3)) else None for k, c in enumerate(cells)])
    pos = [r[0] for r in rows]
    steps = {b - a for a, b in zip(pos, pos[1:])}
    assert len(steps) == 1 and steps.pop() > 0, "positions equally spaced, increasing"
    grid = np.array([float(p) for p in pos])
    comp = np.array([float(r[4]) for r in rows])

    if per_direction:
        assert "with compensation_up_mm and compensation_down_mm (a table per direction) enter none" in "\n".join(header)
        tables = {"up": np.array([float(r[5]) for r in rows]), "down": np.array([float(r[6]) for r in rows])}

        def encoder(P, direction):
            return np.asarray(P, float) + np.interp(P, grid, tables[direction])
        return encoder, {"grid": grid, "values": comp, **tables}

    def position(P):
        return np.asarray(P, float) + np.interp(P, grid, comp)
    return _with_backlash(position, _backlash("\n".join(header))), {"grid": grid, "values": comp}


READERS = {"csv": read_csv, "siemens-eec": read_siemens, "fanuc-pitch": read_fanuc}


def remeasure(data: PositioningData, truth, encoder, rng, repeatability=0.0005) -> PositioningData:
    """The ISO 230-2 test repeated on the compensated machine: at each target and approach the axis is
    at encoder(P) and the laser reads truth_dir(encoder) + (encoder - P) + noise."""
    out = {}
    for d in data.directions:
        e = encoder(data.targets, d)
        dev = truth[d](e) + (e - data.targets) + truth["delta"]
        out[d] = dev[:, None] + rng.normal(0.0, repeatability, (len(data.targets), data.runs))
    return PositioningData(targets=data.targets, up=out.get("up"), down=out.get("down"), unit="mm")
