"""``fitbench multilaterate MEASUREMENTS``: stations, actual points and volumetric errors from
tracking-interferometer lengths, and optionally the 21 geometric errors (ISO 230-1 names) identified from them."""
from __future__ import annotations

import json

import numpy as np

import fitbench.cli.options as cli_options
import methods
from fitbench.cli.guards import check_outputs, jsonable, run_method, say_written, written_files
from fitbench.cli.options import add_reader_options, header_line, warn, write_text_atomic
from methods import InvalidInputError
from methods.units import canonical, warn_implausible


#: the default method by whether the stations are given: the joint adjustment when they are located from the same
#: lengths (the two-step schemes are biased by the machine's errors there, docs/multilateration.md), Case A
#: (eq. 7) with known stations (the joint adjustment is then identical to it, and slower)
DEFAULT_MULTILATERATION = {False: "joint", True: "case_a_distance"}
#: the paper's two-step schemes: step 1 fits the stations to the nominal points
TWO_STEP_MULTILATERATION = tuple(f"multilateration.{m}" for m in ("case_a_distance", "case_a_squared", "case_b_linear",
                                                                   "case_b_taylor", "case_b_centred"))


#: the standard uncertainty of one measured length unless --length-uncertainty says (µm): a tracking interferometer
#: (Etalon LaserTRACER-NG data sheet: MPE 0.2 µm + 0.3 µm/m) gives 0.1-0.4 µm over 1-2 m; 0.5 µm leaves room
DEFAULT_LENGTH_U_UM = 0.5
#: length residuals (RMS) beyond this many length uncertainties: the stations and the lengths disagree (a warning)
INCONSISTENT_FACTOR = 3.0
#: length residuals (RMS) beyond this (mm) are no measurement error: the stations or their unit are wrong (refused)
GROSS_RESIDUAL_MM = 1.0


def length_check(res, u_length_mm: float, stations_given: bool) -> dict:
    """The length residuals against the instrument: RMS, RMS / u (``ratio``), each station's RMS, the station that
    carries the largest, and ``consistent`` (ratio <= INCONSISTENT_FACTOR). With the residual RMS 30x the
    instrument's noise a solver still 'converges' to points that absorb a wrong dead path: the review's stations
    with L + 0.02 mm on one station gave a largest volumetric error of 33.6 µm for a true 12.0 µm, exit 0."""
    r = np.asarray(res.residuals, float)
    m = np.isfinite(r)
    rms = float(np.sqrt(np.mean(r[m] ** 2))) if m.any() else 0.0
    with np.errstate(invalid="ignore"):
        per = np.sqrt(np.nanmean(np.where(m, r, np.nan) ** 2, axis=0))
    k = int(np.nanargmax(per)) if np.isfinite(per).any() else 0
    ratio = rms / u_length_mm
    return {"residual_rms_mm": rms, "length_u_mm": u_length_mm, "ratio": ratio,
            "consistent": bool(ratio <= INCONSISTENT_FACTOR),
            "station_rms_mm": {str(sid): float(v) for sid, v in zip(res.station_ids, per)},
            "worst_station": str(res.station_ids[k]), "stations_given": stations_given}


def point_uncertainty(res, nominal) -> np.ndarray | None:
    """Standard uncertainty (N, 3) of each actual point with the given stations held fixed: sigma^2 (J_i^T J_i)^-1,
    J_i the unit vectors from the stations to point i (the lengths it was measured with), sigma^2 = sum r^2 /
    (lengths - 3 N) from the residuals (GUM type A; Holub et al. 2022, eq. 7's least squares). None without
    degrees of freedom."""
    r = np.asarray(res.residuals, float)
    m = np.isfinite(r)
    dof = int(m.sum()) - 3 * len(res.points)
    if dof <= 0:
        return None
    sigma2 = float(np.sum(r[m] ** 2)) / dof
    d = res.points[:, None, :] - res.stations[None, :, :3]                     # (N, K, 3)
    u = d / np.linalg.norm(d, axis=2, keepdims=True) * m[:, :, None]
    JtJ = np.einsum("nki,nkj->nij", u, u)
    cov = sigma2 * np.linalg.pinv(JtJ)
    return np.sqrt(np.maximum(np.diagonal(cov, axis1=1, axis2=2), 0.0))


def add_parser(sub):
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
    pu.add_argument("--length-uncertainty", type=float, default=DEFAULT_LENGTH_U_UM, metavar="UM",
                    help="standard uncertainty of one measured length in µm (default 0.5, a tracking interferometer): "
                         f"residuals beyond {INCONSISTENT_FACTOR:g} times it are warned about, beyond "
                         f"{GROSS_RESIDUAL_MM:g} mm refused")
    add_reader_options(pu, columns=False)
    pu.add_argument("--json", action="store_true", help="print one JSON object (mm, rad)")
    pu.add_argument("--no-residuals", action="store_true", help="leave the length residuals out of --json")
    pu.set_defaults(func=run)


def run(args) -> int:
    from datasets.io import read_multilateration

    if args.max_iter is not None and args.max_iter < 1:
        raise InvalidInputError(f"--max-iter must be a positive integer, got {args.max_iter}")
    if args.degree < 1:
        raise InvalidInputError(f"--degree must be a positive integer (the component errors' polynomial degree), "
                                f"got {args.degree}")
    if args.errors_csv and not args.identify:
        raise InvalidInputError("--errors-csv needs --identify (the 21 errors come from the identification)")
    check_outputs([args.file, args.stations], [("--errors-csv", args.errors_csv, "geometric errors (CSV)")])
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
    u_len = args.length_uncertainty
    if not (np.isfinite(u_len) and u_len > 0):
        raise InvalidInputError(f"--length-uncertainty must be a positive number of µm, got {u_len!r}")
    res = run_method(spec, data, **({"max_iter": args.max_iter} if args.max_iter is not None and "max_iter" in spec.defaults else {}))
    check = length_check(res, u_len * 1e-3, known)
    if check["residual_rms_mm"] > GROSS_RESIDUAL_MM:
        what = ("the given stations (their coordinates, dead paths L or unit: a stations file in m read as mm?)"
                if known else "the stations located from them (is the file's unit right?)")
        raise InvalidInputError(f"{args.file}: the lengths do not fit {what}: residual RMS "
                                f"{check['residual_rms_mm']:.4g} mm, largest at station {check['worst_station']} "
                                f"({check['station_rms_mm'][check['worst_station']]:.4g} mm); no volumetric errors "
                                "are given from them")
    if not check["consistent"]:
        warn(f"the length residuals (RMS {check['residual_rms_mm'] * 1e3:.3g} µm) are {check['ratio']:.3g} x the "
             f"lengths' standard uncertainty {u_len:g} µm (--length-uncertainty): the lengths and the "
             f"{'given stations' if known else 'model'} disagree, largest at station {check['worst_station']} (RMS "
             f"{check['station_rms_mm'][check['worst_station']] * 1e3:.3g} µm); check its position and dead path L; "
             "the volumetric errors are not to be trusted")
    u_pts = point_uncertainty(res, data.points) if known else None
    ident = _identify(data, res, args.degree) if args.identify else None
    if ident is not None and args.errors_csv:
        from methods.multilateration.export import errors_csv
        write_text_atomic(args.errors_csv, errors_csv(ident))
    said = cli_options.said_warnings()   # printed before the figures, written into the JSON
    if args.json:
        d = res.to_dict(residuals=not args.no_residuals)
        d["units"] = {"length": "mm", "angle": "rad", "input_unit": canonical(args.unit), "input_units": units}
        d["nominal_points"] = jsonable(data.points)
        d["stations_given"] = data.known_stations is not None
        d["notes"] = notes
        d["warnings"] = list(dict.fromkeys([*d.get("warnings", []), *said]))
        d["length_check"] = check
        d["point_uncertainty"] = None if u_pts is None else jsonable(u_pts)
        if ident is not None:
            d["geometric_errors"] = {"degree": ident.model.degree, "travel": list(ident.model.travel),
                                     "basis": "coefficient of (axis position / travel)^j; E[XYZ]* and T* in mm, "
                                              "E[ABC]*, squareness and R* in rad",
                                     "parameters": ident.as_table(), "residual_rms": ident.residual_rms}
        d["files_written"] = written_files()
        cli_options.print_json(json.dumps(jsonable(d)))
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
    print(f"residuals    RMS {np.sqrt(np.mean(r ** 2)) * 1e3:.4f} µm of the lengths = {check['ratio']:.3g} x their "
          f"standard uncertainty {u_len:g} µm: {'consistent' if check['consistent'] else 'INCONSISTENT (see the warning)'}")
    if u_pts is not None:
        un = np.linalg.norm(u_pts, axis=1)
        print(f"points       standard uncertainty from the residuals (stations held fixed): largest "
              f"{un.max() * 1e3:.3f} µm, median {np.median(un) * 1e3:.3f} µm (root sum of squares of x, y, z)")
    else:
        print("points       standard uncertainty not computed: the stations were located from the same lengths")
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
            say_written(args.errors_csv, f"the 21 errors written to {args.errors_csv}")
    return 0 if res.converged else 1


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
