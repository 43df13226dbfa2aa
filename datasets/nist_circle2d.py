"""``python -m datasets.nist_circle2d SOURCE OUT``: NIST's Circle2d reference pairs as the ``nist`` data source reads
them (the ``nist_circle`` study; ``FITBENCH_NIST_DIR=OUT``).

NIST publishes the least-squares reference pairs of its Algorithm Testing System (Shakarji, J. Res. NIST 103 (6),
633-641, 1998) as one zip, "NIST-L2-reference-pairs", on the page of its dimensional metrology group's algorithm
testing (https://www.nist.gov/pml/sensor-science/dimensional-metrology/algorithm-testing). Its folder ``Circle2d``
holds 30 data sets ``cir2d1.ds`` ... ``cir2d30.ds`` and their fits ``cir2dN.fit``. By the zip's own explanations:
a ``.ds`` file is plain text, its first line the number of points, then one point a line, x y z (five decimals), the
points of a 2D set lying in a plane parallel to a coordinate plane (one coordinate the same for all points); a
circle's ``.fit`` file holds 7 numbers, one a line: the centre (x y z), the direction cosines of the normal of the
circle's plane, and the diameter, correct to every digit given.

``SOURCE`` is that ``Circle2d`` folder; for each ``cir2dN`` this writes into ``OUT``:

* ``nist_cir2d_NN.csv``: header ``x,y``, then the two coordinates that vary (x y, x z or y z, in that order), each as
  the shortest text of its float (``-555.16770`` -> ``-555.1677``);
* ``nist_cir2d_NN.json``: ``name``, ``n_points``, ``plane_axes`` (which coordinates were kept and the constant one),
  ``reference_least_squares`` with ``center`` (the fit's two kept coordinates) and ``diameter`` as decimal texts with
  every digit of the ``.fit`` file (trailing zeros dropped), and ``source``.

A run records the SHA-256 of each file it read (``meta.json``, ``inputs``): ``python -m experiments.verify`` compares
a run on files converted here with the committed results only when the bytes are the same.
"""
from __future__ import annotations

import json
import math
import re
import sys
from decimal import Decimal, InvalidOperation
from pathlib import Path

SOURCE_TEXT = ("NIST Algorithm Testing System, 'L2 reference pairs', Circle2d (least-squares reference fits, reported "
               "by NIST as correct to all digits given)")
AXES = "xyz"


class NistFormatError(ValueError):
    """A file of the Circle2d folder that is not in the format NIST's explanations give."""


def _decimal_text(token: str, where: str) -> str:
    """Every digit of a number of a ``.fit`` file, in fixed notation without trailing zeros."""
    try:
        value = Decimal(token)
    except InvalidOperation:
        raise NistFormatError(f"{where}: {token!r} is not a number") from None
    text = format(value, "f")
    return text.rstrip("0").rstrip(".") if "." in text else text


def _text(path: Path) -> str:
    try:
        return path.read_text(encoding="ascii")
    except UnicodeDecodeError as exc:
        raise NistFormatError(f"{path.name}: not ASCII text (byte {exc.start}); NIST's files are plain text") from None


def read_ds(path: Path) -> list[list[str]]:
    """The points of a ``.ds`` file as texts [x, y, z] (the first line, the number of points, is checked); a field
    that is not a finite number is refused naming the file and its line."""
    numbered = [(i, ln.split()) for i, ln in enumerate(_text(path).splitlines(), start=1) if ln.strip()]
    if numbered and len(numbered[0][1]) == 1:
        count, numbered = numbered[0][1][0], numbered[1:]
        if not count.isdigit() or int(count) != len(numbered):
            raise NistFormatError(f"{path.name}: the first line says {count} points, the file holds {len(numbered)}")
    bad = [(i, ln) for i, ln in numbered if len(ln) != 3]
    if bad or len(numbered) < 3:
        raise NistFormatError(f"{path.name}: expected a count line and 3 or more lines of x y z"
                              + (f" (line {bad[0][0]} has {len(bad[0][1])} fields)" if bad else ""))
    for i, ln in numbered:
        for t in ln:
            try:
                finite = math.isfinite(float(t))
            except ValueError:
                finite = False
            if not finite:
                raise NistFormatError(f"{path.name}, line {i}: {t!r} is not a finite number (a line holds the "
                                      f"x y z of one point)")
    return [ln for _, ln in numbered]


def convert_one(ds: Path, fit: Path, name: str) -> tuple[str, str]:
    """(CSV text, JSON text) of one Circle2d pair."""
    points = read_ds(ds)
    columns = list(zip(*points))
    constant = [k for k in range(3) if len({float(v) for v in columns[k]}) == 1]
    if len(constant) != 1:
        raise NistFormatError(f"{ds.name}: a Circle2d set has one coordinate the same for all points, this one "
                              f"{len(constant)}")
    c = constant[0]
    kept = [k for k in range(3) if k != c]
    numbers = _text(fit).split()
    if len(numbers) != 7:
        raise NistFormatError(f"{fit.name}: a circle's fit holds 7 numbers (centre, normal, diameter), "
                              f"this one {len(numbers)}")
    fitted = [_decimal_text(t, fit.name) for t in numbers]
    csv = "x,y\n" + "".join(f"{float(p[kept[0]])!r},{float(p[kept[1]])!r}\n" for p in points)
    meta = {"name": name, "n_points": len(points),
            "plane_axes": f"x={AXES[kept[0]]}, y={AXES[kept[1]]} (constant {AXES[c]}={float(columns[c][0])!r})",
            "reference_least_squares": {"center": [fitted[kept[0]], fitted[kept[1]]], "diameter": fitted[6]},
            "source": SOURCE_TEXT}
    return csv, json.dumps(meta, indent=1)


def convert(source: Path, out: Path) -> list[str]:
    """Convert every ``cir2dN.ds`` of ``source`` with its ``.fit`` into ``out``; the names written."""
    found = sorted((int(m.group(1)), p) for p in Path(source).glob("*.ds")
                   if (m := re.fullmatch(r"cir2d(\d+)", p.stem, re.IGNORECASE)))
    if not found:
        raise NistFormatError(f"{source}: no cir2dN.ds file; give the Circle2d folder of NIST's "
                              f"NIST-L2-reference-pairs zip")
    converted = []
    for n, ds in found:
        fit = ds.with_suffix(".fit")
        if not fit.is_file():
            raise NistFormatError(f"{ds.name} has no {fit.name} beside it")
        name = f"nist_cir2d_{n:02d}"
        csv, meta = convert_one(ds, fit, name)
        converted.append((name, csv, meta))
    out.mkdir(parents=True, exist_ok=True)
    for name, csv, meta in converted:
        (out / f"{name}.csv").write_text(csv, encoding="ascii")
        (out / f"{name}.json").write_text(meta, encoding="ascii")
    return [name for name, _, _ in converted]


def main(argv=None) -> int:
    import argparse
    parser = argparse.ArgumentParser(prog="python -m datasets.nist_circle2d",
                                     description="Convert NIST's Circle2d reference pairs (cir2dN.ds/.fit) into the "
                                                 "files of the nist data source (nist_cir2d_NN.csv/.json).")
    parser.add_argument("source", type=Path, help="the Circle2d folder of NIST's NIST-L2-reference-pairs zip")
    parser.add_argument("out", type=Path, help="the folder to write; then FITBENCH_NIST_DIR=OUT")
    args = parser.parse_args(argv)
    try:
        names = convert(args.source, args.out)
    except (NistFormatError, OSError, UnicodeDecodeError, ValueError) as exc:
        print(f"datasets.nist_circle2d: error: {exc}", file=sys.stderr)
        return 2
    print(f"{len(names)} sets written to {args.out} ({names[0]} ... {names[-1]}); "
          f"run the study with FITBENCH_NIST_DIR={args.out} python -m experiments.run nist_circle")
    return 0


if __name__ == "__main__":
    sys.exit(main())
