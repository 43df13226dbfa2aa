"""``fitbench positioning FILE``: the ISO 230-2 (or VDI 3441) positioning figures of one axis and the GLS
polynomial model with its uncertainty, the temperature correction to 20 °C, and the controller compensation tables
(:mod:`fitbench.compensation`); options with their units (:func:`instrument_length`, :func:`expansion_coefficient`,
:func:`material_temperature`)."""
from __future__ import annotations

import json
import warnings

import numpy as np

import fitbench.cli.options as cli_options
import methods
from fitbench.cli.guards import check_outputs, jsonable, say_written, written_files
from fitbench.cli.options import (add_reader_options, add_report_option, add_test_identity_options,
                                  add_tolerance_option, check_plot_path, finite, header_line, parse_tolerances, quantity,
                                  refuse_decimal_comma, save_figure, test_conditions, verdict, verdict_lines,
                                  verdict_title, warn, warn_bare_tolerances, write_report, write_text_atomic)
from methods import InvalidInputError
from methods.units import JSON_UNITS, UNIT_CHOICES, canonical


def add_parser(sub):
    pp = sub.add_parser("positioning", help="ISO 230-2 positioning figures and the GLS polynomial model")
    pp.add_argument("file", metavar="FILE",
                    help="long table (target, direction, run, actual or deviation) or a wide laser export "
                         "(target, then one column per run: run1 / run1+ run1- / ...)")
    pp.add_argument("--degree", type=int, default=3, help="degree of the polynomial (default 3)")
    g = pp.add_mutually_exclusive_group()
    g.add_argument("--instrument-u", metavar="U", help="standard uncertainty of the instrument: a length with its unit "
                   "(0.5um, 0.0005mm); a bare number is mm (unlike --tolerance, in µm)")
    g.add_argument("--mpe", metavar="MPE", help="the instrument's maximum permissible error (rectangular, u = MPE/√3): a "
                   "length with its unit (2um, 0.002mm); a bare number is mm (unlike --tolerance, in µm)")
    pp.add_argument("--standard", choices=("iso230-2:2014", "iso230-2:1988", "vdi3441"), default="iso230-2:2014")
    add_tolerance_option(pp, "A, E, R, B, M, the directional A_up, A_down, E_up, E_down, R_up, R_down, and B_mean, "
                             "judged by its magnitude |B_mean|")
    add_report_option(pp)
    add_test_identity_options(pp)
    pp.add_argument("--material-temperature", metavar="DEG_C",
                    help="temperature of the axis scale / workpiece during the test: °C as a bare number (10 to 40), "
                         "or with its unit (26C, 79F, 299.15K); the deviations are corrected to 20 °C by the nominal "
                         "differential expansion (needs --expansion-coefficient)")
    pp.add_argument("--expansion-coefficient", metavar="UM_PER_M_K",
                    help="its thermal expansion coefficient: µm/(m·K) as a bare number (steel about 11.5), or with "
                         "its unit (11.5e-6/K, 11.5ppm/K)")
    pp.add_argument("--forward-direction", choices=("+", "-"), default=None,
                    help="wide exports with Forward/Reverse (Hin/Rück) runs: the axis direction the forward runs "
                         "moved in (default: from the order of the targets in the file, + when increasing)")
    pp.add_argument("--run-directions", choices=("up", "down", "up,down", "down,up"), default=None,
                    metavar="{up|down|up,down|down,up}",
                    help="wide exports whose run columns name no direction (Run 1, Run 2, ...): up or down (every run "
                         "approached in the + or - direction), up,down or down,up (alternating: odd runs in the first, "
                         "even runs in the second, a bidirectional test exported without labels); default: one "
                         "direction, not given, refused when the odd and even runs differ as two directions do")
    pp.add_argument("--deviation-unit", choices=UNIT_CHOICES,
                    help="unit of the deviation columns when it differs from --unit (laser exports: targets in mm, "
                         "errors in µm)")
    add_reader_options(pp, columns=False)
    pp.add_argument("--column", action="append", metavar="ROLE=COLUMN",
                    help="the column to read for ROLE (target, direction, run, actual, deviation): a header name or a "
                         "0-based number; needed when two columns are named for one role (Error and Deviation: "
                         "which holds the positioning deviations?), repeatable")
    pp.add_argument("--compensation", nargs=2, action="append", metavar=("FORMAT", "FILE"),
                    help="write a compensation table: FORMAT csv, siemens-eec or fanuc-pitch (repeatable)")
    pp.add_argument("--fanuc-increment", default=None, metavar="UNIT",
                    help="fanuc-pitch: the machine's detection unit and least input increment: 0.001mm (IS-B, default) "
                         "or 0.0001mm (IS-C) for a metric machine, 0.0001in (IS-B) or 0.00001in (IS-C) for an inch "
                         "machine (its tape in counts of inches); a bare number is mm; required for an inch test")
    pp.add_argument("--fanuc-first-point", type=int, default=None, metavar="N",
                    help="fanuc-pitch: the axis' first pitch-error point number (parameter 3621, default 0); the points "
                         "are one block for all axes, so each axis' tape needs its own range (the output says which it "
                         "fills)")
    pp.add_argument("--interval", type=quantity("--interval"), default=None, metavar="MM",
                    help="compensation point spacing (a bare number in mm, or with its unit: 10mm, 0.5in; default: "
                         "the target spacing)")
    pp.add_argument("--compensation-from", choices=("model", "mean"), default=None,
                    help="compensation values from the GLS polynomial (default; refused when its lack-of-fit test "
                         "rejects it unless given explicitly) or the mean deviations at the targets")
    pp.add_argument("--compensation-directions", choices=("mean", "both"), default=None,
                    help="mean (default): one table of the mean bidirectional deviation and a backlash value; both: a "
                         "table per direction as well (csv columns compensation_up_mm / compensation_down_mm, a FANUC "
                         "bidirectional pitch-error tape; not siemens-eec), for a reversal that varies along the travel")
    pp.add_argument("--fanuc-reference-return", choices=("up", "down"), default=None,
                    help="fanuc-pitch with --compensation-directions both: the direction in which the axis returns to "
                         "its reference position (default up, the positive direction); that direction's table holds 0 "
                         "there and 3627 the other's value")
    pp.add_argument("--axis", default=None, help="the axis tested: recorded in the JSON result (fitbench history trends "
                    "each machine's axes apart) and its name in the controller's table (required for siemens-eec; "
                    "csv and fanuc-pitch take it from an 'Axis;Z' line above the table, else say 'not given')")
    pp.add_argument("--reference", type=quantity("--reference"), metavar="MM", help="the machine's reference point, "
                    "where the table holds 0 (a bare number in mm, or with its unit: 250mm, 0.25m; default 0 if the "
                    "travel contains it, else the nearer end)")
    pp.add_argument("--json", action="store_true", help="print one JSON object (mm; see its 'units')")
    pp.add_argument("--plot", metavar="FILE", help="write the plot (.png, .pdf, .svg)")
    pp.set_defaults(func=run)


def model_unavailable(data, degree: int, instrument: float | None) -> tuple[str, str | None] | None:
    """(why, the option that would give it or None) when the GLS polynomial model (paper eq. 2, 8-10) cannot be
    fitted to a test of repeated runs, else None: fewer targets than coefficients, or a target whose runs all read
    the same (the laser zeroed there at each run's start, or a rounded export) while no instrument uncertainty is
    given, or two such targets (U(x) = D + u²(δ) 1 1ᵀ is singular then whatever u(δ)). The ISO 230-2 figures need
    no model and are given all the same."""
    m = len(data.targets)
    if degree + 1 > m:
        return (f"a degree-{degree} polynomial needs at least {degree + 1} targets and this test has {m}",
                f"--degree {m - 1} (or lower)")
    arrows = {"up": " (↑)" if data.direction_given else "", "down": " (↓)"}
    for d in data.directions:
        zero = np.flatnonzero(np.ptp(getattr(data, d), axis=1) == 0)
        if zero.size and (not instrument or zero.size > 1):
            at = " and ".join(f"{data.targets[k] + 0.0:g} mm" for k in zero[:2]) + (", ..." if zero.size > 2 else "")
            why = (f"every run reads the same at target{'s' * (zero.size > 1)} {at}{arrows[d]} (zero scatter: the laser "
                   "zeroed there at each run's start, or rounded values?), and the model is weighted by the scatter "
                   "at the targets")
            if zero.size > 1:
                return why + " (with more than one such target no instrument uncertainty makes its covariance regular)", None
            return why, "the instrument's uncertainty (--mpe or --instrument-u)"
    return None


#: --tolerance figures that carry a sign (B_mean, the mean reversal value): judged by their magnitude, which the
#: verdict line and the JSON check (``judged``) name |B_mean|
SIGNED_FIGURES = ("B_mean",)

#: --fanuc-increment: the FANUC systems' detection unit / least input increment (metric IS-B / IS-C, inch IS-B / IS-C)
FANUC_INCREMENTS = {("0.001", "mm"): 0.001, ("0.0001", "mm"): 0.0001, ("0.0001", "in"): 0.00254,
                    ("0.00001", "in"): 0.000254}


def fanuc_increment(text, required: bool, paths) -> tuple[float, str, str]:
    """(mm, machine unit 'mm' or 'in', label) of ``--fanuc-increment``: 0.001mm / 0.0001mm (metric IS-B / IS-C, a
    bare number is mm) or 0.0001in / 0.00001in (inch IS-B / IS-C). An inch test writing a FANUC tape must say which
    the machine is (``required``): the tape's values, 3624 and 1851 are counts of the machine's own unit, which the
    file's unit does not tell."""
    import re
    if text is None:
        if required:
            raise InvalidInputError(f"not writing {', '.join(str(p) for p in paths)}: the test is in inches and a FANUC "
                                    "tape's values, interval (3624) and backlash (1851) are counts of the machine's own "
                                    "unit: give --fanuc-increment 0.0001in for an inch machine (IS-B; 0.00001in IS-C) or "
                                    "--fanuc-increment 0.001mm for a metric one (IS-B; 0.0001mm IS-C)")
        text = "0.001"
    m = re.fullmatch(r"\s*(0?\.0*1)\s*(mm|in)?\s*", str(text))
    key = (m.group(1).lstrip("0") and "0" + m.group(1).lstrip("0") if m else None, (m.group(2) or "mm") if m else None)
    if key not in FANUC_INCREMENTS:
        raise InvalidInputError(f"--fanuc-increment {text!r}: give 0.001mm or 0.0001mm (a metric machine, IS-B or "
                                "IS-C; a bare number is mm) or 0.0001in or 0.00001in (an inch machine)")
    return FANUC_INCREMENTS[key], key[1], f"{key[0]} {key[1]}"


def column_choices(items) -> dict[str, str] | None:
    """{role: column} of the ``--column ROLE=COLUMN`` options (roles checked by the reader); a role given twice or
    an item without '=' is refused in one line."""
    if not items:
        return None
    out = {}
    for item in items:
        role, eq, col = str(item).partition("=")
        role = role.strip().lower()
        if not eq or not role or not col.strip():
            raise InvalidInputError(f"--column {item!r}: give ROLE=COLUMN, e.g. --column \"deviation=Deviation (µm)\" "
                                    "or --column deviation=4 (0-based)")
        if role in out:
            raise InvalidInputError(f"--column {role} is given twice ({out[role]!r}, {col.strip()!r}): give it once")
        out[role] = col.strip()
    return out


def instrument_length(option: str, text) -> tuple[float | None, bool]:
    """(mm, unit given?) of ``--mpe`` / ``--instrument-u``: a length with its unit (``2um``, ``2 µm``, ``0.5nm``,
    ``0.002mm``) or a bare number in mm (as before units were accepted); a one-line error otherwise."""
    import re
    from methods.units import mm_per
    if text is None:
        return None, False
    refuse_decimal_comma(f"{option} {text!r}", text, f"{option} {{}}")
    m = re.fullmatch(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\d\s.+-][^\s]*)?\s*", str(text))
    if not m:
        raise InvalidInputError(f"{option} {text!r}: give a length with its unit, e.g. {option} 2um (or a bare number in mm)")
    unit = m.group(2)
    if unit is not None:
        try:
            factor = mm_per(unit)
        except InvalidInputError:
            raise InvalidInputError(f"{option} {text!r}: unknown unit {unit!r}; use um (µm), nm or mm, e.g. {option} 2um") from None
    value = finite(option, m.group(1)) * (factor if unit is not None else 1.0)
    if value < 0:
        raise InvalidInputError(f"{option} {text!r} must not be negative")
    return value, unit is not None


def _check_instrument(option: str, text, value_mm: float | None, explicit: bool, data) -> None:
    """Warn when a bare-number (mm) ``--mpe`` / ``--instrument-u`` exceeds every deviation of the axis: the
    option is in mm while ``--tolerance`` and the printout are in µm, and 2 (meant as µm) gave U = 2309 µm."""
    if value_mm is None or explicit or value_mm == 0:
        return
    devs = np.concatenate([np.ravel(a) for a in (data.up, data.down) if a is not None])
    devs = devs[np.isfinite(devs)]
    largest = float(np.max(np.abs(devs))) if len(devs) else 0.0
    if value_mm <= largest:
        return
    from methods.units import likely_unit
    guess = likely_unit(value_mm, max(largest, 1e-6))
    hint = (f"is it in {guess}? give {option} {text}{guess.replace('µ', 'u')}" if guess else
            f"give its unit, e.g. {option} {text}um")
    warn(f"{option} {text} is read as {value_mm:g} mm (a bare number is mm), larger than every deviation of this axis "
         f"(largest |deviation| {largest * 1e3:.3g} µm): {hint} (or {option} {text}mm to keep mm)")


_NUMBER_UNIT = r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S*?)\s*"
#: --expansion-coefficient units -> factor to µm/(m·K) (bare: µm/(m·K), as handbooks tabulate it x 1e-6 /K)
EXPANSION_UNITS = {"": 1.0, "um/(m*k)": 1.0, "um/(m.k)": 1.0, "um/m/k": 1.0, "ppm/k": 1.0, "/k": 1e6, "1/k": 1e6,
                   "k^-1": 1e6, "k-1": 1e6}
#: no material of a machine axis or workpiece expands less than this (Zerodur scales: about 0.01-0.1 µm/(m·K)) or
#: more than EXPANSION_WARN (aluminium 23, magnesium 26 µm/(m·K))
EXPANSION_MIN, EXPANSION_WARN = 1e-3, 30.0
#: a bare --material-temperature outside this range (°C) asks for its unit: ISO 230-2 tests run near 20 °C
WORKSHOP_C = (10.0, 40.0)


def expansion_coefficient(text) -> float | None:
    """``--expansion-coefficient`` in µm/(m·K): a bare number (11.5 for steel), or with its unit (11.5e-6/K,
    11.5ppm/K, 11.5um/(m*K)); a bare value no material has (11.5e-6: 1/K read as µm/(m·K), which silently applied
    no correction) is refused naming the likely unit, one above EXPANSION_WARN warned about."""
    import re
    if text is None:
        return None
    m = re.fullmatch(_NUMBER_UNIT, str(text))
    unit = (m.group(2) if m else "").lower().replace("µ", "u").replace("μ", "u").replace("·", "*").replace(" ", "")
    if not m or unit not in EXPANSION_UNITS:
        raise InvalidInputError(f"--expansion-coefficient {text!r}: give µm/(m·K) as a bare number (11.5 for steel) "
                                "or the value with its unit (11.5e-6/K, 11.5ppm/K)")
    value = finite("--expansion-coefficient", m.group(1)) * EXPANSION_UNITS[unit]
    if unit == "" and 0 < abs(value) < EXPANSION_MIN:
        raise InvalidInputError(f"--expansion-coefficient {text} is read as {value:g} µm/(m·K), less than any material "
                                f"expands (Zerodur about 0.01 µm/(m·K)); {text} looks like 1/K: give {value * 1e6:g} "
                                f"(µm/(m·K)) or {text}/K")
    if abs(value) > EXPANSION_WARN:
        warn(f"--expansion-coefficient {value:g} µm/(m·K) is more than the metals of machine axes expand (steel 11.5, "
             f"aluminium 23); check its unit (a bare number is µm/(m·K))")
    return value


def material_temperature(text) -> tuple[float | None, str]:
    """(°C, how it was given) of ``--material-temperature``: a bare number in °C within WORKSHOP_C, or with its
    unit (26C, 79F, 299.15K); a bare number outside the workshop range is refused naming °F when that fits
    (79 read as °C gave A = 661 µm)."""
    import re
    if text is None:
        return None, ""
    m = re.fullmatch(_NUMBER_UNIT, str(text))
    unit = (m.group(2) if m else "").upper().replace("°", "").replace("DEG", "")
    if not m or unit not in ("", "C", "F", "K"):
        raise InvalidInputError(f"--material-temperature {text!r}: give °C as a bare number (26) or the value with "
                                "its unit (26C, 79F, 299.15K)")
    v = finite("--material-temperature", m.group(1))
    c = {"": v, "C": v, "F": (v - 32.0) * 5.0 / 9.0, "K": v - 273.15}[unit]
    if unit == "" and not WORKSHOP_C[0] <= c <= WORKSHOP_C[1]:
        f_as_c = (v - 32.0) * 5.0 / 9.0
        guess = (f"is it °F ({f_as_c:.1f} °C)? give {text}F, or " if WORKSHOP_C[0] <= f_as_c <= WORKSHOP_C[1]
                 else "give ")
        raise InvalidInputError(f"--material-temperature {text} °C is outside a workshop's {WORKSHOP_C[0]:g} to "
                                f"{WORKSHOP_C[1]:g} °C; {guess}{text}C to confirm °C")
    if not -50.0 <= c <= 100.0:
        raise InvalidInputError(f"--material-temperature {text} ({c:g} °C) is not a workshop temperature")
    return c, ("" if unit in ("", "C") else f" ({text.strip()})")


def run(args) -> int:
    from datasets.io import read_positioning
    from fitbench.plots.positioning import plot, text

    plot_path = check_plot_path(args.plot)
    report_path = check_plot_path(args.report, "--report")
    check_outputs([args.file], [("--plot", args.plot, "plot"), ("--report", args.report, "test report"),
                                *((f"--compensation {fmt}", path, f"compensation table ({fmt})")
                                  for fmt, path in args.compensation or [])])
    instrument_u, u_explicit = instrument_length("--instrument-u", args.instrument_u)
    mpe, mpe_explicit = instrument_length("--mpe", args.mpe)
    if args.degree < 0:
        raise InvalidInputError(f"--degree must be >= 0, got {args.degree}")
    temperature, given_as = material_temperature(args.material_temperature)
    alpha = expansion_coefficient(args.expansion_coefficient)
    if (temperature is None) != (alpha is None):
        raise InvalidInputError("the temperature correction needs both --material-temperature (°C) and "
                                "--expansion-coefficient (µm/(m·K), e.g. 11.5 for steel)")
    fanuc_only = [o for o, v in (("--fanuc-first-point", args.fanuc_first_point),
                                 ("--fanuc-increment", args.fanuc_increment)) if v is not None]
    if args.compensation_directions is not None and not args.compensation:
        raise InvalidInputError("--compensation-directions applies to a compensation table and no --compensation is "
                                "given: add --compensation FORMAT FILE or drop the option")
    if args.fanuc_reference_return is not None and args.compensation_directions != "both":
        raise InvalidInputError("--fanuc-reference-return applies to a FANUC tape per direction: add "
                                "--compensation-directions both (and --compensation fanuc-pitch FILE) or drop the option")
    if args.fanuc_reference_return is not None:
        fanuc_only.append("--fanuc-reference-return")
    if fanuc_only and not any(fmt == "fanuc-pitch" for fmt, _ in args.compensation or []):
        raise InvalidInputError(f"{' and '.join(fanuc_only)} {'apply' if len(fanuc_only) > 1 else 'applies'} to a "
                                "FANUC tape and no --compensation fanuc-pitch is given: add --compensation fanuc-pitch "
                                f"FILE or drop {'them' if len(fanuc_only) > 1 else 'the option'}")
    given_deviation_unit = args.deviation_unit
    with warnings.catch_warnings(record=True) as read_warnings:
        warnings.simplefilter("always")
        data, args.unit, args.deviation_unit = read_positioning(args.file, unit=args.unit,
                                                                deviation_unit=args.deviation_unit,
                                                                skip_rows=args.skip_rows, with_units=True,
                                                                run_directions=args.run_directions,
                                                                columns=column_choices(args.column))
    from methods.units import UnitWarning
    unit_warnings = [str(w.message) for w in read_warnings if issubclass(w.category, UnitWarning)]
    if args.compensation and unit_warnings and given_deviation_unit is None:
        # a controller file from values the reader itself finds implausible: nothing is written (one line)
        from fitbench.compensation import CompensationError
        raise CompensationError(f"not writing {', '.join(p for _, p in args.compensation)}: {unit_warnings[0]}; a "
                                "controller table from them would be wrong by the same factor: give the deviations' "
                                "unit with --deviation-unit (or --deviation-unit mm to confirm mm)")
    if args.compensation and args.deviation_unit is None:
        # a controller applies the table as it is: no plausibility bound tells µm from mm on a good axis (±0.8 µm
        # read as mm passes any limit a 1 m axis allows), so the deviations' unit must be stated
        from fitbench.compensation import CompensationError
        raise CompensationError(f"not writing {', '.join(p for _, p in args.compensation)}: the deviations' unit is "
                                f"not stated in {args.file} (no unit in the header of its deviation columns); a "
                                "controller table needs it: give --deviation-unit um (or --deviation-unit mm)")
    from datasets.io.positioning import ColumnNote
    from methods.positioning.data import RunOrderNote, swap_directions
    run_order = [w.message for w in read_warnings if issubclass(w.category, RunOrderNote)]
    for w in read_warnings:
        if not issubclass(w.category, (RunOrderNote, ColumnNote)):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    notes = [str(w.message) for w in read_warnings if issubclass(w.category, ColumnNote)]
    if args.deviation_unit is None:
        notes.append(f"the deviation columns name no unit: read as {canonical(args.unit)} (give --deviation-unit um if "
                     "they are in µm); no compensation table is written without a stated unit")
        args.deviation_unit = args.unit
    if args.forward_direction is not None and not run_order:
        raise InvalidInputError(f"--forward-direction applies to a wide export whose runs are named Forward/Reverse "
                                f"(or Hin/Rück); {args.file} names its directions (or has none): drop the option")
    if run_order:
        found = run_order[0].forward
        if args.forward_direction is None and found is None:
            raise InvalidInputError(str(run_order[0]))
        if args.forward_direction is not None:
            if args.forward_direction != (found or "+"):
                data = swap_directions(data)
            word = "+ (↑)" if args.forward_direction == "+" else "− (↓)"
            notes.append(f"the Forward/Reverse runs are run order, not direction: forward runs read as approaches in the "
                         f"{word} direction, as --forward-direction {args.forward_direction} says")
        else:
            notes.append(str(run_order[0]))
    if not data.direction_given:
        notes.append("the columns name no approach direction (no direction column, or run columns without + or -): "
                     "evaluated as one direction, not given (shown as ?; "
                     "in the JSON under the keys *_up); give --run-directions up or down to name it, up,down or down,up "
                     "if the runs alternate")
    elif args.run_directions is not None:
        notes.append({"up": "every run read as approached in the + direction (↑), as --run-directions up says",
                      "down": "every run read as approached in the − direction (↓), as --run-directions down says",
                      "up,down": "odd runs read as approaches in the + direction (↑), even runs in − (↓), as "
                                 "--run-directions up,down says",
                      "down,up": "odd runs read as approaches in the − direction (↓), even runs in + (↑), as "
                                 "--run-directions down,up says"}[args.run_directions])
    if given_deviation_unit is None and args.deviation_unit == args.unit:
        args.deviation_unit = None  # printed as one unit, as before
    _check_instrument("--instrument-u", args.instrument_u, instrument_u, u_explicit, data)
    _check_instrument("--mpe", args.mpe, mpe, mpe_explicit, data)
    POS_FIGURES = ("A", "E", "R", "B", "M", "A_up", "A_down", "E_up", "E_down", "R_up", "R_down", "B_mean")
    tolerances = parse_tolerances(args.tolerance, POS_FIGURES)
    thermal = None
    if temperature is not None:
        from methods.positioning.data import thermal_correction
        data = thermal_correction(data, temperature, alpha)
        (p0, c0), (p1, c1) = data.thermal["correction_at_ends_mm"]
        thermal = {"material_temperature_c": temperature, "expansion_coefficient_um_per_m_k": alpha,
                   "correction_um_per_m": -alpha * (temperature - 20.0),
                   "correction_at_ends": [{"target": p0, "correction": c0}, {"target": p1, "correction": c1}]}
        thermal_text = (f"temperature correction (ISO 230-2 nominal differential expansion): material at "
                        f"{temperature:.4g} °C{given_as}, expansion coefficient {alpha:g} µm/(m·K): deviations corrected by "
                        f"{-alpha * (temperature - 20.0):+.4g} µm/m x target position ({c0 * 1e3:+.3f} µm at {p0:g} mm, "
                        f"{c1 * 1e3:+.3f} µm at {p1:g} mm), to 20 °C")
    if data.runs == 1:
        # ISO 230-2's test of axes over 2000 mm: one approach per direction gives E, M, B, not s, R, A nor the model
        from methods.positioning.iso230_2 import SINGLE_RUN_WITHOUT
        res = methods.fit("positioning.iso230_2", data, standard=args.standard)
        notes.append(f"one run per direction (ISO 230-2's procedure for axes over 2000 mm): E, M and B are evaluated; "
                     f"{SINGLE_RUN_WITHOUT}, and so does the polynomial model's uncertainty (u(P_i), paper eq. 10): "
                     "not given")
        if args.compensation and args.compensation_from != "mean":
            from fitbench.compensation import CompensationError
            raise CompensationError(f"not writing {', '.join(p for _, p in args.compensation)}: the polynomial model "
                                    "needs repeated runs and this test has one run per direction: give "
                                    "--compensation-from mean (the measured deviations at the targets)")
    elif (lacking := model_unavailable(data, args.degree, instrument_u or mpe)) is not None:
        # the ISO 230-2 figures need no model: they are given, the model is said not to be (as a rejected one is)
        why, remedy = lacking
        res = methods.fit("positioning.iso230_2", data, standard=args.standard)
        notes.append(f"the polynomial model and its U(P) are not given: {why}" +
                     (f"; give {remedy} for the model" if remedy else ""))
        if args.compensation and args.compensation_from != "mean":
            from fitbench.compensation import CompensationError
            raise CompensationError(f"not writing {', '.join(p for _, p in args.compensation)}: the polynomial model "
                                    f"is not given ({why}): give --compensation-from mean (the measured deviations at "
                                    f"the targets){f', or {remedy}' if remedy else ''}")
    else:
        res = methods.fit("positioning.gls_polynomial", data, degree=args.degree, instrument_u=instrument_u, mpe=mpe)
    given = [p for p in (getattr(res, "polynomial", None) or {}).values() if not p["lack_of_fit"]["rejected"]]
    if given and not res.extra.get("u_delta"):   # a U(P) is printed, from the scatter of the means alone
        k = given[0]["k"]
        why = ("neither --mpe nor --instrument-u is given" if instrument_u is None and mpe is None else "given as 0")
        notes.append(f"U(P) includes the scatter of the means only (u(P_i) = s_i/√n, the positioning paper's eq. 10), "
                     f"not the instrument's error u(δ) ({why}: u(δ) = 0), which the "
                     "paper's model exists to include: it is not the uncertainty of the measured deviation; give the "
                     f"instrument's MPE (e.g. --mpe 2um) or standard uncertainty (--instrument-u) to add it: "
                     f"U(P)² + ({k:g} u(δ))²")
    from fitbench.compensation import model_misfit
    misfit = model_misfit(res)
    if misfit:
        notes.append(f"{misfit.replace(' um', ' µm')}: its U(P) is not the uncertainty of the deviation between the "
                     "targets and is not given; the mean deviations at the targets are the measurement")
    lacks = []
    if args.standard.startswith("iso230-2"):
        from methods.positioning.iso230_2 import conformity
        lacks = conformity(data)
        if lacks:
            notes.append(f"not an ISO 230-2 test: {'; '.join(lacks)}; the figures below are computed by its "
                         "formulas but are not the standard's (not for acceptance)")
    if args.standard != "iso230-2:2014" or len(data.directions) == 1:
        other = methods.fit("positioning.iso230_2", data, standard=args.standard)
        res.figures, res.per_target = other.figures, other.per_target
    comp = None
    table_axis = args.axis
    if args.compensation:
        from datasets.io.positioning import preamble_axis
        from fitbench.compensation import AXIS, write_tables
        found = preamble_axis(args.file, args.skip_rows)
        hint = (f" (line {found[1]} of {args.file} says {found[2]!r}: the SINUMERIK machine-axis name of that axis, "
                f"e.g. {found[0]}1 or {found[0]})" if found else "")
        if (table_axis is None and found and AXIS.fullmatch(found[0])
                and not any(fmt == "siemens-eec" for fmt, _ in args.compensation)):
            table_axis = found[0]
            notes.append(f"compensation table for axis {table_axis!r}, from line {found[1]} of {args.file} "
                         f"({found[2]!r}); --axis names another")
        inch_input = "in" in {canonical(u) for u in (args.unit, args.deviation_unit) if u}
        fanuc_mm, fanuc_unit, fanuc_label = fanuc_increment(args.fanuc_increment, inch_input and any(
            fmt == "fanuc-pitch" for fmt, _ in args.compensation), [p for _, p in args.compensation])
        comp = write_tables(res, data, args.compensation, interval=finite("--interval", args.interval, positive=True),
                            source=args.compensation_from or "model", axis=table_axis, axis_hint=hint,
                            write=write_text_atomic,
                            reference_mm=finite("--reference", args.reference),
                            unit_confirmed=given_deviation_unit is not None, on_confirmed=warn,
                            model_confirmed=args.compensation_from == "model",
                            fanuc_unit_mm=fanuc_mm, fanuc_machine_unit=fanuc_unit, fanuc_first_number=args.fanuc_first_point or 0,
                            per_direction=args.compensation_directions == "both",
                            fanuc_reference_return=args.fanuc_reference_return or "up")
        if comp.attrs.get("reference_note"):
            notes.append(comp.attrs["reference_note"])
        if comp.attrs.get("thermal_note"):      # a correction computed from two given numbers goes into the machine
            notes.append(f"the compensation tables hold the deviations corrected to 20 °C from {temperature:.4g} °C with "
                         f"{alpha:g} µm/(m·K) ({c0 * 1e3:+.3f} µm at {p0:g} mm, {c1 * 1e3:+.3f} µm at {p1:g} mm), "
                         f"given, not measured: for a machine that works at 20 °C or compensates temperature itself; one working at "
                         f"{temperature:.4g} °C with its scale at {temperature:.4g} °C needs them without "
                         "--material-temperature; every file's header says so")
        if comp.attrs.get("reversal_note") and comp.attrs.get("per_direction"):   # the tables per direction hold it
            notes.append(comp.attrs["reversal_note"].removeprefix("NOTE: ").replace(" um", " µm"))
        elif comp.attrs.get("reversal_note"):     # the reversal varies along the travel: the table cannot remove it
            warn(comp.attrs["reversal_note"].removeprefix("NOTE: ") + "; every file's header says so")
        if inch_input:   # read in inches: the csv / SINUMERIK tables are in mm, the FANUC tape in the machine's unit
            formats = {fmt for fmt, _ in args.compensation}
            how = ([f"the {' and '.join(f for f in ('csv', 'siemens-eec') if f in formats)} values are mm: divide them "
                    "by 25.4 for inches"] if formats & {"csv", "siemens-eec"} else [])
            if how:
                notes.append("the compensation tables are in mm, the input in inches: an inch machine (SINUMERIK basic "
                             f"system inch) needs them in its own unit: {'; '.join(how)}")
            if "fanuc-pitch" in formats:
                notes.append(f"the fanuc-pitch tape is for {'an inch' if fanuc_unit == 'in' else 'a metric'} machine, "
                             f"as --fanuc-increment {args.fanuc_increment} says: its values, 3624 and 1851 are counts of "
                             f"{fanuc_label}, rounded on the whole curve")
    missing = [n for n in tolerances if n not in res.figures]
    if missing:
        raise InvalidInputError(f"--tolerance {missing[0]}: this test has no figure {missing[0]} "
                                f"({res.figures.get('directions', 'bidirectional')}, {args.standard})")
    check = verdict({n: abs(res.figures[n]) for n in tolerances}, tolerances)
    for c in (check or {}).get("checks", ()):
        if c["figure"] in SIGNED_FIGURES:       # judged by its magnitude: said so, the figure table keeps the sign
            c["judged"] = f"|{c['figure']}|"
    shown = check and dict(check, checks=[dict(c, figure=c.get("judged", c["figure"])) for c in check["checks"]])
    warn_bare_tolerances(tolerances, {n: abs(res.figures[n]) for n in tolerances})
    said = cli_options.said_warnings()   # printed before the figures, written into the report and the JSON
    if plot_path:
        title = str(args.file) + (f"; corrected to 20 °C from {temperature:g} °C, {alpha:g} µm/(m·K)" if thermal else "")
        title += verdict_title(shown)
        plot(res, plot_path, title=title, data=data, save=save_figure)
    lines = [header_line("positioning", args.unit, deviation_unit=args.deviation_unit)]
    lines += [f"note: {n}" for n in notes]
    lines += ([thermal_text] if thermal else []) + [text(res, degree=args.degree)] + verdict_lines(shown)
    if report_path:
        write_report(report_path, f"ISO 230-2 positioning test{': ' + args.machine if args.machine else ''}",
                     [f"file         {args.file}", f"date         {args.date or '-'}", *lines],
                     lambda sub: plot(res, None, title=str(args.file), data=data, into=sub), aspect=5 / 13)
    if args.json:
        out = dict(res.figures)
        if thermal:
            out["temperature_correction"] = dict(thermal, correction_unit="µm/m of target position (to 20 °C)")
        if check:
            out["verdict"] = check
        out["units"] = dict(JSON_UNITS, input_unit=canonical(args.unit),
                            input_deviation_unit=canonical(args.deviation_unit or args.unit),
                            polynomial="coefficients of increasing powers of the position P in mm: mm / mm^k")
        out["per_target"] = {k: v for k, v in res.per_target.items()}
        # a model its lack-of-fit test rejects has no U(P): null, and lack_of_fit says why; no model at all (the
        # notes say why): null, not an empty object
        out["polynomial"] = {d: {"coefficients": p["coefficients"], "covariance": p["covariance"],
                                 "degree": p["degree"], "k": p["k"],
                                 "U_at_targets": None if p["lack_of_fit"]["rejected"] else p["U_at_targets"],
                                 "lack_of_fit": p["lack_of_fit"]}
                             for d, p in res.polynomial.items()} or None
        out["u_delta"] = res.extra.get("u_delta")
        out["notes"] = notes
        out["warnings"] = said
        if args.standard.startswith("iso230-2"):
            out["iso230_2_conformity"] = {"meets_minimum": not lacks, "lacks": lacks}
        # the axis as given (--axis; '' if not): fitbench history keeps each machine's axes apart
        out["details"] = {"conditions": test_conditions(args, axis=args.axis or "", files=[str(args.file)])}
        if comp is not None:   # the table written (what the text's "compensation table ... written to" lines say)
            out["compensation"] = {
                "tables": [{"format": fmt, "path": path, **({"fanuc_points": comp.attrs["fanuc_numbers"]}
                                                             if fmt == "fanuc-pitch" else {})}
                           for fmt, path in args.compensation],
                "source": comp.attrs["source"], "interval_mm": comp.attrs["interval_mm"], "points": len(comp),
                "first_mm": float(comp.position_mm.iloc[0]), "last_mm": float(comp.position_mm.iloc[-1]),
                "reference_mm": float(comp.position_mm.iloc[comp.attrs["reference_index"]]),
                "chosen": comp.attrs.get("chosen"), "warning": comp.attrs.get("warning"),
                **({"directions": "both"} if comp.attrs.get("per_direction") else {})}
        out["files_written"] = written_files()
        cli_options.print_json(json.dumps(jsonable(out)))
        return 0
    print("\n".join(lines))
    if comp is not None:
        for fmt, path in args.compensation:
            say_written(path, f"compensation table{'s per direction' if comp.attrs.get('per_direction') else ''} ({fmt}, every {comp.attrs['interval_mm']:g} mm from {comp.position_mm.iloc[0]:g} "
                  f"to {comp.position_mm.iloc[-1]:g} mm, from the {comp.attrs['source']}) written to {path}"
                  + (f": {comp.attrs['chosen']}" if comp.attrs.get("chosen") else "")
                  + (f"; {comp.attrs['fanuc_points']}" if fmt == "fanuc-pitch" else ""))
    return 0
