"""Command line: ``python -m methods list``, ``fit METHOD_ID FILE`` and the machine-test subcommands.

Bad input ends with one line on stderr and exit status 2, never a traceback.
"""
from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

import methods
from methods._errors import InvalidInputError

EXIT_BAD_INPUT = 2


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2 (argparse prints usage over several lines)
        raise InvalidInputError(f"{message} (see 'python -m methods --help')")


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


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return "nan" if not math.isfinite(v) else f"{v:.10g}"
    return str(v)


def cmd_list(args) -> int:
    specs = methods.list_methods(args.family)
    if args.json:
        print(json.dumps([{"id": s.id, "family": s.family, "kind": s.kind, "summary": s.summary,
                           "reference": s.reference, "defaults": {k: _jsonable(v) for k, v in s.defaults.items()}}
                          for s in specs], indent=1))
        return 0
    width = max((len(s.id) for s in specs), default=10)
    for s in specs:
        print(f"{s.id:<{width}}  {s.kind:<14}  {s.reference}")
    return 0


def _jsonable(v):
    from methods._result import _jsonable as j
    return j(v)


def cmd_fit(args) -> int:
    from datasets import points_from  # imported here: 'list' must work without pandas loaded

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
    source, points = points_from(args.file)
    result = spec(points, **params)
    if args.json:
        d = result.to_dict(residuals=not args.no_residuals)
        d["source"] = source
        d["n_points"] = int(np.asarray(points).shape[0])
        print(json.dumps(d))
        return 0
    rows = [("method", result.method), ("data", f"{source} ({len(points)} points)")]
    if hasattr(result, "center"):
        rows += [("center x", _fmt(result.center[0])), ("center y", _fmt(result.center[1]))]
    if hasattr(result, "radius"):
        rows += [("radius", _fmt(result.radius))]
    if hasattr(result, "inner_radius"):
        rows += [("inner radius", _fmt(result.inner_radius)), ("outer radius", _fmt(result.outer_radius)),
                 ("contacts", f"outer {result.contacts['outer']}, inner {result.contacts['inner']}")]
    if hasattr(result, "semi_axes"):
        rows += [("semi-axes", f"a = {_fmt(result.semi_axes[0])}, b = {_fmt(result.semi_axes[1])}"),
                 ("angle", f"{_fmt(result.angle)} rad ({_fmt(math.degrees(result.angle))} deg, direction of a)")]
    rows += [("form error", _fmt(result.form_error)),
             ("converged", f"{'yes' if result.converged else 'NO'} ({result.message})"),
             ("iterations", _fmt(result.iterations)), ("evaluations", _fmt(result.nfev)),
             ("runtime", f"{result.runtime_s * 1e3:.3f} ms"),
             ("parameters", ", ".join(f"{k}={v!r}" for k, v in result.params.items()) or "-")]
    for k, v in rows:
        print(f"{k:<12} {v}")
    return 0 if result.converged else 1


def cmd_circular_test(args) -> int:
    from datasets import points_from
    from methods.circular_test import diagnose, evaluate
    from methods.circular_test.report import polar_plot, text

    _, cw = points_from(args.cw)
    _, ccw = points_from(args.ccw)
    center = tuple(args.nominal_center) if args.nominal_center else None
    conditions = {"nominal_radius": args.nominal_radius, "nominal_center": center, "feed_mm_min": args.feed,
                  "files": {"cw": str(args.cw), "ccw": str(args.ccw)}, "centre_for_G": args.center}
    ev = evaluate(cw, ccw, args.nominal_radius, center, center=args.center, conditions=conditions)
    dg = None
    if center is not None:
        dg = diagnose(cw, ccw, args.nominal_radius, center, feed_mm_min=args.feed, cyclic_pitch=args.cyclic_pitch)
    if args.plot:
        polar_plot(cw, ccw, ev, args.plot)
    if args.json:
        out = {k: ev[k] for k in ("G_cw", "G_ccw", "G_b", "H", "F_max", "F_min", "mean_radial_deviation", "center")}
        out["diagnostics"] = ({k: v for k, v in dg.items() if not k.startswith("_")} if dg else
                              "not estimated: give --nominal-center X Y")
        out["details"] = {k: v for k, v in ev.items() if k not in out}
        if dg:
            out["details"]["diagnostics_model"] = dg["_model"]
        print(json.dumps(_jsonable(out)))
        return 0
    print(text(ev, dg))
    if dg is None:
        print("diagnostics: not estimated (give --nominal-center X Y)")
    return 0


def cmd_positioning(args) -> int:
    from methods.positioning import read_csv
    from methods.positioning.report import plot

    data = read_csv(args.file)
    res = methods.fit("positioning.gls_polynomial", data, degree=args.degree, instrument_u=args.instrument_u,
                      mpe=args.mpe)
    if args.standard != "iso230-2:2014":
        res.figures = methods.fit("positioning.iso230_2", data, standard=args.standard).figures
    if args.plot:
        plot(res, args.plot, title=str(args.file))
    if args.json:
        out = dict(res.figures)
        out["per_target"] = {k: v for k, v in res.per_target.items()}
        out["polynomial"] = {d: {"coefficients": p["coefficients"], "covariance": p["covariance"],
                                 "degree": p["degree"], "U_at_targets": p["U_at_targets"], "k": p["k"]}
                             for d, p in res.polynomial.items()}
        out["u_delta"] = res.extra["u_delta"]
        print(json.dumps(_jsonable(out)))
        return 0
    f = res.figures
    print(f"ISO 230-2 ({f['standard']}, k = {f['k']:g}): {f['targets']} targets x {f['runs']} runs")
    for key in ("A", "A_up", "A_down", "E", "E_up", "E_down", "M", "R", "R_up", "R_down", "B", "B_mean"):
        print(f"  {key:<7} {f[key]:.6g}")
    for key in ("Ps", "U", "Pa", "P"):
        if key in f:
            print(f"  {key:<7} {f[key]:.6g}")
    print(f"model: degree-{args.degree} polynomial by GLS, u(delta) = {res.extra['u_delta']:.4g}")
    for d, p in res.polynomial.items():
        coefs = ", ".join(f"{c:.6g}" for c in p["coefficients"])
        print(f"  {d:<5} coefficients (increasing powers of P): {coefs}; max U(P_i) = {p['U_at_targets'].max():.4g}")
    return 0


def cmd_magnify(args) -> int:
    from datasets import read_points
    from methods.magnify import MagnifyInput

    data = MagnifyInput(read_points(args.reference), read_points(args.measured))
    params = {"eta": args.eta}
    if args.method == "offset":
        params["delta"] = args.delta
        params["selection"] = args.selection
    elif args.delta is not None:
        raise InvalidInputError("--delta is a parameter of --method offset")
    res = methods.fit(f"magnify.{args.method}", data, **params)
    if args.plot:
        plot_magnified(data, res, args.plot, args.eta)
    if args.json:
        d = res.to_dict(residuals=not args.no_residuals)
        print(json.dumps(d))
        return 0
    print(f"method       {res.method} ({res.message})")
    print(f"points       {len(res.points)}; largest contouring error {res.form_error:.6g}")
    print(f"continuity   {res.extra['continuity']:.3g} (largest magnified step / (eta x largest measured step))")
    print(f"loops        {res.extra['self_intersections']} self-intersections of the magnified trajectory")
    return 0


def cmd_multilaterate(args) -> int:
    from methods.multilateration import read_csv

    data = read_csv(args.file, args.stations)
    method = args.method if "." in args.method else f"multilateration.{args.method}"
    spec = methods.get(method)
    if spec.family != "multilateration":
        raise InvalidInputError(f"{method} is not a multilateration method; "
                                f"'python -m methods list --family multilateration' lists them")
    res = spec(data, **({"max_iter": args.max_iter} if args.max_iter is not None and "max_iter" in spec.defaults else {}))
    ident = _identify(data, res, args.degree) if args.identify else None
    if args.json:
        d = res.to_dict(residuals=not args.no_residuals)
        d["nominal_points"] = _jsonable(data.points)
        d["stations_given"] = data.known_stations is not None
        if ident is not None:
            d["geometric_errors"] = {"degree": ident.model.degree, "travel": list(ident.model.travel),
                                     "basis": "coefficient of (axis position / travel)^j; E[XYZ]* and T* in mm, "
                                              "E[ABC]*, squareness and R* in rad",
                                     "parameters": ident.as_table(), "residual_rms": ident.residual_rms}
        print(json.dumps(_jsonable(d)))
        return 0 if res.converged else 1
    vol = np.linalg.norm(res.volumetric_errors, axis=1)
    known = data.known_stations is not None
    print(f"method       {res.method} ({res.message})")
    print(f"data         {args.file}: {len(data.stations)} stations, {len(data.points)} points, "
          f"{int(data.mask.sum())} lengths; stations {'given' if known else 'located (step 1)'}")
    print(f"{'station':<10} {'x':>14} {'y':>14} {'z':>14} {'L':>12}")
    for sid, st in zip(res.station_ids, res.stations):
        print(f"{sid:<10} {st[0]:14.6f} {st[1]:14.6f} {st[2]:14.6f} {st[3]:12.6f}")
    print(f"volumetric   largest |error| {vol.max() * 1e3:.3f} um, RMS {np.sqrt(np.mean(vol ** 2)) * 1e3:.3f} um")
    r = res.residuals[np.isfinite(res.residuals)]
    print(f"residuals    RMS {np.sqrt(np.mean(r ** 2)) * 1e3:.4f} um of the lengths")
    for step, c in res.condition_numbers.items():
        print(f"kappa        {step:<16} median {np.median(c['svd']):.3g} (SVD), Theorem 1 lower estimate "
              f"{np.median(c['theorem1']):.3g}: {c['system']}")
    print(f"converged    {'yes' if res.converged else 'NO'}; runtime {res.runtime_s * 1e3:.2f} ms")
    if ident is not None:
        travel = ", ".join(f"{t:g}" for t in ident.model.travel)
        print(f"geometric errors (ISO 230-1 names), coefficients of (position / travel)^j, travels {travel} mm; "
              f"fit residual RMS {ident.residual_rms * 1e3:.3f} um")
        for row in ident.as_table():
            name = row["parameter"]
            linear = (name[0] == "E" and name[1] in "XYZ") or name[0] == "T"
            unit, scale = ("um", 1e3) if linear else ("urad", 1e6)
            print(f"  {row['parameter']:<7} {row['value'] * scale:12.4f} +- {row['u'] * scale:.4f} {unit}")
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


def plot_magnified(data, res, path, eta):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.plot(*data.reference.T, color="0.5", lw=1, label="reference")
    ax.plot(*res.points.T, lw=0.8, label=f"{res.method}, eta = {eta:g}")
    ax.set_aspect("equal")
    ax.legend(fontsize=8)
    ax.set_title(f"continuity {res.extra['continuity']:.2f}, loops {res.extra['self_intersections']}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="python -m methods", description="fitbench fitting methods")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    pl = sub.add_parser("list", help="one line per registered method: id, kind, reference")
    pl.add_argument("--family", help="only this family (e.g. circle)")
    pl.add_argument("--json", action="store_true", help="machine-readable listing with defaults")
    pl.set_defaults(func=cmd_list)
    pf = sub.add_parser("fit", help="fit a file or published data set with one method")
    pf.add_argument("method", metavar="METHOD_ID")
    pf.add_argument("file", metavar="FILE", help="a points file (x, y) or a published data set name")
    pf.add_argument("--param", action="append", metavar="KEY=VALUE", help="method parameter (repeatable)")
    pf.add_argument("--json", action="store_true", help="print the result as one JSON object")
    pf.add_argument("--no-residuals", action="store_true", help="leave the per-point residuals out of --json")
    pf.set_defaults(func=cmd_fit)
    pc = sub.add_parser("circular-test", help="ISO 230-4 evaluation and diagnostics of a CW and a CCW run")
    pc.add_argument("cw", metavar="CW.csv", help="the clockwise run (x, y)")
    pc.add_argument("ccw", metavar="CCW.csv", help="the counter-clockwise run (x, y)")
    pc.add_argument("--nominal-radius", type=float, required=True, metavar="R")
    pc.add_argument("--nominal-center", type=float, nargs=2, metavar=("X", "Y"),
                    help="nominal centre (machine coordinates); needed for F about it and for the diagnostics")
    pc.add_argument("--center", choices=("lsq", "mz"), default="lsq", help="centre for G: least squares or minimum zone")
    pc.add_argument("--feed", type=float, metavar="MM_PER_MIN", help="feed: gives the servo mismatch in ms")
    pc.add_argument("--cyclic-pitch", type=float, metavar="MM", help="ball-screw pitch: estimates the cyclic error")
    pc.add_argument("--json", action="store_true", help="print one JSON object")
    pc.add_argument("--plot", metavar="FILE", help="write the polar plot (PNG or PDF)")
    pc.set_defaults(func=cmd_circular_test)
    pp = sub.add_parser("positioning", help="ISO 230-2 positioning figures and the GLS polynomial model")
    pp.add_argument("file", metavar="FILE", help="long table: target, direction (+/-), run, actual or deviation")
    pp.add_argument("--degree", type=int, default=3, help="degree of the polynomial (default 3)")
    g = pp.add_mutually_exclusive_group()
    g.add_argument("--instrument-u", type=float, metavar="U", help="standard uncertainty of the instrument, u(delta)")
    g.add_argument("--mpe", type=float, metavar="MPE", help="the instrument's maximum permissible error (rectangular)")
    pp.add_argument("--standard", choices=("iso230-2:2014", "iso230-2:1988", "vdi3441"), default="iso230-2:2014")
    pp.add_argument("--json", action="store_true", help="print one JSON object")
    pp.add_argument("--plot", metavar="FILE", help="write the plot (figures 2 and 3 of the paper)")
    pp.set_defaults(func=cmd_positioning)
    pm = sub.add_parser("magnify", help="magnified contouring-error trajectory (nearest or contour-parallel offset)")
    pm.add_argument("reference", metavar="REFERENCE.csv", help="reference polyline (x, y; arcs as fine polylines)")
    pm.add_argument("measured", metavar="MEASURED.csv", help="measured trajectory (x, y), in order")
    pm.add_argument("--eta", type=float, required=True, metavar="E", help="magnification")
    pm.add_argument("--delta", type=float, metavar="D", help="offset distance (> the largest error; default twice it)")
    pm.add_argument("--method", choices=("offset", "nearest"), default="offset")
    pm.add_argument("--selection", choices=("same_side", "nearest_of_both"), default="same_side",
                    help="offset method: the offset on the point's side, or the paper's printed step (2)")
    pm.add_argument("--json", action="store_true", help="print one JSON object (points: the magnified trajectory)")
    pm.add_argument("--no-residuals", action="store_true", help="leave the per-point errors out of --json")
    pm.add_argument("--plot", metavar="FILE", help="write a plot")
    pm.set_defaults(func=cmd_magnify)
    pu = sub.add_parser("multilaterate", help="stations, actual points and volumetric errors from tracking-interferometer lengths")
    pu.add_argument("file", metavar="MEASUREMENTS.csv", help="columns station, x, y, z (nominal point), length")
    pu.add_argument("--method", default="case_a_distance", metavar="ID",
                    help="multilateration method id or its short name (default case_a_distance, the paper's eq. 7)")
    pu.add_argument("--stations", metavar="FILE", help="known stations: columns station, x, y, z, L (skips step 1)")
    pu.add_argument("--max-iter", type=int, metavar="N", help="iteration limit of the iterative methods")
    pu.add_argument("--identify", action="store_true",
                    help="also identify the 18 component and 3 squareness errors (needs columns xp, yp, zp)")
    pu.add_argument("--degree", type=int, default=3, help="polynomial degree of the component errors (default 3)")
    pu.add_argument("--json", action="store_true", help="print one JSON object")
    pu.add_argument("--no-residuals", action="store_true", help="leave the length residuals out of --json")
    pu.set_defaults(func=cmd_multilaterate)
    from methods.roundness import cli as roundness_cli
    roundness_cli.add_parser(sub)
    return p


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
        return args.func(args)
    except InvalidInputError as exc:
        print(f"fitbench: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BrokenPipeError:
        return 0
