"""``fitbench fit METHOD_ID FILE``: one method on a points file or a published data set (a table, JSON, a quick-look
plot); ``--param KEY=VALUE`` takes the type of the parameter's default (:func:`parse_value`)."""
from __future__ import annotations

import json
import math

import numpy as np

import fitbench.cli.options as cli_options
import methods
from fitbench.cli.guards import check_outputs, run_method, written_files
from fitbench.cli.options import add_reader_options, check_plot_path, read_profile_args, save_figure
from fitbench.cli.options import quantity
from fitbench.cli.roundness import limacon_warning
from methods import InvalidInputError
from methods.units import canonical


def add_parser(sub):
    pf = sub.add_parser("fit", help="fit a file or published data set with one method")
    pf.add_argument("method", metavar="METHOD_ID", help="the method, e.g. circle.gauss_newton ('fitbench list' shows "
                    "every method with what it minimises)")
    pf.add_argument("file", metavar="FILE", help="a points file (x, y, or angle + radial deviation) or a published "
                                                "data set name")
    pf.add_argument("--param", action="append", metavar="KEY=VALUE", help="method parameter (repeatable)")
    pf.add_argument("--nominal-radius", type=quantity("--nominal-radius"), metavar="R_MM",
                    help="angle + radial-deviation files: the radius the deviations are about (mm, or with its unit: "
                         "150mm; default: the deviations alone)")
    add_reader_options(pf, polar=True, printed="mm")
    pf.add_argument("--json", action="store_true", help="print the result as one JSON object (mm, rad; see its "
                    "'units')")
    pf.add_argument("--no-residuals", action="store_true", help="leave the per-point residuals out of --json")
    pf.add_argument("--verbose", action="store_true",
                    help="also print the solver's message on a converged fit (its stopping and optimality tests; "
                         "always in --json as 'message')")
    pf.add_argument("--plot", metavar="FILE", help="write a quick look: points, fitted curve, residuals (.png, .pdf, .svg)")
    pf.set_defaults(func=run)


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


def _axis_label(label: str, axes: tuple) -> str:
    """A result's line label with the coordinates named as the file named them (``center x`` -> ``center z``
    for a file read from its x and z columns)."""
    head, _, last = label.rpartition(" ")
    if head and last in ("x", "y"):
        return f"{head} {axes[0] if last == 'x' else axes[1]}"
    return label


def run(args) -> int:
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
    check_outputs([args.file], [("--plot", args.plot, "plot")])
    source, points, unit, notes, axes = read_profile_args(args)
    result = run_method(spec, points, **params)
    notes = [*notes, *(n for n in (result.extra or {}).get("notes", []) if isinstance(n, str))]  # the result's own
    offcentre = limacon_warning(points, getattr(result, "form_error", None), notes,   # as roundness warns
                                args.nominal_radius)
    if offcentre:
        cli_options.warn(offcentre)
    said = cli_options.said_warnings()   # printed before the figures, written into the JSON
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
        d["warnings"] = list(dict.fromkeys([*d.get("warnings", []), *said]))
        d["files_written"] = written_files()
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
