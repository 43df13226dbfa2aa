"""``fitbench circular-test CW CCW``: the ISO 230-4 evaluation of a CW and a CCW run (G, F, H about the nominal
circle) and the diagnostics of the machine's errors (squareness, backlash, servo mismatch, ...): a table, JSON,
the polar plot and a report."""
from __future__ import annotations

import json
import math

import numpy as np

import fitbench.cli.options as cli_options
import methods
from fitbench.cli.guards import check_outputs, jsonable, written_files
from fitbench.cli.options import (add_reader_options, add_report_option, add_test_identity_options,
                                  add_tolerance_option, check_plot_path, finite, header_line, parse_tolerances,
                                  save_figure, verdict, verdict_lines, verdict_title, warn, warn_bare_tolerances,
                                  write_report)
from fitbench.cli.options import quantity
from methods import InvalidInputError
from methods.units import JSON_UNITS, canonical


def add_parser(sub):
    pc = sub.add_parser("circular-test", help="ISO 230-4 evaluation and diagnostics of a CW and a CCW run")
    pc.add_argument("files", nargs="+", metavar="FILE",
                    help="CW.csv CCW.csv, or one file with both runs (a direction or run column); x, y columns or "
                         "angle + radial deviation")
    pc.add_argument("--nominal-radius", type=quantity("--nominal-radius"), required=True, metavar="R_MM",
                    help="nominal radius (mm, or with its unit: 150mm, 5.9in)")
    pc.add_argument("--nominal-center", type=quantity("--nominal-center"), nargs=2, metavar=("X", "Y"),
                    help="nominal centre in machine coordinates (mm); needed for F about it and for the diagnostics")
    pc.add_argument("--center", choices=("lsq", "mz"), default="lsq", help="centre for G: least squares or minimum zone")
    pc.add_argument("--feed", type=quantity("--feed", "feed"), metavar="MM_PER_MIN",
                    help="feed (mm/min, or with its unit: 2000mm/min, 2m/min): gives the servo mismatch in ms")
    pc.add_argument("--cyclic-pitch", type=quantity("--cyclic-pitch"), metavar="MM",
                    help="ball-screw pitch (mm, or with its unit: 10mm): estimates the cyclic error")
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
    pc.set_defaults(func=run)


def _read_circular_runs(args):
    """({'cw': points, 'ccw': points} as the user labelled them, the first file's CircularRuns, labelled?), from one
    file (direction/run column) or two."""
    from datasets.io import read_runs
    from methods.circular_test.evaluation import MIN_ARC_DEG
    kw = dict(columns=tuple(args.columns) if args.columns else None, plane=args.plane, unit=args.unit,
              skip_rows=args.skip_rows, angle_unit=args.angle_unit, nominal_radius=args.nominal_radius,
              min_arc_deg=MIN_ARC_DEG,
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


#: the machine planes in their right-handed order (first axis x right, second up, seen from the third's + side,
#: where G02 turns clockwise: ISO 6983-1 / ISO 841), and the mirrored pairs that view them from the - side
PLANE_AXES = {("x", "y"): "xy", ("y", "z"): "yz", ("z", "x"): "zx"}
MIRRORED_AXES = {(b, a): p for (a, b), p in PLANE_AXES.items()}


def _plane_of(axes: tuple, plane: str | None) -> tuple[str, str | None]:
    """(the plane of the two coordinates read, a note when they are a mirrored pair). ``--columns x z`` puts X right
    and Z up: the ZX plane seen from -Y, where a G02 (clockwise seen from +Y) turns counter-clockwise, so the runs
    were called the wrong way round and the diagnostics named Z "Y". Such a pair is read in the plane's own order
    (z, x), the note says so; the nominal centre given in the columns' order is turned with it."""
    pair = tuple(str(a).lower() for a in axes)
    if pair in MIRRORED_AXES:
        p = MIRRORED_AXES[pair]
        return p, (f"--columns {pair[0]} {pair[1]} views the {p.upper()} plane from -{'XYZ'['yzx'.index(p[0])]}; read "
                   f"as {p[0]}, {p[1]} (the plane seen from +{'XYZ'['yzx'.index(p[0])]}, where G02 turns clockwise, "
                   f"ISO 6983-1); centres are printed as ({p[0]}, {p[1]})")
    return plane or PLANE_AXES.get(pair, "xy"), None


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


def run(args) -> int:
    from methods.circular_test import diagnose, evaluate
    from fitbench.plots.circular_test import FIGSIZE as POLAR_FIGSIZE, diagnostics_json, model_json, polar_plot, text
    from methods.circular_test.evaluation import nominal_mismatch
    from methods.circular_test.runs import (check_nominal, check_pair, drop_repeated, off_circle_ends,
                                            overrun_text, trim)

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
    check_outputs(args.files, [("--plot", args.plot, "plot"), ("--report", args.report, "test report")])
    tolerances = parse_tolerances(args.tolerance, ("G", "G_cw", "G_ccw", "G_b", "H"))
    runs, first, labelled = _read_circular_runs(args)
    args.unit = first.unit
    plane, plane_note = _plane_of(first.axes, args.plane)
    if plane_note:   # a mirrored pair (--columns x z): read in the plane's own order, so G02 is CW as ISO 6983 says
        runs = {k: np.ascontiguousarray(p[:, ::-1]) for k, p in runs.items()}
        if args.nominal_center is not None:
            args.nominal_center = args.nominal_center[::-1]
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
    for name, pts in runs.items():   # data off the nominal circle (a unit or a centre mistake): said before any
        label = name.upper() if labelled else ('first', 'second')[name == 'ccw']   # direction is judged about it
        if (why := nominal_mismatch(pts, label, R, args.nominal_center, args.unit, center=center0)) is not None:
            raise InvalidInputError(why)
    trimmed = {}
    notes = ["angle + radial deviation: points placed about the nominal centre (0, 0), which the diagnostics use"] \
        if polar_centre else []
    notes += [first.columns_note] if first.columns_note else []
    notes += [plane_note] if plane_note else []
    for name in ("cw", "ccw"):
        label = name.upper() if labelled else ('first', 'second')[name == 'ccw']   # runs told apart by order
        runs[name], repeats, said = drop_repeated(runs[name], center0, label)  # a dwell is no contour point
        if said:
            warn(said)
            notes.append(said)
        runs[name], rep = trim(runs[name], center0, arc_deg=arc, lead_in_deg=args.lead_in, lead_out_deg=args.lead_out,
                               overrun="end" if args.lead_in or args.lead_out else "auto", name=label)
        trimmed[name] = dict(rep, **repeats)
        trim_note, trim_warning = overrun_text(rep, label, arc)
        if (fed := off_circle_ends(runs[name], center0, label)) is not None:
            raise InvalidInputError(fed)
        if len(runs[name]) < 10:
            raise InvalidInputError(f"circular test ({name.upper()} run): {len(runs[name])} point(s) left after removing "
                                    f"the lead-in/out and the overrun beyond {arc:g}°; at least 10 are needed")
        if trim_warning:   # the passes over the same angles differ: which end was kept, and how to keep the other
            warn(trim_warning)
        if trim_note:
            notes.append(trim_note)
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
    conditions = {"nominal_radius_mm": R, "nominal_center_mm": center, "feed_mm_min": feed, "plane": plane,
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
    warn_bare_tolerances(tolerances, values)
    said = cli_options.said_warnings()   # printed before the figures, written into the report and the JSON
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
        out["warnings"] = said
        if check:
            out["verdict"] = check
        if dg:
            out["details"]["diagnostics_model"] = model_json(dg["_model"], conditions["plane"])
        out["files_written"] = written_files()
        cli_options.print_json(json.dumps(jsonable(out)))
        return 0
    print("\n".join(lines))
    return 0
