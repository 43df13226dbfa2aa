"""``fitbench magnify REFERENCE MEASURED``: the magnified contouring-error trajectory (nearest point or
contour-parallel offset)."""
from __future__ import annotations

import json

import numpy as np

import fitbench.cli.options as cli_options
from fitbench.cli.guards import check_outputs, written_files
import methods
from fitbench.cli.options import (PROFILE_LIMIT_MM, add_reader_options, check_plot_path, finite, header_line,
                                  save_figure)
from fitbench.cli.options import quantity
from methods import InvalidInputError
from methods.units import canonical, warn_implausible


def add_parser(sub):
    pm = sub.add_parser("magnify", help="magnified contouring-error trajectory (nearest or contour-parallel offset)")
    pm.add_argument("reference", metavar="REFERENCE.csv", help="reference polyline (x, y; arcs as fine polylines)")
    pm.add_argument("measured", metavar="MEASURED.csv", help="measured trajectory (x, y), in order")
    pm.add_argument("--eta", type=float, required=True, metavar="E", help="magnification (a positive number)")
    pm.add_argument("--delta", type=quantity("--delta"), metavar="D_MM",
                    help="offset distance (mm, or with its unit: 10um; > the largest contouring error; default twice it)")
    pm.add_argument("--method", choices=("offset", "nearest"), default="offset")
    pm.add_argument("--selection", choices=("same_side", "nearest_of_both"), default="same_side",
                    help="offset method: the offset on the point's side, or the paper's printed step (2)")
    add_reader_options(pm, angles=False)   # x, y trajectories only
    pm.add_argument("--json", action="store_true", help="print one JSON object (points: the magnified trajectory, mm)")
    pm.add_argument("--no-residuals", action="store_true", help="leave the per-point errors out of --json")
    pm.add_argument("--plot", metavar="FILE", help="write a plot (.png, .pdf, .svg)")
    pm.set_defaults(func=run)


def run(args) -> int:
    from datasets import read_points
    from methods.magnify import MagnifyInput

    eta = finite("--eta", args.eta, positive=True, allow_none=False)
    plot_path = check_plot_path(args.plot)
    check_outputs([args.reference, args.measured], [("--plot", args.plot, "plot")])
    cols = tuple(args.columns) if args.columns else None   # x, y from the header (x, y, z: --plane or --columns)
    from datasets.io import points_unit
    # each file in its header's unit (or --unit, else mm), converted to mm as every reader does
    ref_unit, meas_unit = (points_unit(f, cols, plane=args.plane, unit=args.unit, skip_rows=args.skip_rows)
                           for f in (args.reference, args.measured))
    data = MagnifyInput(read_points(args.reference, cols, plane=args.plane, unit=ref_unit, skip_rows=args.skip_rows),
                        read_points(args.measured, cols, plane=args.plane, unit=meas_unit, skip_rows=args.skip_rows))
    args.unit = meas_unit
    half = float(np.max(np.ptp(data.measured, axis=0))) / 2
    warn_implausible("trajectory sizes (half the points' span)", half, PROFILE_LIMIT_MM, meas_unit, typical_mm=50.0)
    params = {"eta": eta}
    if args.method == "offset":
        params["delta"] = finite("--delta", args.delta, positive=True)
        params["selection"] = args.selection
    elif args.delta is not None:
        raise InvalidInputError("--delta is a parameter of --method offset")
    try:
        res = methods.fit(f"magnify.{args.method}", data, **params)
    except InvalidInputError as exc:
        if getattr(exc, "delta_emax", None) is None:
            raise
        delta, emax = (v * 1e3 for v in exc.delta_emax)   # mm -> µm
        raise InvalidInputError(f"--delta {delta:.4g} µm must be larger than the largest contouring error "
                                f"({emax:.4g} µm); choose a larger --delta (e.g. {2 * emax:.3g}um, twice it, "
                                "the default)") from None
    said = cli_options.said_warnings()   # printed before the figures, written into the JSON
    if plot_path:
        from fitbench.plots.magnify import plot_magnified
        plot_magnified(data, res, plot_path, eta, save=save_figure)
    if args.json:
        d = res.to_dict(residuals=not args.no_residuals)
        d["units"] = {"length": "mm", "input_unit": canonical(meas_unit), "reference_unit": canonical(ref_unit)}
        d["warnings"] = list(dict.fromkeys([*d.get("warnings", []), *said]))
        d["files_written"] = written_files()
        cli_options.print_json(json.dumps(d))
        return 0
    both = "" if canonical(ref_unit) == canonical(meas_unit) else f"; reference in {canonical(ref_unit)}"
    print(header_line("magnify", meas_unit, both))
    print(f"method       {res.method} ({res.message})")
    print(f"points       {len(res.points)}; largest contouring error {res.form_error * 1e3:.3f} µm "
          "(distance from the reference path)")
    if args.method == "offset":
        print(f"magnified    about points of the path up to {res.extra['max_magnified_distance'] * 1e3:.3f} µm from "
              "the measured point (|p - r~|: at a corner the distance to the corner, magnified radially)")
    print(f"continuity   {res.extra['continuity']:.3g} (largest magnified step / (eta x largest measured step))")
    print(f"loops        {res.extra['self_intersections']} self-intersections of the magnified trajectory")
    return 0
