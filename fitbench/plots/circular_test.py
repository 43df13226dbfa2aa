"""Report of one circular test: the ISO 230-4 figures, the diagnostics table ranked by contribution, and
a polar plot read like ballbar software's: radial deviation magnified about the nominal circle with a
scale in µm per division, the G band (minimum and maximum circles), start and direction markers of both
runs, a test-conditions panel and the diagnostics ranked by their contribution to the circular deviation."""
from __future__ import annotations

import re
import textwrap

import numpy as np

from fitbench.plots import report_figure, ring_label

LABELS = {"squareness": "squareness", "scale_mismatch": "scale mismatch X-Y", "servo_mismatch": "servo mismatch X-Y",
          "backlash_x": "backlash X", "backlash_y": "backlash Y", "reversal_spike_x": "reversal spike X",
          "reversal_spike_y": "reversal spike Y", "cyclic_error": "cyclic error"}
#: what the sign of each diagnostic means (X, Y: the plane's first and second axes; angles about the centre from +X
#: towards +Y), by the model of methods/circular_test/diagnostics.py (checked on a hand-built path in
#: tests/test_circular_test_operator.py); in the JSON as each diagnostic's ``sign``
SIGNS = {
    "squareness": "positive: the angle between the +X and +Y axes is less than 90° by the value (the Y axis leans "
                  "towards +X); negative: more than 90°",
    "scale_mismatch": "X scale error minus Y's: positive: X travels further than Y for the same command (the path is "
                      "longer along X); negative: Y travels further",
    "servo_mismatch": "X's following error minus Y's (a lag time with the feed, else a lag length): positive: X lags "
                      "behind Y; negative: Y lags behind X",
    "backlash_x": "positive: lost motion: X falls short of its command by half the value in its direction of travel, "
                  "a step of the value at its reversals (0° and 180°); negative: overshoot",
    "backlash_y": "positive: lost motion: Y falls short of its command by half the value in its direction of travel, "
                  "a step of the value at its reversals (90° and 270°); negative: overshoot",
    "reversal_spike_x": "positive: X sticks at its reversals (0° and 180°): a spike of the value outwards from the "
                        "circle, decaying over the spike decay angle; negative: inwards (an overshoot)",
    "reversal_spike_y": "positive: Y sticks at its reversals (90° and 270°): a spike of the value outwards from the "
                        "circle, decaying over the spike decay angle; negative: inwards (an overshoot)",
    "cyclic_error": "an amplitude (no sign): the mean of the X and Y cyclic errors' amplitudes"}
#: the same for the set-up (``details.diagnostics_model`` of the JSON)
MODEL_SIGNS = {"centre_offset": "the measured path's centre minus the nominal centre, (X, Y)",
               "radius_offset": "each run's mean radius minus the nominal radius: positive: larger"}
#: the meaning of a positive and of a negative value in a few words (the text output's last column)
SHORT = {"squareness": ("angle X-Y below 90°", "angle X-Y above 90°"),
         "scale_mismatch": ("X travels further", "Y travels further"),
         "servo_mismatch": ("X lags behind Y", "Y lags behind X"),
         "backlash_x": ("lost motion", "overshoot"), "backlash_y": ("lost motion", "overshoot"),
         "reversal_spike_x": ("outward spike", "inward spike"), "reversal_spike_y": ("outward spike", "inward spike")}


def for_plane(text: str, plane: str | None) -> str:
    """``text`` with X and Y (the first and second axes) named as the plane names them ('zx': Z and X)."""
    a, b = (plane or "xy").upper()[:2] if plane and len(plane) >= 2 else ("X", "Y")
    return re.sub(r"\b([XY])\b", lambda m: a if m.group(1) == "X" else b, text)


def meaning(name: str, value, u=None, plane: str | None = None, contribution: float | None = None) -> str:
    """What ``value`` of the diagnostic ``name`` means, in a few words; 'none at this resolution' when the value
    prints as 0.000 in its unit or its ``contribution`` to the circle as 0.00 µm (a sign of nm-level rounding
    noise is no finding); '' when its sign is not resolved (within 2 u of 0)."""
    if name not in SHORT or value is None:
        return ""
    if round(value, 3) == 0 or (contribution is not None and round(contribution, 2) == 0):
        return "none at this resolution"
    if u is not None and abs(value) <= 2 * u:
        return ""
    return for_plane(SHORT[name][0 if value > 0 else 1], plane)


#: human unit of each diagnostics unit, and the factor to the JSON's (mm, rad, s, ratio)
HUMAN_UNIT = {"um": "µm", "urad": "µrad", "um/m": "µm/m", "ms": "ms"}
TO_JSON = {"um": (1e-3, "mm"), "urad": (1e-6, "rad"), "um/m": (1e-6, "1 (m/m)"), "ms": (1e-3, "s")}


def contribution_um(name: str, item: dict, R_mm: float, feed_mm_min: float | None) -> float | None:
    """Peak-to-valley of the radial deviation a source causes on the circle (µm): the ranking of the report.
    Squareness a and scale mismatch s give R a / 2 and R s / 2 amplitude (peak-to-valley R a, R s); a servo
    mismatch d = l_x - l_y of the axes' lag lengths (given in µm, or as tau in ms with the feed v: d = v tau) gives
    (d / 2) sin 2 theta (``methods.circular_test.diagnostics``), peak-to-valley |d|; backlash b of an axis a step of
    b; a spike or cyclic error of amplitude h about h (spike) and 2 h (cyclic)."""
    v = item.get("value")
    if v is None:
        return None
    if name == "squareness":
        return abs(v) * 1e-6 * R_mm * 1e3
    if name == "scale_mismatch":
        return abs(v) * 1e-6 * R_mm * 1e3
    if name == "servo_mismatch":
        if item["unit"] == "ms" and feed_mm_min:
            return abs(v) * 1e-3 * (feed_mm_min / 60.0) * 1e3
        return abs(v)   # the lag length difference itself
    if name == "cyclic_error":
        return 2 * abs(v)
    return abs(v)


def _label(name: str, plane: str | None) -> str:
    """The label with the plane's axis letters (X, Y for 'xy'; Z, X for 'zx'; Y, Z for 'yz')."""
    return for_plane(LABELS[name], plane)


def ranked(dg: dict, R_mm: float, feed_mm_min=None, plane: str | None = None, names: bool = False) -> list:
    """[(label, item, contribution µm or None)] sorted by contribution, the largest first (with ``names``, the
    diagnostic's name first in each tuple)."""
    rows = [(n, _label(n, plane), dg[n], contribution_um(n, dg[n], R_mm, feed_mm_min)) for n in LABELS if n in dg]
    rows.sort(key=lambda r: (r[3] is None, -(r[3] or 0.0)))
    return rows if names else [r[1:] for r in rows]


def diagnostics_json(dg: dict, plane: str | None = None) -> dict:
    """The diagnostics in the JSON's units (mm, rad, s, ratio), each with what its sign means (``sign``)."""
    out = {}
    for k, item in dg.items():
        if k.startswith("_"):
            continue
        f, unit = TO_JSON[item["unit"]]
        d = {"value": None if item["value"] is None else item["value"] * f, "unit": unit,
             "u": None if item["u"] is None else item["u"] * f, "sign": for_plane(SIGNS[k], plane)}
        if "note" in item:
            d["note"] = item["note"]
        out[k] = d
    return out


def model_json(model: dict, plane: str | None = None) -> dict:
    """``diagnose``'s ``_model`` in the JSON's units: centre and radius offsets and the residual RMS in mm, the spike
    decay angle in rad (the API's dict names them in µm and degrees), with the signs of the offsets."""
    out = {"centre_offset": [v * 1e-3 for v in model["centre_offset_um"]],
           "radius_offset": {k: v * 1e-3 for k, v in model["radius_offset_um"].items()},
           "spike_decay": float(np.radians(model["spike_decay_deg"])),
           "residual_rms": model["residual_rms_um"] * 1e-3}
    out.update({k: v for k, v in model.items()
                if k not in ("centre_offset_um", "radius_offset_um", "spike_decay_deg", "residual_rms_um")})
    out["signs"] = {k: for_plane(v, plane) for k, v in MODEL_SIGNS.items()}
    return out


def _signed(value: float, digits: int = 2) -> str:
    """``value`` with its sign to ``digits`` decimals; a value that rounds to zero prints as +0.00, never -0.00."""
    return f"{(value if round(value, digits) != 0 else 0.0):+.{digits}f}"


def text(ev, dg: dict | None) -> str:
    """The evaluation ``ev`` (a CircularTestFit) and the diagnostics ``dg`` as a person reads them (µm)."""
    um = 1e3
    arc = ev.arc_deg
    partial = ev.partial_arc
    lines = ["ISO 230-4 circular test" + (f" (partial arc: CW {arc.get('cw', 0):.1f}°, CCW {arc.get('ccw', 0):.1f}°)"
                                          if partial else ""),
             f"  nominal radius          {ev.nominal_radius:.6g} mm",
             f"  centre ({ev.center_kind})          ({ev.center[0]:.6f}, {ev.center[1]:.6f}) mm",
             f"  G  CW / CCW             {ev.figures['G_cw'] * um:.2f} / {ev.figures['G_ccw'] * um:.2f} µm",
             f"  G(b)                    {ev.figures['G_b'] * um:.2f} µm",
             f"  H (1996)                {ev.figures['H'] * um:.2f} µm{' (over the common arc)' if partial else ''}",
             f"  F max / F min           {ev.figures['F_max'] * um:+.2f} / {ev.figures['F_min'] * um:+.2f} µm ({ev.F_about})",
             f"  mean radial deviation   {_signed(ev.figures['mean_radial_deviation'] * um)} µm"]
    if dg:
        feed = ev.conditions.get("feed_mm_min")
        lines += ["diagnostics (least squares on the error signatures; value +- standard uncertainty u), ranked by their",
                  "  contribution to the circular deviation (peak-to-valley); last: what a sign beyond 2 u means"]
        plane = ev.conditions.get("plane")
        for name, label, item, contrib in ranked(dg, ev.nominal_radius, feed, plane, names=True):
            if item["value"] is None:
                lines.append(f"  {label:<22}  {item.get('note', 'not estimated')}")
            else:
                unit = HUMAN_UNIT.get(item["unit"], item["unit"])
                lines.append((f"  {label:<22}  {_value_u(item['value'], item['u'], unit)} {unit:<5}  "
                              f"contribution {contrib:7.2f} µm  {meaning(name, item['value'], item['u'], plane, contrib)}").rstrip())
        m = dg["_model"]
        fit = f"fit converged in {m['iterations']} iterations" if m["converged"] else "fit NOT converged (below)"
        lines.append(f"  residual RMS {m['residual_rms_um']:.2f} µm; spike decay {m['spike_decay_deg']:.2f}°; {fit}")
        if not m["converged"]:
            lines.append(f"  {m['message']}; the values above are its last iterate's")
    return "\n".join(lines)


def _value_u(value: float, u: float, unit: str) -> str:
    """``value +- u`` to 3 decimals (0.001 µm, µrad, µm/m: below any ballbar's resolution, where a value that prints
    as 0.000 means nothing, :func:`meaning`); a time (ms) to the first significant digit of a smaller u (GUM 7.2.6):
    0.001 ms is not below what the servo-mismatch fit resolves (a 2 ms lag with u = 0.3 µs read '+- 0.000 ms')."""
    d = 3
    if unit == "ms" and np.isfinite(u) and 0 < abs(u) < 0.0005:
        d = int(min(9, -np.floor(np.log10(abs(u)))))
    v = round(float(value), d) + 0.0                           # + 0.0: no "-0.000"
    return f"{v:+10.{d}f} +- {float(u):.{d}f}"


def _nice_division(span_um: float) -> float:
    """A 1-2-5 step (µm) so that the span covers about 4 divisions."""
    raw = max(span_um / 4.0, 1e-6)
    exp = np.floor(np.log10(raw))
    for m in (1, 2, 5, 10):
        if m * 10 ** exp >= raw:
            return float(m * 10 ** exp)
    return float(10 ** (exp + 1))


#: the figure's size (inches): the report shows it about 800 px wide, where 8.5 pt text is about 10 px high
FIGSIZE = (9.0, 6.4)
#: smallest font (pt) of any text of the figure, and the table's font
MIN_FONT_PT = 8.5


def _num(v: float, u: float | None = None, signed: bool = False) -> str:
    """``v`` to the decimal of the first significant digit of its uncertainty ``u`` (0 to 3 decimals);
    without ``u`` one decimal (0.1 µm, the resolution a ballbar reports)."""
    d = 1 if not u or not np.isfinite(u) else int(np.clip(-np.floor(np.log10(abs(u))), 0, 3))
    v = round(float(v), d) + 0.0                               # + 0.0: no "-0.0"
    return f"{v:+.{d}f}" if signed else f"{v:.{d}f}"


def _table_rows(ev, cond: dict, R: float, div: float, diagnostics) -> list:
    """The panel as rows: ('head', text) or ('row', label, value, extra) with a unit on every number."""
    um = 1e3
    arc = ev.arc_deg
    centre = cond.get("nominal_center_mm") or cond.get("nominal_center")
    feed = cond.get("feed_mm_min")
    f = ev.figures
    rows = [("head", "Test conditions", "", ""),
            ("row", "machine", textwrap.shorten(str(cond.get("machine") or "-"), 36, placeholder=" ..."), ""),
            ("row", "date", str(cond.get("date") or "-"), ""),
            ("row", "plane", str(cond.get("plane") or "xy").upper(), ""),
            ("row", "radius", f"{R:g} mm", ""),
            ("row", "centre", "(" + ", ".join(f"{v:g}" for v in centre) + ") mm" if centre else "-", ""),
            ("row", "feed", f"{feed:g} mm/min" if feed else "-", ""),
            ("row", "arc CW / CCW", f"{arc.get('cw', 360):.0f}° / {arc.get('ccw', 360):.0f}°", ""),
            ("row", "scale", f"{div:g} µm/div", ""),
            ("head", "Results (ISO 230-4)", "", ""),
            ("row", "G CW / CCW", f"{_num(f['G_cw'] * um)} / {_num(f['G_ccw'] * um)} µm", ""),
            ("row", "G(b)", f"{_num(f['G_b'] * um)} µm", ""),
            ("row", "H", f"{_num(f['H'] * um)} µm", ""),
            ("row", "F max / min", f"{_num(f['F_max'] * um, signed=True)} / {_num(f['F_min'] * um, signed=True)} µm", "")]
    if diagnostics:
        rows.append(("head", "Diagnostics (ranked)", "value", "contribution"))
        if not diagnostics["_model"]["converged"]:
            rows.append(("row", "least-squares fit", "NOT converged", ""))
        for label, item, contrib in ranked(diagnostics, R, feed, cond.get("plane")):
            if item["value"] is None:
                rows.append(("row", label, "n/a", ""))
            else:
                unit = HUMAN_UNIT.get(item["unit"], item["unit"])
                rows.append(("row", label, f"{_num(item['value'], item.get('u'), signed=True)} {unit}",
                             f"{contrib:.1f} µm"))
    return rows


def _draw_table(fig, rows: list, left: float, right: float, top: float, bottom: float) -> list:
    """The rows as a three-column table in the figure's box [left, right] x [bottom, top] (figure
    fractions): labels left-aligned, values and contributions right-aligned, a rule under each heading.
    The font is MIN_FONT_PT + 0.5 unless the rows would not fit the box's height. Returns the texts."""
    import matplotlib.transforms as mtrans
    from matplotlib.lines import Line2D
    height_pt = (top - bottom) * fig.bbox.height / fig.dpi * 72
    n_gap = sum(1 for r in rows[1:] if r[0] == "head")
    size = min(MIN_FONT_PT + 0.5, height_pt / (1.45 * (len(rows) + 0.6 * n_gap)))
    step = 1.45 * size
    x_value, x_extra = left + 0.72 * (right - left), right
    out, y = [], 0.0
    for i, (kind, label, value, extra) in enumerate(rows):
        if kind == "head" and i:
            y += 0.6 * step
        tr = fig.transSubfigure + mtrans.ScaledTranslation(0, -y / 72, fig.dpi_scale_trans)
        weight = "bold" if kind == "head" else "normal"
        colour = "0.3" if kind == "head" else "k"
        out.append(fig.text(left, top, label, transform=tr, fontsize=size, fontweight=weight, va="top", ha="left"))
        if value:
            out.append(fig.text(x_value if extra else right, top, value, transform=tr, fontsize=size, va="top",
                                ha="right", color=colour if kind == "head" else "k"))
        if extra:
            out.append(fig.text(x_extra, top, extra, transform=tr, fontsize=size, va="top", ha="right",
                                color=colour if kind == "head" else "k"))
        if kind == "head":
            rule = fig.transSubfigure + mtrans.ScaledTranslation(0, -(y + 1.2 * size) / 72, fig.dpi_scale_trans)
            fig.add_artist(Line2D([left, right], [top, top], transform=rule, color="0.6", lw=0.6))
        y += step
    return out


def polar_plot(cw, ccw, ev, path, title: str = "", *, diagnostics=None, conditions=None, save=None, into=None):
    """Both runs as radial deviation (µm) about the evaluation centre, drawn on a polar grid whose
    rings are a fixed number of µm apart (the scale is printed: µm per division); the nominal circle is
    the ring 0; the G band (min and max radius of both runs) shaded; start (o) and direction (arrow)
    markers; beside it a table of the test conditions, the ISO 230-4 figures and the ranked diagnostics,
    every number with its unit, and the legend below the plot. Every text is at least MIN_FONT_PT (about
    10 px with the figure 800 px wide). Returns the figure's scale dict {'um_per_division', 'divisions',
    'figure_text'}."""
    with report_figure(path, dpi=120, save=save, into=into, figsize=FIGSIZE) as fig:
        c = ev.center
        R = ev.nominal_radius
        cond = dict(ev.conditions)
        cond.update(conditions or {})
        runs = []
        for pts, label, colour in ((cw, "CW (G02)", "tab:blue"), (ccw, "CCW (G03)", "tab:red")):
            pts = np.asarray(pts, float)
            ang = np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0])
            dev_um = (np.hypot(pts[:, 0] - c[0], pts[:, 1] - c[1]) - R) * 1e3
            runs.append((ang, dev_um, label, colour))
        lo = min(d.min() for _, d, _, _ in runs)
        hi = max(d.max() for _, d, _, _ in runs)
        div = _nice_division(max(hi - lo, 1e-3))
        # rings: from below the smallest to above the largest deviation, in whole divisions
        r0 = np.floor(lo / div) - 1
        n_div = int(np.ceil(hi / div) - r0 + 1)
        base = r0 * div                                        # the radius drawn at the plot centre (µm)
        ax = fig.add_axes([0.045, 0.235, 0.5, 0.6], projection="polar")
        ring = np.linspace(0, 2 * np.pi, 721)
        ax.fill_between(ring, lo - base, hi - base, color="0.88", alpha=0.5, lw=0)
        ax.plot(ring, np.full_like(ring, lo - base), color="0.55", lw=0.8)
        ax.plot(ring, np.full_like(ring, hi - base), color="0.55", lw=0.8,
                label=f"G band, min/max circles: {_num(hi - lo)} µm")
        ax.plot(ring, np.full_like(ring, -base), color="0.2", lw=1.2, ls="--",
                label=f"nominal circle R = {R:g} mm (0 µm)")
        outer = n_div * div
        for i, (ang, dev, label, colour) in enumerate(runs):
            ax.plot(ang, dev - base, lw=0.8, color=colour, label=label)
            # start marker on the trace, and an arrow just outside the trace along the direction of travel
            ax.plot(ang[0], dev[0] - base, "o", color=colour, ms=9, mfc="white", mec=colour, mew=2, zorder=5,
                    label=f"{label.split()[0]} start")
            a = np.unwrap(ang)
            k = int(np.searchsorted(np.abs(a - a[0]), np.radians(25.0)))
            k = min(max(k, 1), len(ang) - 1)
            r_arrow = outer * (0.93 - 0.05 * i)
            ax.annotate("", xy=(ang[k], r_arrow), xytext=(ang[0], r_arrow),
                        arrowprops=dict(arrowstyle="-|>", color=colour, lw=2.0, mutation_scale=16,
                                        connectionstyle=f"arc3,rad={0.12 if a[k] > a[0] else -0.12}"))
        ticks = np.arange(1, n_div + 1) * div
        ax.set_rticks(ticks)
        # ring labels on a white ground so that a trace passing under them does not hide them
        ax.set_yticklabels([ring_label(base + t) for t in ticks], fontsize=MIN_FONT_PT,
                           bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.8))
        ax.yaxis.set_zorder(4)                                 # the ring labels over the traces
        ax.set_rlim(0, outer)
        ax.set_rlabel_position(112.5)
        ax.set_thetagrids(np.arange(0, 360, 45), labels=[f"{a}°" for a in range(0, 360, 45)], fontsize=9.5)
        head = "\n".join(textwrap.wrap(title, 60)) + "\n" if title else ""
        ax.set_title(head + f"radial deviation about the {ev.center_kind} centre: scale {div:g} µm/div",
                     fontsize=10, pad=14)
        handles, labels = ax.get_legend_handles_labels()
        fig.legend(handles, labels, loc="upper center", fontsize=MIN_FONT_PT, ncol=2, frameon=False,
                   bbox_to_anchor=(0.295, 0.15), columnspacing=1.2, handlelength=1.8)
        rows = _table_rows(ev, cond, R, div, diagnostics)
        _draw_table(fig, rows, 0.6, 0.975, 0.93, 0.03)
        lines = [" ".join(x for x in r[1:] if x) for r in rows]
        return {"um_per_division": div, "divisions": n_div, "figure_text": lines}
