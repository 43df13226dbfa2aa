"""The helpers the ``fitbench`` subcommands share (each one's module: :mod:`fitbench.cli.fit`,
:mod:`fitbench.cli.roundness`, :mod:`fitbench.cli.history`, ...): the reader, tolerance and report options, reading a profile, checking and writing
output files, the PASS/FAIL verdict. Below the subcommand modules: it imports none of them.

Bad input is an :class:`~methods.InvalidInputError` (one line on stderr, exit status 2, in
:func:`fitbench.cli.commands.main`); lengths on the command line and in tolerances are in mm and µm.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from methods import InvalidInputError
from methods.files import writable_target
from methods.units import UNIT_CHOICES, canonical, warn_implausible


def version() -> str:
    from fitbench import __version__
    return __version__


#: the program the user ran, which starts every error and warning line (set by :func:`fitbench.cli.commands.main`)
PROGRAM = "fitbench"


#: the running command's warnings (:func:`fitbench.cli.commands.main` sets both, None outside a command): the Python
#: warnings (a reader's UnitWarning, ...) recorded and not printed yet, and every warning line printed so far
CAUGHT: list | None = None
SAID: list | None = None


def warn(message: str) -> None:
    """Print one ``PROGRAM: warning: ...`` line now, and keep it for the command's report and JSON
    (:func:`said_warnings`)."""
    print(f"{PROGRAM}: warning: {message}", file=sys.stderr)
    if SAID is not None:
        SAID.append(str(message))


def said_warnings() -> list[str]:
    """Every warning the running command has given, each once, in order: the Python warnings recorded since the
    last call (UserWarning and its subclasses) are printed first as :func:`warn` lines. A subcommand calls it
    before it prints its figures, writes its report or its JSON, so that the warnings come before the numbers on
    the terminal and are written into the report page and the JSON's ``warnings``, beside the notes."""
    if CAUGHT:
        pending = list(CAUGHT)
        del CAUGHT[:]
        for w in pending:
            if issubclass(w.category, UserWarning):
                warn(str(w.message))
    return list(dict.fromkeys(SAID or []))


#: the JSON a ``--json`` command printed while :func:`fitbench.cli.commands.main` keeps stdout for it alone (what
#: anything else prints meanwhile, e.g. a plugin when it is imported, goes to stderr); None: printed at once
JSON_PENDING: list | None = None


def print_json(text: str) -> None:
    """Print a command's JSON object: held until the command ends when its stdout is guarded (``--json``, see
    :data:`JSON_PENDING`), so that stdout carries the JSON alone, else printed now."""
    if JSON_PENDING is not None:
        JSON_PENDING.append(text)
    else:
        print(text)


def finite(name: str, value, *, positive: bool = False, allow_none: bool = True):
    """A command-line number: finite (and > 0 with ``positive``), else a one-line error."""
    if value is None and allow_none:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v) or (positive and v <= 0):
        raise InvalidInputError(f"{name} must be a {'positive' if positive else 'finite'} number, got {value!r}")
    return v


def check_plot_path(path, option: str = "--plot") -> Path | None:
    """Refuse, before any computation, a plot file in a missing folder or with a format matplotlib cannot write;
    ``option``: the option that gave it (named in the error line)."""
    if path is None:
        return None
    path = Path(path)
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    formats = Figure().canvas.get_supported_filetypes()
    ext = path.suffix.lower().lstrip(".")
    if path.is_dir():
        raise InvalidInputError(f"{option} {path}: is a folder; give a file name such as "
                                f"{path / ('report.pdf' if option == '--report' else 'plot.png')}")
    if ext not in formats:
        raise InvalidInputError(f"{option} {path}: unknown image format {path.suffix or '(none)'!r}; "
                                f"use one of .{', .'.join(sorted(formats))}")
    target = writable_target(path)  # a FIFO, a device or a folder: refused now, not after the computation
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        raise InvalidInputError(f"{option} {path}: the folder {parent} does not exist; create it first")
    return path


def save_figure(fig, path, dpi=120) -> None:
    """Write a matplotlib figure (:func:`fitbench.plots.write_figure`) with the command's other outputs, to the one
    temporary :func:`fitbench.cli.guards.output_path` gives (no atomic write nested inside it); a failed write is one
    line."""
    from fitbench.cli.guards import output_path
    from fitbench.plots import write_figure
    try:
        with output_path(path) as tmp:
            write_figure(fig, tmp, dpi=dpi)
    except OSError as exc:
        raise InvalidInputError(f"cannot write {path}: {exc.strerror or exc}") from None


def write_text_atomic(path, text: str) -> None:
    """Write a text output file atomically into an existing folder, with the command's other outputs
    (:func:`fitbench.cli.guards.output_path`); one line on failure."""
    from fitbench.cli.guards import output_path
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InvalidInputError(f"{path}: the folder {parent} does not exist; create it first")
    try:
        with output_path(path) as tmp:
            Path(tmp).write_bytes(text.encode("utf-8"))
    except OSError as exc:
        raise InvalidInputError(f"cannot write {path}: {exc.strerror or exc}") from None


def add_reader_options(p, *, columns=True, polar=False, angles=True, printed: str = "µm"):
    """--unit, --skip-rows (and --columns / --plane; with ``polar`` --angle-unit): the options of every file reader;
    ``angles``: the command reads angle + radial-deviation files too (said in --columns' help); ``printed``: the unit
    the command prints lengths in (whatever the input's)."""
    p.add_argument("--unit", default=None, choices=UNIT_CHOICES,
                   help="length unit of the input file(s) (default: the header's unit, e.g. 'x [um]', else mm); "
                        f"the input is converted to mm and lengths are printed in {printed}")
    p.add_argument("--skip-rows", type=int, default=0, metavar="N",
                   help="skip N lines at the top of each file (the instrument's preamble)")
    if columns:
        g = p.add_mutually_exclusive_group()
        g.add_argument("--columns", nargs=2, metavar=("A", "B"),
                       help="the two columns to read (header names, case and spaces ignored, or 0-based numbers): "
                            + ("x y, or an angle and a radial deviation / radius" if angles else "x y")
                            + " (default: from the header)")
        g.add_argument("--plane", choices=("xy", "yz", "zx"), help="the plane's two named columns (x,y / y,z / z,x)")
    if polar:
        p.add_argument("--angle-unit", choices=("deg", "rad"),
                       help="angle column of an angle + radial-deviation file (default: the header's, e.g. 'angle [deg]')")


def header_line(command: str, unit: str | None, extra: str = "", deviation_unit: str | None = None) -> str:
    unit = unit or "mm"
    units = canonical(unit) + (f", deviations {canonical(deviation_unit)}" if deviation_unit else "")
    converted = canonical(unit) != "mm" or (deviation_unit and canonical(deviation_unit) != "mm")
    return (f"fitbench {version()} {command}: input unit {units}{' (converted to mm)' if converted else ''}; "
            f"lengths printed in µm{extra}")


#: a bare ``--tolerance`` (µm) that the figure it judges exceeds this many times or more is likely a drawing's mm
#: value (A=0.1 meant as 0.1 mm read as 0.1 µm: FAIL for an 8.5 µm axis, 85 times it; a machine or part that is
#: accepted or rejected is not ten times out of tolerance; a tolerance meant in µm is said so with ``um``)
TOLERANCE_SUSPECT_RATIO = 10.0


def add_tolerance_option(p, names: str):
    p.add_argument("--tolerance", action="append", metavar="NAME=VALUE",
                   help=f"a tolerance in µm (a bare number) or with its unit (NAME=10um, NAME=0.01mm) for one of the "
                        f"standard's figures ({names}); repeatable: PASS/FAIL in the table, the JSON and the plot (the "
                        "exit status does not change); a bare number that the figure it judges exceeds "
                        f"{TOLERANCE_SUSPECT_RATIO:g} times or more is warned about (is it in mm?)")


#: a number with an optional unit after it: '10', '10um', '10 µm', '0.01mm', '1e-2 mm'
NUMBER_WITH_UNIT = r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\d\s.+-][^\s]*)?\s*"


def refuse_decimal_comma(what: str, text: str, example: str) -> None:
    """Refuse a value written with a decimal comma (``10,5um``, ``10,5 um``, ``0,5``) in one line saying so, with the
    value written with a point (``example`` formats it), rather than as an unknown unit ',5um'."""
    import re
    m = re.fullmatch(r"\s*([-+]?\d*),(\d+)(\s*\S*)\s*", str(text))
    if m:
        point = example.format(f"{m.group(1)}.{m.group(2)}{m.group(3)}")
        if len(m.group(2)) == 3 and m.group(1).lstrip("+-"):  # 1,000: a decimal comma or a thousands separator
            raise InvalidInputError(f"{what}: a comma in the number, a decimal comma or a thousands separator; write "
                                    f"{point} if it is decimal, "
                                    f"{example.format(f'{m.group(1)}{m.group(2)}{m.group(3)}')} if it separates "
                                    f"thousands")
        raise InvalidInputError(f"{what}: a decimal comma; write the number with a point, e.g. {point}")


#: feed units: mm/min per unit (a bare --feed is mm/min)
FEED_MM_PER_MIN = {"mm/min": 1.0, "m/min": 1000.0, "mm/s": 60.0, "in/min": 25.4}


def quantity(option: str, kind: str = "length"):
    """An argparse ``type`` for an option taking a length (a bare number in mm, or with its unit: 150mm, 0.15m,
    5.9in, 150 µm) or, with ``kind="feed"``, a feed (a bare number in mm/min, or 2000mm/min, 2m/min, 33mm/s): the
    value in mm (mm/min). A bare 'nan' or 'inf' passes as a float for the command's own check of the number; anything
    else is one line naming the unit to give."""
    import argparse
    import re
    from methods.units import mm_per
    base, examples = (("mm/min", "2000mm/min, 2m/min") if kind == "feed" else ("mm", "150mm, 0.15m, 5.9in"))

    def parse(text):
        try:
            refuse_decimal_comma(repr(str(text)), text, f"{option} {{}}")
        except InvalidInputError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        m = re.fullmatch(NUMBER_WITH_UNIT, str(text))
        if not m:
            try:
                return float(text)   # nan, inf: refused by the command's check of a finite number
            except ValueError:
                raise argparse.ArgumentTypeError(f"{text!r} is not a number: give a number in {base} or with its "
                                                 f"unit (e.g. {examples})") from None
        value, unit = float(m.group(1)), m.group(2)
        if unit is None:
            return value
        try:
            factor = (FEED_MM_PER_MIN[unit.lower()] if kind == "feed" else mm_per(unit))
        except (KeyError, InvalidInputError):
            known = ", ".join(FEED_MM_PER_MIN) if kind == "feed" else "mm, um (µm), nm, m, in"
            raise argparse.ArgumentTypeError(f"{text!r}: unknown unit {unit!r}; give a number in {base} or with one "
                                             f"of {known} (e.g. {examples})") from None
        return value * factor
    parse.__name__ = kind
    return parse


class Tolerances(dict):
    """``--tolerance`` items as {figure name: tolerance in mm}, and how each was written: ``texts`` {name: the
    value as given}, ``bare`` the names given as a bare number (µm), which :func:`warn_bare_tolerances` checks."""

    def __init__(self):
        super().__init__()
        self.texts: dict = {}
        self.bare: set = set()

    def given(self, name: str) -> tuple[str, bool] | None:
        """(the tolerance as written, given as a bare number?) of one figure; None if it has no text."""
        return (self.texts[name], name in self.bare) if name in self.texts else None


def parse_tolerances(items, allowed) -> Tolerances:
    """``--tolerance NAME=VALUE`` items as {figure name: tolerance in mm}; ``allowed``: the names (any case). VALUE
    is a length with its unit (``10um``, ``10 µm``, ``0.01mm``, ``500nm``) or a bare number in µm (as the printout)."""
    import re
    from methods.units import mm_per
    out = Tolerances()
    by_lower = {a.lower(): a for a in allowed}
    for item in items or []:
        key, eq, text = str(item).partition("=")
        name = by_lower.get(key.strip().lower())
        if not eq or name is None:
            raise InvalidInputError(f"--tolerance {item!r}: give NAME=VALUE with NAME one of {', '.join(allowed)} and "
                                    "VALUE in µm or with its unit (e.g. 10um, 0.01mm)")
        refuse_decimal_comma(f"--tolerance {item!r}", text, f"{name}={{}}")
        m = re.fullmatch(NUMBER_WITH_UNIT, text)
        if not m:
            raise InvalidInputError(f"--tolerance {item!r}: give the tolerance as a length with its unit, e.g. "
                                    f"{name}=10um or {name}=0.01mm (a bare number is µm)")
        unit = m.group(2)
        factor = 1e-3
        if unit is not None:
            try:
                factor = mm_per(unit)
            except InvalidInputError:
                raise InvalidInputError(f"--tolerance {item!r}: unknown unit {unit!r}; use um (µm), nm or mm, e.g. "
                                        f"{name}=10um or {name}=0.01mm") from None
        value = finite(f"--tolerance {name}", m.group(1), allow_none=False)
        if not value > 0:
            raise InvalidInputError(f"--tolerance {item!r}: a tolerance must be positive, e.g. {name}=10um")
        out[name] = value * factor
        out.texts[name] = text.strip()
        if unit is None:
            out.bare.add(name)
        else:
            out.bare.discard(name)
    return out


def warn_bare_tolerances(tolerances, values_mm: dict) -> None:
    """Warn, naming the unit to give, about each tolerance given as a bare number (µm) that its figure
    (``values_mm``: {name: value in mm}) exceeds :data:`TOLERANCE_SUSPECT_RATIO` times or more, as ``--mpe``'s
    bare number is warned about."""
    for name in sorted(getattr(tolerances, "bare", ()), key=list(tolerances).index):
        tol, value = tolerances[name], values_mm.get(name)
        if value is None or not (math.isfinite(value) and abs(value) >= TOLERANCE_SUSPECT_RATIO * tol):
            continue
        text = tolerances.texts[name]
        warn(f"--tolerance {name}={text} is read as {tol * 1e3:g} µm (a bare number is µm), and {name} is "
             f"{abs(value) * 1e3:.4g} µm, {abs(value) / tol:.3g} times it: is it in mm? give --tolerance {name}={text}mm "
             f"({tol * 1e6:g} µm), or --tolerance {name}={text}um to keep µm")


def verdict(values_mm: dict, tolerances_mm: dict, given: dict | None = None) -> dict | None:
    """PASS/FAIL of each figure against its tolerance (value <= tolerance passes), and the overall verdict;
    None without tolerances. Each check records the tolerance as written (``tolerance_given``, and
    ``tolerance_bare``: a bare number, read as µm), from ``given`` ({figure: (text, bare)}) or, when
    ``tolerances_mm`` is a :class:`Tolerances`, from it."""
    if not tolerances_mm:
        return None
    if given is None and isinstance(tolerances_mm, Tolerances):
        given = {name: tolerances_mm.given(name) for name in tolerances_mm}
    checks = []
    for name, tol in tolerances_mm.items():
        check = {"figure": name, "value_mm": float(values_mm[name]), "tolerance_mm": tol,
                 "result": "PASS" if float(values_mm[name]) <= tol else "FAIL"}
        if given and given.get(name):
            check["tolerance_given"], check["tolerance_bare"] = given[name]
        checks.append(check)
    return {"checks": checks, "overall": "PASS" if all(c["result"] == "PASS" for c in checks) else "FAIL"}


def tolerance_text(check: dict) -> str:
    """'tolerance 10 µm' of a verdict check, saying how a bare number was read: 'tolerance 0.1 µm (a bare
    number: µm)' (a bare ``--tolerance`` is µm, a bare ``--mpe`` mm: the line shows which reading judged)."""
    return (f"tolerance {check['tolerance_mm'] * 1e3:g} µm"
            + (" (a bare number: µm)" if check.get("tolerance_bare") else ""))


def verdict_lines(v: dict | None) -> list[str]:
    if not v:
        return []
    lines = [f"verdict      {v['overall']}"]
    lines += [f"  {c['figure']:<12} {c['value_mm'] * 1e3:10.3f} µm  {tolerance_text(c)}  {c['result']}"
              for c in v["checks"]]
    return lines


#: the test dates ``fitbench history`` reads from a result's conditions (strptime formats; --date writes the first)
DATE_FORMATS = ("%Y-%m-%d", "%Y-%m-%d %H:%M", "%Y-%m-%dT%H:%M:%S", "%d.%m.%Y")


def test_date(text: str) -> str:
    """A ``--date`` as written into a result: YYYY-MM-DD (zero-padded), checked to be a calendar date, so that
    ``fitbench history`` can date the test later; '' (not given) stays ''."""
    import argparse
    import datetime as dt
    text = str(text).strip()
    if not text:
        return ""
    try:
        return dt.datetime.strptime(text, DATE_FORMATS[0]).date().isoformat()
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a date; give the test date as YYYY-MM-DD, "
                                         "e.g. 2026-11-25") from None


def add_test_identity_options(p):
    """--machine and --date of a machine-tool test (circular-test, positioning, roundness): printed in the report
    and recorded in the JSON result's ``details.conditions``, where ``fitbench history`` dates the test."""
    p.add_argument("--machine", default="", help="machine name (the report's title, the JSON result's conditions)")
    p.add_argument("--date", default="", type=test_date, help="test date, YYYY-MM-DD (the report, the JSON result's conditions; "
                                                "'fitbench history' dates the test by it, else by the file's time)")


def test_conditions(args, **more) -> dict:
    """The JSON ``details.conditions`` of a test: its machine and date as given, and ``more``."""
    return {"machine": args.machine, "date": args.date, **more}


def add_report_option(p):
    p.add_argument("--report", metavar="FILE.pdf",
                   help="write a one-page test report: conditions, figures, verdict, diagnostics and the plot")


def write_report(path, title: str, lines: list[str], draw, aspect: float) -> None:
    """The one-page report (:func:`fitbench.plots.report_page.one_page`) with the command's warnings in a box above
    its text (:func:`said_warnings`), written atomically; one line on failure."""
    from fitbench.plots.report_page import one_page
    one_page(path, title=title, lines=lines, draw=draw, aspect=aspect, save=save_figure, warnings=said_warnings())


def verdict_title(v: dict | None) -> str:
    return "" if not v else f"; verdict {v['overall']} (" + ", ".join(
        f"{c['figure']} {c['value_mm'] * 1e3:.2f} µm / {c['tolerance_mm'] * 1e3:g} µm" for c in v["checks"]) + ")"


#: a profile (fit, roundness) whose half extent exceeds this is implausible for its declared unit: a 10 m part
PROFILE_LIMIT_MM = 5000.0
#: a roundness profile whose half extent exceeds this is implausible: roundness instruments take parts well below
#: 2 m in diameter, so a 6 mm pin in µm read as mm (3000 "mm") is warned about, naming µm
ROUNDNESS_LIMIT_MM = 1000.0


#: points whose smaller principal extent is below this fraction of the larger lie on a line for a circle's
#: purposes (an arc under about 0.5°): the two columns read are not the circle's plane
FLAT_RATIO = 1e-3


def flat_points(points, axes=("x", "y")) -> str | None:
    """What is wrong when ``points`` (N, 2, mm) lie on a straight line to :data:`FLAT_RATIO` of their extent: the
    two columns read are likely not the plane of the circle (x, y of a ZX-plane circle: its y is constant, and
    the fits then gave a 3.77 km radius, 'two points at the same polar angle' or 'is the file in µm?'); None
    otherwise."""
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[0] < 3 or not np.isfinite(p).all():
        return None
    q = p - p.mean(axis=0)
    _, _, vt = np.linalg.svd(q, full_matrices=False)
    extent = np.ptp(q @ vt.T, axis=0)
    if not (extent[0] > 0 and extent[1] <= FLAT_RATIO * extent[0]):
        return None
    return (f"the points read as ({axes[0]}, {axes[1]}) lie on a straight line to within {extent[1]:.3g} mm over "
            f"{extent[0]:.6g} mm: no circle in these two columns; if the file holds another coordinate the circle "
            "is in another plane (give --plane or --columns)")


def _polar_value(args) -> str | None:
    """'deviation' or 'radius': what the second column of the angle file ``args.file`` holds
    (:func:`datasets.io.resolve`)."""
    from datasets.io import resolve, sniff
    return resolve(sniff(args.file, args.skip_rows), tuple(args.columns) if args.columns else None,
                   args.plane).polar_value


#: a roundness profile whose radius (half its span) is below this is implausible: roundness instruments take wires
#: and pins down to about 0.1 mm in diameter, so a 10 mm part in mm read as µm (a radius of 0.01 "mm") is warned about
ROUNDNESS_MIN_MM = 0.05


def small_part_problem(half_mm: float, unit: str) -> str:
    """The warning on a roundness profile of radius ``half_mm`` below :data:`ROUNDNESS_MIN_MM`, naming the unit
    that would make its numbers a part's size (about 25 mm), as :func:`methods.units.warn_implausible` does for
    too large profiles."""
    from methods.units import mm_per
    value = half_mm / mm_per(unit)               # the file's numbers, in their declared unit
    fits = [u for u in ("mm", "in", "m") if u != canonical(unit) and ROUNDNESS_MIN_MM <= value * mm_per(u) <= ROUNDNESS_LIMIT_MM]
    best = min(fits, key=lambda u: abs(np.log(value * mm_per(u) / 25.0)), default=None)
    hint = f"; is the file in {best}? (--unit {best})" if best else ""
    return (f"profile radii (half the points' span) of {half_mm:.3g} mm (read as {canonical(unit)}) are implausibly "
            f"small for a roundness part (below {ROUNDNESS_MIN_MM:g} mm){hint}")


def nominal_radius_problem(nominal_mm: float, limit_mm: float, deviation_mm: float | None = None) -> str:
    """The warning on a ``--nominal-radius`` no roundness part (or profile) has: above ``limit_mm`` (likely typed in
    µm), or, with ``deviation_mm``, so small that the deviations are a good part of it (likely typed in m); as
    ``circular-test`` says of its own (:func:`methods.circular_test.evaluation.nominal_mismatch`)."""
    from methods.units import likely_unit, mm_per
    guess = likely_unit(nominal_mm, 25.0)
    hint = (f"is it in {guess}? give --nominal-radius {nominal_mm * mm_per(guess):.6g} (or "
            f"{nominal_mm:g}{guess.replace('µ', 'u')})" if guess else "check its unit (a bare number is mm)")
    if deviation_mm is not None:
        return (f"--nominal-radius {nominal_mm:g} mm is implausibly small for these deviations (up to "
                f"{deviation_mm * 1e3:.3g} µm, {deviation_mm / nominal_mm:.0%} of it); {hint}")
    what = "a roundness part" if limit_mm == ROUNDNESS_LIMIT_MM else "a profile"
    return (f"--nominal-radius {nominal_mm:g} mm is implausible for {what} (radii above {limit_mm:g} mm); {hint}")


def read_profile_args(args, limit_mm: float = PROFILE_LIMIT_MM, refuse_flat: bool = False,
                      min_arc_deg: float | None = None):
    """(source, points in mm, length unit used, notes, names of the two coordinates) of ``fit`` and ``roundness``: a file in any instrument
    layout (x, y or angle + radial deviation, :func:`datasets.io.read_profile`) or a published data set's
    name; sizes implausible for the unit are warned about, naming the likely unit (profile radii, half the span, above
    ``limit_mm``: :data:`PROFILE_LIMIT_MM`, or :data:`ROUNDNESS_LIMIT_MM` for ``roundness``); points on a straight
    line (:func:`flat_points`) are warned about, or refused with ``refuse_flat``; ``min_arc_deg``: the smallest arc
    evaluated (angles in radians read as degrees are refused naming the angle unit, :func:`datasets.io.read_runs`)."""
    from datasets import points_from
    from datasets.io import read_profile
    nominal = finite("--nominal-radius", getattr(args, "nominal_radius", None), positive=True)
    if Path(args.file).exists() or args.unit or args.columns or args.plane or args.skip_rows or nominal:
        got = read_profile(args.file, columns=tuple(args.columns) if args.columns else None, plane=args.plane,
                           unit=args.unit, skip_rows=args.skip_rows, angle_unit=args.angle_unit,
                           nominal_radius=nominal, min_arc_deg=min_arc_deg)
        source, points, unit, notes, axes = str(args.file), got.runs[0][1], got.unit, list(got.notes), got.axes
        polar_alone = got.kind == "polar" and nominal is None and any("without a nominal radius" in n for n in notes)
    else:
        (source, points), unit, notes, polar_alone, axes = points_from(args.file), "mm", [], False, ("x", "y")
        got = None
    points = np.asarray(points, dtype=float)
    if nominal and got is not None and (got.kind != "polar" or _polar_value(args) == "radius"):
        what = "radii, not radial deviations" if got.kind == "polar" else "x, y coordinates"
        notes.append(f"--nominal-radius {nominal:g} mm is not used: the file gives {what} (the option places the "
                     "radial deviations of an angle + deviation file)")
    if (flat := flat_points(points, axes)) is not None:
        if refuse_flat:
            raise InvalidInputError(f"{source}: {flat}")
        warn(f"{source}: {flat}")
    if points.ndim == 2 and points.shape[0] and np.isfinite(points).all():
        if polar_alone:
            # the span of the deviations themselves: their radii about the centre they were placed about (0, 0),
            # not about the points' centroid, which unequal angle steps move metres off a 236 km circle
            span = float(np.ptp(np.hypot(*points.T)))
            warn_implausible("radial deviations spanning", span, 10.0, unit, typical_mm=0.01)
        elif got is not None and got.kind == "polar" and nominal and nominal > limit_mm and \
                float(np.max(np.hypot(*points.T))) > limit_mm and _polar_value(args) == "deviation":
            # the placed radii are the option's: the implausible number is --nominal-radius, not the file's unit
            warn(nominal_radius_problem(nominal, limit_mm))
        else:
            half = float(np.max(np.ptp(points, axis=0))) / 2
            warn_implausible("profile radii (half the points' span)", half, limit_mm, unit, typical_mm=25.0)
            if limit_mm == ROUNDNESS_LIMIT_MM and 0 < half < ROUNDNESS_MIN_MM and not (
                    got is not None and got.kind == "polar" and nominal and _polar_value(args) == "deviation"):
                warn(small_part_problem(half, unit))
            if got is not None and got.kind == "polar" and nominal and _polar_value(args) == "deviation":
                from datasets.io import ASSUMED_DEVIATION_LIMIT_MM
                dev = float(np.max(np.abs(np.hypot(*points.T) - nominal)))
                if 0.05 * nominal < dev <= ASSUMED_DEVIATION_LIMIT_MM:
                    # deviations a roundness trace has, about a radius they are a good part of: the option is small
                    warn(nominal_radius_problem(nominal, limit_mm, deviation_mm=dev))
                else:
                    warn_implausible("radial deviations", dev, 0.05 * nominal, unit, typical_mm=0.01)
    return source, points, unit, notes, axes
