"""``fitbench roundness FILE``: an ISO 12181 roundness report (table, JSON, polar and spectrum plot)."""
from __future__ import annotations

import fitbench.cli.options as cli_options
from fitbench.cli.guards import check_outputs, written_files

import json
import warnings

import numpy as np

from methods.units import JSON_UNITS, canonical

from methods.roundness.evaluation import REFERENCE_NAMES
from methods.roundness.filter import UndersampledWarning, parse_cutoff
from fitbench.cli.options import (add_reader_options, add_report_option, add_test_identity_options, header_line,
                                  ROUNDNESS_LIMIT_MM, add_tolerance_option, check_plot_path, parse_tolerances, test_conditions, read_profile_args, save_figure, Tolerances, tolerance_text, verdict, verdict_lines,
                                  verdict_title, warn, warn_bare_tolerances, write_report)
from fitbench.cli.options import quantity


def add_parser(subparsers):
    p = subparsers.add_parser("roundness", help="ISO 12181 roundness: filtered profile, RONt/p/v/q about the "
                                                "reference circles, harmonic spectrum")
    p.add_argument("file", metavar="FILE", help="a profile file (x, y, or angle + radial deviation as roundness "
                                                "instruments export it) or a published data set name")
    p.add_argument("--cutoff", default="50", metavar="UPR",
                   help="Gaussian filter cut-off in undulations per revolution: none, 15, 50 (default), 150, 500, "
                        "1500 or any positive value (ISO 16610-21)")
    p.add_argument("--reference", choices=("lsci", "mzci", "mici", "mcci", "all"), default="all",
                   help="reference circle(s) (default: all four)")
    p.add_argument("--nominal-radius", type=quantity("--nominal-radius"), metavar="R_MM",
                   help="angle + radial-deviation files: the radius the deviations are about (mm, or with its unit: 10mm; default: the "
                        "deviations alone, as an instrument's limaçon evaluation)")
    add_reader_options(p, polar=True)
    p.add_argument("--json", action="store_true", help="print one JSON object (lengths in mm)")
    p.add_argument("--plot", metavar="PNG", help="write the polar plot and the harmonic spectrum")
    add_tolerance_option(p, "RONt, RONp, RONv, RONq: the verdict is judged about the minimum zone circle (MZCI, the "
                            "reference of ISO 12181-2 and ISO 1101's tolerance zone) or the one --reference chooses; "
                            "the other circles' figures are shown for information")
    add_report_option(p)
    add_test_identity_options(p)
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    import methods
    from fitbench.plots.roundness import plot

    cutoff = parse_cutoff(args.cutoff, "--cutoff")
    plot_path = check_plot_path(args.plot)
    report_path = check_plot_path(args.report, "--report")
    check_outputs([args.file], [("--plot", args.plot, "plot"), ("--report", args.report, "test report")])
    tolerances = parse_tolerances(args.tolerance, ("RONt", "RONp", "RONv", "RONq"))
    source, points, unit, notes, axes = read_profile_args(args, limit_mm=ROUNDNESS_LIMIT_MM, refuse_flat=True,
                                                        min_arc_deg=360.0)   # a closed profile
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UndersampledWarning)
        res = methods.fit("roundness.iso12181", points, cutoff_upr=cutoff, reference=args.reference)
    for w in caught:
        if issubclass(w.category, UndersampledWarning):
            warn(str(w.message))
    offcentre = limacon_warning(points, res.form_error, notes, args.nominal_radius)
    if offcentre:
        warn(offcentre)
    check = roundness_verdict(res.references, tolerances, chosen=args.reference != "all")
    if check:   # the figures the verdict judges: about its reference circle
        warn_bare_tolerances(tolerances, res.references[check["reference"]])
    said = cli_options.said_warnings()   # printed before the figures, written into the report and the JSON
    if plot_path:
        plot(res, plot_path, title=f"{source}{verdict_title(check)}", save=lambda fig, path: save_figure(fig, path, dpi=110))
    lines = [header_line("roundness", unit, "; centre and radius in mm")]
    lines += [f"note: {n}" for n in notes] + [report(res, source, axes)] + roundness_verdict_lines(check)
    if report_path:
        write_report(report_path, f"ISO 12181 roundness{': ' + args.machine if args.machine else ''}",
                     [f"date         {args.date or '-'}", *lines], lambda sub: plot(res, None, title=source, into=sub),
                     aspect=5.4 / 12)
    if args.json:
        d = res.to_dict(residuals=False)
        d["spectrum"] = {k: np.asarray(v).tolist() for k, v in res.spectrum.items()}
        if check:
            d["verdict"] = check
        d.update(source=source, input_unit=unit, notes=notes,
                 # the keys every command's JSON has (length, angle, input_unit), and the older lengths/angles
                 units={**JSON_UNITS, "input_unit": canonical(unit), "lengths": "mm", "angles": "rad",
                        "cutoff_upr": "undulations per revolution",
                        "spectrum.amplitude": "mm", "spectrum.phase": "rad"})
        d.pop("extra", None)
        d["warnings"] = list(dict.fromkeys([*d.get("warnings", []), *said]))
        d["details"] = {"conditions": test_conditions(args, files=[source])}
        d["files_written"] = written_files()
        cli_options.print_json(json.dumps(d))
        return 0 if res.converged else 1
    print("\n".join(lines))
    return 0 if res.converged else 1


#: deviations alone are evaluated about a circle of unknown radius R (the limaçon approximation, ISO 12181-1:
#: valid for an eccentricity e small against R): the radius from the spindle axis of a circle e off it is
#: R + e cos(θ - φ) - e² sin²(θ - φ) / (2R) + ..., and the limaçon drops that last term, a second harmonic of
#: peak-to-valley e² / (2R). An eccentricity whose term exceeds LIMACON_SHARE of RONt for some part radius above
#: LIMACON_MIN_RADIUS_MM is warned about.
LIMACON_SHARE = 0.05
LIMACON_MIN_RADIUS_MM = 1.0


def limacon_problem(eccentricity_mm: float, form_error_mm: float) -> str | None:
    """What the limaçon evaluation of deviations alone may get wrong for a profile ``eccentricity_mm`` off the
    centre it was measured about (the least-squares centre: the first harmonic of the deviations), or None when
    e² / (2R) stays below :data:`LIMACON_SHARE` of RONt for every radius R above :data:`LIMACON_MIN_RADIUS_MM`."""
    e, form = float(eccentricity_mm), float(form_error_mm)
    if not (np.isfinite(e) and np.isfinite(form) and form > 0):
        return None
    below = e ** 2 / (2.0 * LIMACON_SHARE * form)    # the radius below which e²/(2R) > LIMACON_SHARE x RONt
    if not below > LIMACON_MIN_RADIUS_MM:
        return None
    return (f"the profile is {e * 1e3:.4g} µm off centre ({e / form:.3g} x RONt {form * 1e3:.4g} µm; the first "
            f"harmonic of the deviations): evaluated without the part's radius R (the limaçon approximation), the "
            f"form figures carry a false 2 UPR term of up to e²/(2R) = {e * e * 1e3 / 2:.4g} µm·mm / R, more than "
            f"{LIMACON_SHARE * 100:g} % of RONt for R below {below:.4g} mm; give --nominal-radius R_MM (the radius the "
            "deviations are about) or centre the part")


def limacon_warning(points, form_error_mm, notes, nominal_radius) -> str | None:
    """:func:`limacon_problem` of a profile read from angle + radial deviations without its radius (the reader's note
    says so; ``points`` placed about (0, 0), mm), for ``fitbench roundness`` and ``fitbench fit``: the eccentricity is
    the first harmonic of the radii (linear least squares on 1, cos θ, sin θ: the limaçon's least-squares centre,
    ISO 12181-1), ``form_error_mm`` the command's form figure; None for any other input."""
    if nominal_radius is not None or form_error_mm is None or not any("without a nominal radius" in n for n in notes):
        return None
    p = np.asarray(points, dtype=float)
    theta, r = np.arctan2(p[:, 1], p[:, 0]), np.hypot(p[:, 0], p[:, 1])
    basis = np.column_stack([np.ones_like(theta), np.cos(theta), np.sin(theta)])
    coef = np.linalg.lstsq(basis, r - r.mean(), rcond=None)[0]
    return limacon_problem(float(np.hypot(coef[1], coef[2])), float(form_error_mm))


#: the reference circle a roundness tolerance is checked with unless the user chooses one: ISO 1101 defines the
#: roundness tolerance zone as two concentric circles t apart, i.e. the minimum zone, which is also ISO 12181-2's
#: default reference (the MZCI)
DEFAULT_VERDICT_REFERENCE = "mzci"


def roundness_verdict(references: dict, tolerances: dict, chosen: bool = False) -> dict | None:
    """PASS/FAIL of the figures about one reference circle (``verdict``'s checks and overall): the one ``--reference``
    chose (``chosen``), else the MZCI (:data:`DEFAULT_VERDICT_REFERENCE`); with ``reference`` naming it and
    ``information`` holding the same checks about the other circles shown, which do not decide the verdict. A part
    whose minimum-zone RONt was 4.708 um for a 5 um tolerance read FAIL overall, because its LSCI RONt (5.051 um)
    was also checked."""
    if not tolerances:
        return None
    kind = next(iter(references)) if chosen else DEFAULT_VERDICT_REFERENCE
    r = references[kind]
    given = {f"{name} {k.upper()}": tolerances.given(name) if isinstance(tolerances, Tolerances) else None
             for k in references for name in tolerances}
    check = verdict({f"{name} {kind.upper()}": r[name] for name in tolerances},
                    {f"{name} {kind.upper()}": tol for name, tol in tolerances.items()}, given)
    others = verdict({f"{name} {k.upper()}": o[name] for k, o in references.items() if k != kind for name in tolerances},
                     {f"{name} {k.upper()}": tol for k in references if k != kind for name, tol in tolerances.items()},
                     given)
    check["reference"] = kind
    check["reference_basis"] = ("chosen with --reference" if chosen else
                                "minimum zone, the default of ISO 12181-2 and the tolerance zone of ISO 1101")
    check["information"] = others["checks"] if others else []
    return check


def roundness_verdict_lines(v: dict | None) -> list[str]:
    """:func:`verdict_lines` naming the reference that decides, then the other circles' checks for information."""
    if not v:
        return []
    lines = verdict_lines(v)
    lines[0] += f" (about the {v['reference'].upper()}: {v['reference_basis']})"
    if v["information"]:
        lines.append("  for information (not part of the verdict):")
        lines += [f"  {c['figure']:<12} {c['value_mm'] * 1e3:10.3f} µm  {tolerance_text(c)}  "
                  f"{'within' if c['result'] == 'PASS' else 'beyond'}" for c in v["information"]]
    return lines


def report(res, source: str, axes: tuple = ("x", "y")) -> str:
    """The instrument-style table: one row per reference circle, lengths in µm (centre and radius in mm);
    ``axes`` names the two coordinates as the file named them."""
    cut = "none (unfiltered)" if res.cutoff_upr is None else f"{res.cutoff_upr:g} UPR Gaussian (ISO 16610-21)"
    lines = [f"data          {source} ({res.n_points} points)",
             f"filter        {cut}" + ("" if res.cutoff_upr is None else f"; {res.filter_path}"),
             f"raw LSCI      centre ({res.raw_lsci['center'][0]:.6f}, {res.raw_lsci['center'][1]:.6f}) mm, "
             f"radius {res.raw_lsci['radius']:.6f} mm (deviations filtered about it)", ""]
    names = ["RONt [µm]", "RONp [µm]", "RONv [µm]", "RONq [µm]", f"centre {axes[0]} [mm]", f"centre {axes[1]} [mm]",
             "radius [mm]"]
    rows = [[f"{r[p] * 1e3:.4f}" for p in ("RONt", "RONp", "RONv", "RONq")]
            + [f"{r['center'][0]:.6f}", f"{r['center'][1]:.6f}", f"{r['radius']:.6f}"] for r in res.references.values()]
    # each column as wide as its widest entry, two spaces between columns: numbers never touch (a radius
    # about 1e6 x the deviations' span without a nominal radius is 12+ digits wide)
    widths = [max(len(n), *(len(row[j]) for row in rows)) for j, n in enumerate(names)]
    label = max(38, *(len(REFERENCE_NAMES[k]) for k in res.references))
    head = f"{'reference':<{label}}  " + "  ".join(f"{n:>{w}}" for n, w in zip(names, widths)) + "  status"
    lines += [head, "-" * len(head)]
    for (kind, r), row in zip(res.references.items(), rows):
        lines.append(f"{REFERENCE_NAMES[kind]:<{label}}  " + "  ".join(f"{v:>{w}}" for v, w in zip(row, widths)) + "  "
                     + ("ok" if r["converged"] else f"NOT CERTIFIED ({r['message']})"))
    lobes = ", ".join(f"{d['upr']} UPR {d['amplitude'] * 1e3:.4f} µm" for d in res.dominant_lobes)
    lines += ["", f"dominant lobes (amplitude of the filtered deviation): {lobes or '-'}"]
    lines += [f"warning: {w}" for w in res.warnings]
    return "\n".join(lines)


