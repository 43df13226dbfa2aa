"""The subcommands of ``fitbench`` (also ``python -m fitbench`` and ``python -m methods``): ``list``,
``fit METHOD_ID FILE`` and the machine-test subcommands (circular-test, positioning, magnify,
multilaterate, roundness), one argparse tree built by :func:`build_parser`.

Bad input ends with one line on stderr and exit status 2, never a traceback; warnings (a likely unit
mix-up, a swapped pair of runs, a nominal centre far from the data) are lines ``fitbench: warning: ...``
on stderr. Units: every reader takes ``--unit`` (its file's length unit, default mm); options on the
command line are in mm (lengths), mm/min (feed) and degrees (angles); printed output is in µm, µrad and
°; JSON in mm and rad with a ``units`` field. Subcommands are one table (``SUBCOMMANDS``): adding one is
a function ``add_NAME(sub)`` that builds its parser and sets ``func``.
"""
from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
import warnings

import numpy as np

import fitbench.cli.options as cli_options
from fitbench.threads import one_thread_environment
import methods
from methods import InvalidInputError
from methods.units import JSON_UNITS, UNIT_CHOICES, canonical, warn_implausible
from fitbench.cli.options import (PROFILE_LIMIT_MM, add_reader_options, add_report_option, add_test_identity_options,
                                  add_tolerance_option, check_plot_path, finite, header_line,
                                  parse_tolerances, read_profile_args, save_figure, verdict,
                                  verdict_lines, verdict_title, version, warn, write_report, test_conditions,
                                  write_text_atomic)

EXIT_BAD_INPUT = 2
#: the subcommands of ``fitbench`` that run the experiment modules (fitbench.cli.DELEGATED), absent from
#: ``python -m methods``
EXPERIMENT_SUBCOMMANDS = ("run", "report", "verify")
#: a method raised an exception of its own (a bug in the method, not bad input): one line, this status
EXIT_METHOD_FAILED = 3
#: Ctrl-C (SIGINT): 128 + 2, what a shell reports for a process SIGINT ended
EXIT_INTERRUPTED = 130


PROG = "python -m methods"


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2 (argparse prints usage over several lines)
        raise InvalidInputError(f"{message} (see '{self.prog.split()[0] if self.prog.startswith('fitbench') else PROG} --help')")


def parse_value(key: str, text: str, default, method_id: str):
    """Coerce a ``--param KEY=VALUE`` string to the type of the parameter's default."""
    def bad(kind):
        return InvalidInputError(f"{method_id}: parameter {key}={text!r} is not {kind}")
    if isinstance(default, bool):
        low = text.strip().lower()
        if low in ("1", "true", "yes", "on"):
            return True
        if low in ("0", "false", "no", "off"):
            return False
        raise bad("a boolean (true/false)")
    if isinstance(default, int):
        try:
            return int(text)
        except ValueError:
            raise bad("an integer") from None
    if isinstance(default, float):
        try:
            return float(text)
        except ValueError:
            raise bad("a number") from None
    if isinstance(default, str):
        return text
    # default None or a sequence: a number, a list "0,0,299" or "[0,0,299]", or a word
    stripped = text.strip()
    if stripped.lower() in ("none", "null", ""):
        return None
    try:
        value = json.loads(stripped if stripped.startswith("[") else f"[{stripped}]")
    except json.JSONDecodeError:
        return stripped
    return value[0] if len(value) == 1 and not stripped.startswith("[") else value


class MethodFailed(Exception):
    """A method raised an exception other than :class:`~methods.InvalidInputError` (its own bug, e.g. a
    plugin writing into its read-only input): printed as one line, exit status :data:`EXIT_METHOD_FAILED`."""


def _flush_c_stdio() -> None:
    """Flush the C library's stdio buffers (what compiled code printed with printf is still in them)."""
    try:
        import ctypes
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):
        pass   # no C library to reach (Windows): Python's prints are redirected all the same


#: the variables BLAS and OpenMP libraries read their thread count from when they load (as the engine's workers)
@contextlib.contextmanager
def one_blas_thread():
    """One BLAS/OpenMP thread while a subcommand computes, unless the user chose a count
    (:func:`fitbench.threads.one_thread_environment`): libraries loaded already are limited through threadpoolctl;
    those loaded during the command (SciPy's OpenBLAS) read the variables, set to 1 in the block (docs/cli.md: the
    figures)."""
    with one_thread_environment() as chosen:
        if chosen:
            yield
        else:
            from threadpoolctl import threadpool_limits
            with threadpool_limits(limits=1):
                yield


@contextlib.contextmanager
def stdout_to_stderr():
    """Send what is printed to stdout to stderr inside the block: Python's prints (``sys.stdout``) and, when
    stdout is a real file descriptor, what compiled code writes to descriptor 1 (a Fortran or C solver's
    iteration log), whose C buffers are flushed before descriptor 1 is restored."""
    with contextlib.redirect_stdout(sys.stderr):
        try:
            out_fd, err_fd = sys.__stdout__.fileno(), sys.__stderr__.fileno()
        except (AttributeError, OSError, ValueError):
            out_fd = None
        if out_fd is None or out_fd == err_fd:
            yield
            return
        sys.__stdout__.flush()
        _flush_c_stdio()
        saved = os.dup(out_fd)
        try:
            os.dup2(err_fd, out_fd)
            yield
        finally:
            _flush_c_stdio()
            os.dup2(saved, out_fd)
            os.close(saved)


def run_method(spec, data, **params):
    """``spec(data, **params)`` with the method's prints sent to stderr (stdout carries the command's output
    alone: ``--json`` stays one JSON object) and its own exceptions turned into one line naming it
    (:class:`MethodFailed`); bad input (:class:`~methods.InvalidInputError`, the result gate's refusal) passes."""
    try:
        with stdout_to_stderr():
            return spec(data, **params)
    except InvalidInputError:
        raise
    except (Exception, SystemExit, GeneratorExit) as exc:   # a method's sys.exit() is no success (nor a silent end)
        text = " ".join(str(exc).split()) or "(no message)"
        hint = ("a bug in fitbench: please report it" if spec.builtin else
                f"an error inside the method (module {spec.module}), not in the data: report it to its author")
        if isinstance(exc, ValueError) and "read-only" in text:
            hint += "; a method gets read-only points and must copy them (points.copy()) before writing"
        what = (f"{type(exc).__name__}: {text[:300]}" if isinstance(exc, Exception) else
                f"it raised {type(exc).__name__}({', '.join(map(repr, exc.args))[:300]})")
        raise MethodFailed(f"{spec.id} failed: {what} ({hint})") from None


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return "nan" if not math.isfinite(v) else f"{v:.10g}"
    return str(v)


def cmd_list(args) -> int:
    from methods import describe_methods  # the built-in methods without importing their families

    specs = describe_methods(args.family)
    if args.json:
        cli_options.print_json(json.dumps([{"id": s.id, "family": s.family, "kind": s.kind, "summary": s.summary,
                           "reference": s.reference, "defaults": {k: _jsonable(v) for k, v in s.defaults.items()}}
                          for s in specs], indent=1))
        return 0
    width = max((len(s.id) for s in specs), default=10)
    for s in specs:
        print(f"{s.id:<{width}}  {s.kind:<14}  {s.reference}")
    return 0


def _jsonable(v):
    from methods.result_base import jsonable as j
    return j(v)


def _axis_label(label: str, axes: tuple) -> str:
    """A result's line label with the coordinates named as the file named them (``center x`` -> ``center z``
    for a file read from its x and z columns)."""
    head, _, last = label.rpartition(" ")
    if head and last in ("x", "y"):
        return f"{head} {axes[0] if last == 'x' else axes[1]}"
    return label


def cmd_fit(args) -> int:
    spec = methods.get(args.method)
    params = {}
    for item in args.param or []:
        key, eq, text = item.partition("=")
        key = key.strip()
        if not eq or not key:
            raise InvalidInputError(f"--param needs KEY=VALUE, got {item!r}")
        if key not in spec.defaults:
            raise InvalidInputError(f"{spec.id} has no parameter {key!r}; its parameters are: "
                                    f"{', '.join(spec.defaults) or 'none'}")
        params[key] = parse_value(key, text, spec.defaults[key], spec.id)
    plot_path = check_plot_path(args.plot)
    source, points, unit, notes, axes = read_profile_args(args)
    result = run_method(spec, points, **params)
    if plot_path:
        if spec.family not in ("circle", "ellipse"):
            raise InvalidInputError(f"--plot draws circle and ellipse fits; {spec.id} is a {spec.family} method")
        from fitbench.plots.fit import plot_fit
        plot_fit(points, result, spec.family, plot_path, title=f"{source} ({canonical(unit)} read, mm shown)",
                 save=save_figure)
    if args.json:
        d = result.to_dict(residuals=not args.no_residuals)
        d["source"] = source
        d["n_points"] = int(np.asarray(points).shape[0])
        d["units"] = {"length": "mm", "angle": "rad", "input_unit": canonical(unit)}
        if notes:
            d["notes"] = notes
        cli_options.print_json(json.dumps(d))
        return 0
    print(f"input unit {canonical(unit)}{' (converted to mm)' if canonical(unit) != 'mm' else ''}; "
          "lengths below in mm")
    for n in notes:
        print(f"note: {n}")
    rows = [("method", result.method), ("data", f"{source} ({len(points)} points)")]
    rows += [(_axis_label(k, axes), v) for k, v in result.report_lines()]
    rows += [("form error", f"{_fmt(result.form_error)} mm"),
             # the solver's own test (in its unit frame) is for --verbose and the JSON; the reason of a NO is the operator's
             ("converged", "yes" if result.converged else f"NO ({result.message})"),
             *([("solver", result.message)] if args.verbose and result.converged else []),
             ("iterations", _fmt(result.iterations)), ("evaluations", _fmt(result.nfev)),
             ("runtime", f"{result.runtime_s * 1e3:.3f} ms"),
             ("parameters", ", ".join(f"{k}={v!r}" for k, v in result.params.items()) or "-")]
    for k, v in rows:
        print(f"{k:<12} {v}")
    return 0 if result.converged else 1


# ----------------------------------------------------------------------------------------- circular test
def _read_circular_runs(args):
    """({'cw': points, 'ccw': points} as the user labelled them, the first file's CircularRuns, labelled?), from one
    file (direction/run column) or two."""
    from datasets.io import read_runs
    kw = dict(columns=tuple(args.columns) if args.columns else None, plane=args.plane, unit=args.unit,
              skip_rows=args.skip_rows, angle_unit=args.angle_unit, nominal_radius=args.nominal_radius,
              nominal_center=tuple(args.nominal_center) if args.nominal_center else (0.0, 0.0))
    if len(args.files) > 2:
        raise InvalidInputError(f"give one file holding both runs or two files (CW then CCW), got {len(args.files)}")
    files = [read_runs(f, **kw) for f in args.files]
    for f in files:   # two columns that are not the circle's plane: said before any radius or unit is blamed
        for _, pts in f.runs:
            if (flat := cli_options.flat_points(pts, f.axes)) is not None:
                raise InvalidInputError(f"{f.source}: {flat}")
    if len(files) == 2:
        for f in files:
            if len(f.runs) != 1:
                raise InvalidInputError(f"{f.source}: holds {len(f.runs)} runs; with two files give one run per file")
        if files[0].unit != files[1].unit:
            raise InvalidInputError(f"{files[0].source} is in {files[0].unit} but {files[1].source} in {files[1].unit}; "
                                    "give both runs in one unit")
        return {"cw": files[0].runs[0][1], "ccw": files[1].runs[0][1]}, files[0], True
    runs = files[0].runs
    if len(runs) != 2:
        raise InvalidInputError(f"{files[0].source}: one run only; give the CCW run as a second file or a file with a "
                                "direction (cw/ccw) or run column holding both")
    tags = [t for t, _ in runs]
    if set(tags) == {"cw", "ccw"}:
        return {t: pts for t, pts in runs}, files[0], True
    return {"cw": runs[0][1], "ccw": runs[1][1]}, files[0], False  # labels from the point order


#: radial deviations of a circular test beyond this are a unit mistake (a ballbar measures within +-1 mm)
CIRCULAR_DEVIATION_LIMIT_MM = 1.0


def _check_polar_deviations(runs, R, nominal_center, unit, assumed: bool = False) -> None:
    """An angle + radial-deviation file whose deviations exceed ``CIRCULAR_DEVIATION_LIMIT_MM``: a warning naming the
    likely unit of the deviation column (µm read as mm: 3.1 became 3.1 mm), or that line as the error when the data
    would be refused as far from the nominal radius anyway; no warning of its own when the unit was ``assumed``
    (the reader warned already, :data:`datasets.io.ASSUMED_DEVIATION_LIMIT_MM`)."""
    from methods.circular_test.evaluation import RADIUS_TOLERANCE
    from methods.units import likely_unit
    c = np.asarray(nominal_center if nominal_center is not None else (0.0, 0.0), float)
    dev = max(float(np.max(np.abs(np.hypot(*(np.asarray(p) - c).T) - R))) for p in runs.values())
    if not dev > CIRCULAR_DEVIATION_LIMIT_MM:
        return
    guess = likely_unit(dev, 0.01)
    hint = f"; is the deviation column in {guess}? (--unit {guess.replace('µ', 'u')})" if guess else "; check --unit"
    msg = (f"radial deviations up to {dev:.4g} mm (read as {canonical(unit)}) are implausible for a circular test (a "
           f"ballbar measures within ±{CIRCULAR_DEVIATION_LIMIT_MM:g} mm){hint}")
    if dev > RADIUS_TOLERANCE * R:
        raise InvalidInputError(msg)
    if not assumed:
        warn(msg)


#: a circular test's feed below this (mm/min) is a unit mistake (m/min read as mm/min): ballbar tests run at
#: hundreds to thousands of mm/min
FEED_MIN_MM_MIN = 10.0


def cmd_circular_test(args) -> int:
    from methods.circular_test import diagnose, evaluate
    from fitbench.plots.circular_test import FIGSIZE as POLAR_FIGSIZE, diagnostics_json, model_json, polar_plot, text
    from methods.circular_test.runs import check_nominal, check_pair, drop_repeated, trim

    R = finite("--nominal-radius", args.nominal_radius, positive=True, allow_none=False)
    if args.nominal_center is not None:
        args.nominal_center = [finite("--nominal-center", v) for v in args.nominal_center]
    feed = finite("--feed", args.feed, positive=True)
    if feed is not None and feed < FEED_MIN_MM_MIN:
        hours = 2 * math.pi * R / feed / 60.0
        warn(f"--feed {feed:g} mm/min: one revolution of the R {R:g} mm circle would take {hours:.3g} h; the feed is "
             f"in mm/min (is it m/min? --feed {feed * 1000:g})")
    pitch = finite("--cyclic-pitch", args.cyclic_pitch, positive=True)
    arc = finite("--arc", args.arc, positive=True)
    plot_path = check_plot_path(args.plot)
    report_path = check_plot_path(args.report, "--report")
    tolerances = parse_tolerances(args.tolerance, ("G", "G_cw", "G_ccw", "G_b", "H"))
    runs, first, labelled = _read_circular_runs(args)
    args.unit = first.unit
    if first.kind == "polar":
        _check_polar_deviations(runs, R, args.nominal_center, args.unit, first.unit_assumed)
    polar_centre = first.kind == "polar" and args.nominal_center is None
    if polar_centre:  # angle + radial deviation: the reader placed the points about the nominal centre (0, 0) itself
        args.nominal_center = [0.0, 0.0]
    for name, pts in runs.items():
        if len(pts) < 10:
            raise InvalidInputError(f"circular test ({name.upper()} run): needs at least 10 points, got {len(pts)}")
    center0 = tuple(args.nominal_center) if args.nominal_center else \
        tuple(methods.fit("circle.gauss_newton", np.vstack(list(runs.values()))).center)
    trimmed = {}
    notes = ["angle + radial deviation: points placed about the nominal centre (0, 0), which the diagnostics use"] \
        if polar_centre else []
    for name in ("cw", "ccw"):
        label = name.upper() if labelled else ('first', 'second')[name == 'ccw']   # runs told apart by order
        runs[name], repeats, said = drop_repeated(runs[name], center0, label)  # a dwell is no contour point
        if said:
            warn(said)
            notes.append(said)
        runs[name], rep = trim(runs[name], center0, arc_deg=arc, lead_in_deg=args.lead_in, lead_out_deg=args.lead_out)
        trimmed[name] = dict(rep, **repeats)
        if len(runs[name]) < 10:
            raise InvalidInputError(f"circular test ({name.upper()} run): {len(runs[name])} point(s) left after removing "
                                    f"the lead-in/out and the overrun beyond {arc:g}°; at least 10 are needed")
        if rep["overrun_trimmed_points"] or rep["lead_removed_points"]:
            notes.append(f"{name.upper()} run: recorded {rep['recorded_arc_deg']:.1f}°, "
                         f"{rep['lead_removed_points']} lead-in/out point(s) removed, "
                         f"{rep['overrun_trimmed_points']} point(s) of overrun beyond {arc:g}° trimmed; "
                         f"{rep['evaluated_arc_deg']:.1f}° evaluated")
    if labelled:
        runs, pair_warnings = check_pair(runs, center0, as_given=args.as_given)
    else:
        from methods.circular_test.runs import direction
        first = "cw" if direction(runs["cw"], center0)[0] == "cw" else "ccw"
        runs = {"cw": runs["cw"], "ccw": runs["ccw"]} if first == "cw" else {"cw": runs["ccw"], "ccw": runs["cw"]}
        runs, pair_warnings = check_pair(runs, center0, as_given=False)
        notes.append("directions read from the point order of each run")
    for w in pair_warnings:
        warn(w)
    center = tuple(args.nominal_center) if args.nominal_center else None
    conditions = {"nominal_radius_mm": R, "nominal_center_mm": center, "feed_mm_min": feed, "plane": args.plane or "xy",
                  "machine": args.machine, "date": args.date, "files": [str(f) for f in args.files],
                  "centre_for_G": args.center, "input_unit": canonical(args.unit), "nominal_arc_deg": arc,
                  "trimming": trimmed}
    ev = evaluate(runs["cw"], runs["ccw"], R, center, center=args.center, conditions=conditions)
    both = methods.fit("circle.gauss_newton", np.vstack([runs["cw"], runs["ccw"]]))
    for w in check_nominal(both.center, both.radius, center, R):
        warn(w)
    dg = None
    if center is not None:
        dg = diagnose(runs["cw"], runs["ccw"], R, center, feed_mm_min=feed, cyclic_pitch=pitch, partial=ev.partial_arc)
        if not dg["_model"]["converged"]:
            warn(f"diagnostics: {dg['_model']['message']}; the estimates are its last iterate's")
    values = dict(ev.figures, G=max(ev.figures["G_cw"], ev.figures["G_ccw"]))
    check = verdict({n: values[n] for n in tolerances}, tolerances)
    if plot_path:
        polar_plot(runs["cw"], runs["ccw"], ev, plot_path, title=verdict_title(check).lstrip("; "), diagnostics=dg,
                   conditions=conditions, save=save_figure)
    lines = [header_line("circular-test", args.unit, "; options in mm, mm/min and degrees")]
    lines += [f"note: {n}" for n in notes] + [text(ev, dg)]
    if dg is None:
        lines.append("diagnostics: not estimated (give --nominal-center X Y)")
    lines += verdict_lines(check)
    if report_path:
        write_report(report_path, f"ISO 230-4 circular test{': ' + args.machine if args.machine else ''}",
                     [f"files        {', '.join(str(f) for f in args.files)}", f"date         {args.date or '-'}",
                      *lines], lambda sub: polar_plot(runs["cw"], runs["ccw"], ev, None, diagnostics=dg,
                                                      title=verdict_title(check).lstrip("; "),
                                                      conditions=conditions, into=sub), aspect=POLAR_FIGSIZE[1] / POLAR_FIGSIZE[0])
    if args.json:
        d = ev.to_dict(residuals=False)
        out = {k: d.pop(k) for k in (*ev.FIGURES, "center")}
        out["units"] = dict(JSON_UNITS, input_unit=canonical(args.unit))
        out["diagnostics"] = (diagnostics_json(dg, conditions["plane"]) if dg else
                              "not estimated: give --nominal-center X Y")
        from dataclasses import fields
        from methods import FitResult
        shared = {f.name for f in fields(FitResult)}  # the evaluation's own fields only
        out["details"] = {k: v for k, v in d.items() if k not in shared}
        out["notes"] = notes
        if check:
            out["verdict"] = check
        if dg:
            out["details"]["diagnostics_model"] = model_json(dg["_model"], conditions["plane"])
        cli_options.print_json(json.dumps(_jsonable(out)))
        return 0
    print("\n".join(lines))
    return 0


def add_circular_test(sub):
    pc = sub.add_parser("circular-test", help="ISO 230-4 evaluation and diagnostics of a CW and a CCW run")
    pc.add_argument("files", nargs="+", metavar="FILE",
                    help="CW.csv CCW.csv, or one file with both runs (a direction or run column); x, y columns or "
                         "angle + radial deviation")
    pc.add_argument("--nominal-radius", type=float, required=True, metavar="R_MM", help="nominal radius (mm)")
    pc.add_argument("--nominal-center", type=float, nargs=2, metavar=("X", "Y"),
                    help="nominal centre in machine coordinates (mm); needed for F about it and for the diagnostics")
    pc.add_argument("--center", choices=("lsq", "mz"), default="lsq", help="centre for G: least squares or minimum zone")
    pc.add_argument("--feed", type=float, metavar="MM_PER_MIN", help="feed (mm/min): gives the servo mismatch in ms")
    pc.add_argument("--cyclic-pitch", type=float, metavar="MM", help="ball-screw pitch (mm): estimates the cyclic error")
    pc.add_argument("--arc", type=float, default=360.0, metavar="DEG",
                    help="nominal arc of each run (default 360; ISO 230-4 partial arcs >= 90): overrun beyond it is trimmed")
    pc.add_argument("--lead-in", type=float, default=0.0, metavar="DEG", help="remove this arc at the start of each run")
    pc.add_argument("--lead-out", type=float, default=0.0, metavar="DEG", help="remove this arc at the end of each run")
    pc.add_argument("--as-given", action="store_true",
                    help="keep the CW/CCW labels even when the point order says otherwise (only warn)")
    pc.add_argument("--angle-unit", choices=("deg", "rad"), help="angle column of an angle + radial-deviation file")
    add_tolerance_option(pc, "G (the larger of CW and CCW), G_cw, G_ccw, G_b, H")
    add_report_option(pc)
    add_test_identity_options(pc)
    add_reader_options(pc)
    pc.add_argument("--json", action="store_true", help="print one JSON object (mm, rad; see its 'units')")
    pc.add_argument("--plot", metavar="FILE", help="write the polar plot (.png, .pdf, .svg)")
    pc.set_defaults(func=cmd_circular_test)


# ----------------------------------------------------------------------------------------- positioning
def instrument_length(option: str, text) -> tuple[float | None, bool]:
    """(mm, unit given?) of ``--mpe`` / ``--instrument-u``: a length with its unit (``2um``, ``2 µm``, ``0.5nm``,
    ``0.002mm``) or a bare number in mm (as before units were accepted); a one-line error otherwise."""
    import re
    from methods.units import mm_per
    if text is None:
        return None, False
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


def cmd_positioning(args) -> int:
    from datasets.io import read_positioning
    from fitbench.plots.positioning import plot, text

    plot_path = check_plot_path(args.plot)
    report_path = check_plot_path(args.report, "--report")
    instrument_u, u_explicit = instrument_length("--instrument-u", args.instrument_u)
    mpe, mpe_explicit = instrument_length("--mpe", args.mpe)
    if args.degree < 0:
        raise InvalidInputError(f"--degree must be >= 0, got {args.degree}")
    temperature, given_as = material_temperature(args.material_temperature)
    alpha = expansion_coefficient(args.expansion_coefficient)
    if (temperature is None) != (alpha is None):
        raise InvalidInputError("the temperature correction needs both --material-temperature (°C) and "
                                "--expansion-coefficient (µm/(m·K), e.g. 11.5 for steel)")
    given_deviation_unit = args.deviation_unit
    with warnings.catch_warnings(record=True) as read_warnings:
        warnings.simplefilter("always")
        data, args.unit, args.deviation_unit = read_positioning(args.file, unit=args.unit,
                                                                deviation_unit=args.deviation_unit,
                                                                skip_rows=args.skip_rows, with_units=True)
    from methods.units import UnitWarning
    unit_warnings = [str(w.message) for w in read_warnings if issubclass(w.category, UnitWarning)]
    if args.compensation and unit_warnings and given_deviation_unit is None:
        # a controller file from values the reader itself finds implausible: nothing is written (one line)
        from fitbench.compensation import CompensationError
        raise CompensationError(f"not writing {', '.join(p for _, p in args.compensation)}: {unit_warnings[0]}; a "
                                "controller table from them would be wrong by the same factor: give the deviations' "
                                "unit with --deviation-unit (or --deviation-unit mm to confirm mm)")
    from methods.positioning.data import RunOrderNote, swap_directions
    run_order = [w.message for w in read_warnings if issubclass(w.category, RunOrderNote)]
    for w in read_warnings:
        if not issubclass(w.category, RunOrderNote):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    notes = []
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
        thermal = {"material_temperature_c": temperature, "expansion_coefficient_um_per_m_k": alpha,
                   "correction_um_per_m": -alpha * (temperature - 20.0)}
        thermal_text = (f"temperature correction (ISO 230-2 nominal differential expansion): material at "
                        f"{temperature:.4g} °C{given_as}, expansion coefficient {alpha:g} µm/(m·K): deviations corrected by "
                        f"{-alpha * (temperature - 20.0):+.4g} µm/m x target position, to 20 °C")
    res = methods.fit("positioning.gls_polynomial", data, degree=args.degree, instrument_u=instrument_u, mpe=mpe)
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
    if args.compensation:
        from fitbench.compensation import write_tables
        comp = write_tables(res, data, args.compensation, interval=finite("--interval", args.interval, positive=True),
                            source=args.compensation_from, axis=args.axis or "X1", write=write_text_atomic,
                            reference_mm=finite("--reference", args.reference),
                            unit_confirmed=given_deviation_unit is not None, on_confirmed=warn)
    missing = [n for n in tolerances if n not in res.figures]
    if missing:
        raise InvalidInputError(f"--tolerance {missing[0]}: this test has no figure {missing[0]} "
                                f"({res.figures.get('directions', 'bidirectional')}, {args.standard})")
    check = verdict({n: abs(res.figures[n]) for n in tolerances}, tolerances)
    if plot_path:
        title = str(args.file) + (f"; corrected to 20 °C from {temperature:g} °C, {alpha:g} µm/(m·K)" if thermal else "")
        title += verdict_title(check)
        plot(res, plot_path, title=title, data=data, save=save_figure)
    lines = [header_line("positioning", args.unit, deviation_unit=args.deviation_unit)]
    lines += [f"note: {n}" for n in notes]
    lines += ([thermal_text] if thermal else []) + [text(res, degree=args.degree)] + verdict_lines(check)
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
        out["polynomial"] = {d: {"coefficients": p["coefficients"], "covariance": p["covariance"],
                                 "degree": p["degree"], "U_at_targets": p["U_at_targets"], "k": p["k"]}
                             for d, p in res.polynomial.items()}
        out["u_delta"] = res.extra["u_delta"]
        out["notes"] = notes
        if args.standard.startswith("iso230-2"):
            out["iso230_2_conformity"] = {"meets_minimum": not lacks, "lacks": lacks}
        # the axis as given (--axis; '' if not): fitbench history keeps each machine's axes apart
        out["details"] = {"conditions": test_conditions(args, axis=args.axis or "", files=[str(args.file)])}
        cli_options.print_json(json.dumps(_jsonable(out)))
        return 0
    print("\n".join(lines))
    if comp is not None:
        for fmt, path in args.compensation:
            print(f"compensation table ({fmt}, every {comp.attrs['interval_mm']:g} mm from {comp.position_mm.iloc[0]:g} "
                  f"to {comp.position_mm.iloc[-1]:g} mm, from the {args.compensation_from}) written to {path}")
    return 0


def add_positioning(sub):
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
    add_tolerance_option(pp, "A, E, R, B, M, A_up, ...")
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
    pp.add_argument("--deviation-unit", choices=UNIT_CHOICES,
                    help="unit of the deviation columns when it differs from --unit (laser exports: targets in mm, "
                         "errors in µm)")
    add_reader_options(pp, columns=False)
    pp.add_argument("--compensation", nargs=2, action="append", metavar=("FORMAT", "FILE"),
                    help="write a compensation table: FORMAT csv, siemens-eec or fanuc-pitch (repeatable)")
    pp.add_argument("--interval", type=float, default=None, metavar="MM",
                    help="compensation point spacing (mm; default: the target spacing)")
    pp.add_argument("--compensation-from", choices=("model", "mean"), default="model",
                    help="compensation values from the GLS polynomial (default) or the mean deviations at the targets")
    pp.add_argument("--axis", default=None, help="the axis tested: recorded in the JSON result (fitbench history trends "
                    "each machine's axes apart) and its name in the controller's table (default X1)")
    pp.add_argument("--reference", type=float, metavar="MM", help="the machine's reference point, where the table "
                    "holds 0 (mm; default 0 if the travel contains it, else the nearer end)")
    pp.add_argument("--json", action="store_true", help="print one JSON object (mm; see its 'units')")
    pp.add_argument("--plot", metavar="FILE", help="write the plot (.png, .pdf, .svg)")
    pp.set_defaults(func=cmd_positioning)


# ----------------------------------------------------------------------------------------- magnify
def cmd_magnify(args) -> int:
    from datasets import read_points
    from methods.magnify import MagnifyInput

    eta = finite("--eta", args.eta, positive=True, allow_none=False)
    plot_path = check_plot_path(args.plot)
    cols = tuple(args.columns) if args.columns else None   # x, y from the header (x, y, z: --plane or --columns)
    from datasets.io import points_unit
    units = {points_unit(f, cols, plane=args.plane, unit=args.unit, skip_rows=args.skip_rows)
             for f in (args.reference, args.measured)}
    if len(units) > 1:
        raise InvalidInputError(f"{args.reference} and {args.measured} are in different units ({', '.join(sorted(units))}); "
                                "give both in one unit")
    args.unit = units.pop()
    data = MagnifyInput(read_points(args.reference, cols, plane=args.plane, unit=args.unit, skip_rows=args.skip_rows),
                        read_points(args.measured, cols, plane=args.plane, unit=args.unit, skip_rows=args.skip_rows))
    half = float(np.max(np.ptp(data.measured, axis=0))) / 2
    warn_implausible("trajectory half-widths", half, PROFILE_LIMIT_MM, args.unit, typical_mm=50.0)
    params = {"eta": eta}
    if args.method == "offset":
        params["delta"] = finite("--delta", args.delta, positive=True)
        params["selection"] = args.selection
    elif args.delta is not None:
        raise InvalidInputError("--delta is a parameter of --method offset")
    res = methods.fit(f"magnify.{args.method}", data, **params)
    if plot_path:
        from fitbench.plots.magnify import plot_magnified
        plot_magnified(data, res, plot_path, eta, save=save_figure)
    if args.json:
        d = res.to_dict(residuals=not args.no_residuals)
        d["units"] = {"length": "mm", "input_unit": canonical(args.unit)}
        cli_options.print_json(json.dumps(d))
        return 0
    print(header_line("magnify", args.unit))
    print(f"method       {res.method} ({res.message})")
    print(f"points       {len(res.points)}; largest contouring error {res.form_error * 1e3:.3f} µm")
    print(f"continuity   {res.extra['continuity']:.3g} (largest magnified step / (eta x largest measured step))")
    print(f"loops        {res.extra['self_intersections']} self-intersections of the magnified trajectory")
    return 0


def add_magnify(sub):
    pm = sub.add_parser("magnify", help="magnified contouring-error trajectory (nearest or contour-parallel offset)")
    pm.add_argument("reference", metavar="REFERENCE.csv", help="reference polyline (x, y; arcs as fine polylines)")
    pm.add_argument("measured", metavar="MEASURED.csv", help="measured trajectory (x, y), in order")
    pm.add_argument("--eta", type=float, required=True, metavar="E", help="magnification (a positive number)")
    pm.add_argument("--delta", type=float, metavar="D_MM", help="offset distance (mm; > the largest error; default twice it)")
    pm.add_argument("--method", choices=("offset", "nearest"), default="offset")
    pm.add_argument("--selection", choices=("same_side", "nearest_of_both"), default="same_side",
                    help="offset method: the offset on the point's side, or the paper's printed step (2)")
    add_reader_options(pm)
    pm.add_argument("--json", action="store_true", help="print one JSON object (points: the magnified trajectory, mm)")
    pm.add_argument("--no-residuals", action="store_true", help="leave the per-point errors out of --json")
    pm.add_argument("--plot", metavar="FILE", help="write a plot (.png, .pdf, .svg)")
    pm.set_defaults(func=cmd_magnify)


# ----------------------------------------------------------------------------------------- multilateration
#: the default method by whether the stations are given: the joint adjustment when they are located from the same
#: lengths (the two-step schemes are biased by the machine's errors there, docs/multilateration.md), Case A
#: (eq. 7) with known stations (the joint adjustment is then identical to it, and slower)
DEFAULT_MULTILATERATION = {False: "joint", True: "case_a_distance"}
#: the paper's two-step schemes: step 1 fits the stations to the nominal points
TWO_STEP_MULTILATERATION = tuple(f"multilateration.{m}" for m in ("case_a_distance", "case_a_squared", "case_b_linear",
                                                                   "case_b_taylor", "case_b_centred"))


def cmd_multilaterate(args) -> int:
    from datasets.io import read_multilateration

    if args.max_iter is not None and args.max_iter < 1:
        raise InvalidInputError(f"--max-iter must be a positive integer, got {args.max_iter}")
    if args.degree < 1:
        raise InvalidInputError(f"--degree must be a positive integer (the component errors' polynomial degree), "
                                f"got {args.degree}")
    if args.errors_csv and not args.identify:
        raise InvalidInputError("--errors-csv needs --identify (the 21 errors come from the identification)")
    data, units = read_multilateration(args.file, args.stations, unit=args.unit, skip_rows=args.skip_rows,
                                       with_units=True)
    args.unit = units["x"] if len(set(units.values())) == 1 else args.unit or "mm"  # the header's, else --unit / mm
    # tracking interferometers measure up to ~15-20 m: longer lengths are a unit mistake
    warn_implausible("measured lengths", float(np.nanmax(data.lengths)), 50_000.0, units["length"], typical_mm=2000.0)
    known = data.known_stations is not None
    chosen = args.method or (DEFAULT_MULTILATERATION[known])
    method = chosen if "." in chosen else f"multilateration.{chosen}"
    spec = methods.get(method)
    if spec.family != "multilateration":
        raise InvalidInputError(f"{method} is not a multilateration method; "
                                f"'python -m methods list --family multilateration' lists them")
    notes = []
    if not known:
        if method in TWO_STEP_MULTILATERATION:
            warn(f"{method} locates the stations from the nominal points while the lengths go to the actual ones: the "
                 "stations absorb the machine's errors and the volumetric errors come out biased (docs/multilateration.md: "
                 "14-22 µm RMS of 32 µm); --method joint adjusts stations and points together, or give --stations")
        notes.append("stations located from the same lengths: the volumetric errors are determined up to a rigid-body "
                     "motion, which self-located stations cannot observe (the points are aligned to the nominal ones; "
                     "a rigid part of the machine's errors does not appear)")
    res = run_method(spec, data, **({"max_iter": args.max_iter} if args.max_iter is not None and "max_iter" in spec.defaults else {}))
    ident = _identify(data, res, args.degree) if args.identify else None
    if ident is not None and args.errors_csv:
        from methods.multilateration.export import errors_csv
        write_text_atomic(args.errors_csv, errors_csv(ident))
    if args.json:
        d = res.to_dict(residuals=not args.no_residuals)
        d["units"] = {"length": "mm", "angle": "rad", "input_unit": canonical(args.unit), "input_units": units}
        d["nominal_points"] = _jsonable(data.points)
        d["stations_given"] = data.known_stations is not None
        d["notes"] = notes
        if ident is not None:
            d["geometric_errors"] = {"degree": ident.model.degree, "travel": list(ident.model.travel),
                                     "basis": "coefficient of (axis position / travel)^j; E[XYZ]* and T* in mm, "
                                              "E[ABC]*, squareness and R* in rad",
                                     "parameters": ident.as_table(), "residual_rms": ident.residual_rms}
        cli_options.print_json(json.dumps(_jsonable(d)))
        return 0 if res.converged else 1
    vol = np.linalg.norm(res.volumetric_errors, axis=1)
    mixed = ", ".join(f"{c} {u}" for c, u in units.items() if u != canonical(args.unit))
    print(header_line("multilaterate", args.unit, "; station coordinates in mm" + (f"; header units: {mixed}" if mixed else "")))
    print(f"method       {res.method} ({res.message})")
    for n in notes:
        print(f"note: {n}")
    print(f"data         {args.file}: {len(data.stations)} stations, {len(data.points)} points, "
          f"{int(data.mask.sum())} lengths; stations {'given' if known else 'located (step 1)' if method in TWO_STEP_MULTILATERATION else 'located with the points'}")
    print(f"{'station':<10} {'x [mm]':>14} {'y [mm]':>14} {'z [mm]':>14} {'L [mm]':>12}")
    for sid, st in zip(res.station_ids, res.stations):
        print(f"{sid:<10} {st[0]:14.6f} {st[1]:14.6f} {st[2]:14.6f} {st[3]:12.6f}")
    print(f"volumetric   largest |error| {vol.max() * 1e3:.3f} µm, RMS {np.sqrt(np.mean(vol ** 2)) * 1e3:.3f} µm")
    r = res.residuals[np.isfinite(res.residuals)]
    print(f"residuals    RMS {np.sqrt(np.mean(r ** 2)) * 1e3:.4f} µm of the lengths")
    for step, c in res.condition_numbers.items():
        print(f"kappa        {step:<16} median {np.median(c['svd']):.3g} (SVD), Theorem 1 lower estimate "
              f"{np.median(c['theorem1']):.3g}: {c['system']}")
    print(f"converged    {'yes' if res.converged else 'NO'}; runtime {res.runtime_s * 1e3:.2f} ms")
    if ident is not None:
        travel = ", ".join(f"{t:g}" for t in ident.model.travel)
        print(f"geometric errors (ISO 230-1 names), coefficients of (position / travel)^j, travels {travel} mm; "
              f"fit residual RMS {ident.residual_rms * 1e3:.3f} µm")
        for row in ident.as_table():
            name = row["parameter"]
            linear = (name[0] == "E" and name[1] in "XYZ") or name[0] == "T"
            unit, scale = ("µm", 1e3) if linear else ("µrad", 1e6)
            print(f"  {row['parameter']:<7} {row['value'] * scale:12.4f} +- {row['u'] * scale:.4f} {unit}")
        if args.errors_csv:
            print(f"the 21 errors written to {args.errors_csv}")
    return 0 if res.converged else 1


def add_multilaterate(sub):
    pu = sub.add_parser("multilaterate", help="stations, actual points and volumetric errors from tracking-interferometer lengths")
    pu.add_argument("file", metavar="MEASUREMENTS.csv", help="columns station, x, y, z (nominal point), length")
    pu.add_argument("--method", default=None, metavar="ID",
                    help="multilateration method id or its short name (default: joint, stations and points adjusted "
                         "together, when the stations are located from the data; case_a_distance, the paper's eq. 7, "
                         "with --stations)")
    pu.add_argument("--stations", metavar="FILE", help="known stations: columns station, x, y, z, L (skips step 1)")
    pu.add_argument("--max-iter", type=int, metavar="N", help="iteration limit of the iterative methods (>= 1)")
    pu.add_argument("--identify", action="store_true",
                    help="also identify the 18 component and 3 squareness errors (needs columns xp, yp, zp)")
    pu.add_argument("--degree", type=int, default=3, help="polynomial degree of the component errors (default 3, >= 1)")
    pu.add_argument("--errors-csv", metavar="FILE", help="with --identify: write the 21 errors (ISO 230-1 names) as CSV")
    add_reader_options(pu, columns=False)
    pu.add_argument("--json", action="store_true", help="print one JSON object (mm, rad)")
    pu.add_argument("--no-residuals", action="store_true", help="leave the length residuals out of --json")
    pu.set_defaults(func=cmd_multilaterate)


def _identify(data, res, degree):
    """The 21 geometric errors from the volumetric errors (kinematic chain of the multilateration paper)."""
    from methods.multilateration.kinematics import identify
    if data.offsets is None:
        raise InvalidInputError("--identify needs the tool offsets: add columns xp, yp, zp to the measurements "
                                "(0, 0, 0 for the bare reflector; at least two non-parallel offsets)")
    axes = data.points - data.offsets
    travel = np.max(np.abs(axes), axis=0)
    travel[travel == 0] = 1.0
    return identify(axes, data.offsets, res.volumetric_errors, degree=degree, travel=tuple(travel), rigid=True)


# ----------------------------------------------------------------------------------------- the table
def add_list(sub):
    pl = sub.add_parser("list", help="one line per registered method: id, kind, reference")
    pl.add_argument("--family", help="only this family (e.g. circle)")
    pl.add_argument("--json", action="store_true", help="machine-readable listing with defaults")
    pl.set_defaults(func=cmd_list)


def add_fit(sub):
    pf = sub.add_parser("fit", help="fit a file or published data set with one method")
    pf.add_argument("method", metavar="METHOD_ID")
    pf.add_argument("file", metavar="FILE", help="a points file (x, y, or angle + radial deviation) or a published "
                                                "data set name")
    pf.add_argument("--param", action="append", metavar="KEY=VALUE", help="method parameter (repeatable)")
    pf.add_argument("--nominal-radius", type=float, metavar="R_MM",
                    help="angle + radial-deviation files: the radius the deviations are about (mm; default: the "
                         "deviations alone)")
    add_reader_options(pf, polar=True, printed="mm")
    pf.add_argument("--json", action="store_true", help="print the result as one JSON object")
    pf.add_argument("--no-residuals", action="store_true", help="leave the per-point residuals out of --json")
    pf.add_argument("--verbose", action="store_true",
                    help="also print the solver's message on a converged fit (its stopping and optimality tests; "
                         "always in --json as 'message')")
    pf.add_argument("--plot", metavar="FILE", help="write a quick look: points, fitted curve, residuals (.png, .pdf, .svg)")
    pf.set_defaults(func=cmd_fit)


def add_roundness(sub):
    """ISO 12181 roundness: the parser and command live in fitbench/cli/roundness.py."""
    from fitbench.cli import roundness
    roundness.add_parser(sub)


def add_history(sub):
    """The trend of a machine's tests: fitbench/cli/history.py."""
    from fitbench.cli import history
    history.add_parser(sub)


#: the subcommands: name -> function adding its parser (another module may add an entry)
SUBCOMMANDS = {"list": add_list, "fit": add_fit, "circular-test": add_circular_test, "positioning": add_positioning,
               "magnify": add_magnify, "multilaterate": add_multilaterate, "roundness": add_roundness,
               "history": add_history}


def build_parser(prog: str = PROG, extra_commands: dict | None = None) -> argparse.ArgumentParser:
    p = _Parser(prog=prog, description="fitbench: fitting methods of machine-tool metrology")
    p.add_argument("--version", action="version", version=f"fitbench {version()}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in SUBCOMMANDS.values():
        add(sub)
    for name, help_text in (extra_commands or {}).items():
        sub.add_parser(name, help=help_text, add_help=False)
    for action in sub.choices.values():
        action.add_argument("--version", action="version", version=f"fitbench {version()}",
                            help="print the version and exit") if "--version" not in action._option_string_actions else None
    return p


def _json_only(args) -> int:
    """Run a ``--json`` command with everything printed to stdout sent to stderr (:func:`stdout_to_stderr`: a
    plugin printing when it is imported, compiled code writing to descriptor 1) and print the command's JSON
    (:func:`fitbench.cli.options.print_json`) once stdout is restored: stdout carries the JSON object alone."""
    saved, cli_options.JSON_PENDING = cli_options.JSON_PENDING, []
    pending = cli_options.JSON_PENDING
    try:
        with stdout_to_stderr():
            code = args.func(args)
    finally:
        cli_options.JSON_PENDING = saved
    for text in pending:
        print(text)
    return code


def main(argv=None, prog: str = "fitbench", extra_commands: dict | None = None) -> int:
    """The command ``prog`` (``fitbench``, or ``python -m methods`` without the experiment subcommands): error
    and warning lines start with ``prog`` (:data:`fitbench.cli.options.PROGRAM`)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    saved, cli_options.PROGRAM = cli_options.PROGRAM, prog
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", category=UserWarning)
            failed = None
            try:
                if argv and argv[0] in EXPERIMENT_SUBCOMMANDS and argv[0] not in (extra_commands or {}):
                    raise InvalidInputError(f"'{argv[0]}' is a subcommand of fitbench, not of {prog}: use "
                                            f"'fitbench {argv[0]} ...' or 'python -m experiments.{argv[0]} ...'")
                args = build_parser(prog, extra_commands).parse_args(argv)
                with one_blas_thread():
                    if not getattr(args, "json", False):
                        return args.func(args)
                    return _json_only(args)
            except InvalidInputError as exc:
                failed = str(exc)
                raise
            finally:
                from methods.units import UnitWarning
                for w in caught:
                    # an error naming the unit to give (--unit ...) says what a unit warning before it said
                    if issubclass(w.category, UserWarning) and not (
                            failed and issubclass(w.category, UnitWarning) and "--unit" in failed):
                        warn(str(w.message))
    except InvalidInputError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except MethodFailed as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return EXIT_METHOD_FAILED
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:   # Ctrl-C: one line and the shell's status for SIGINT, as experiments.run ends
        print(f"\n{prog}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        cli_options.PROGRAM = saved
