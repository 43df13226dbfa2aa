"""Report of one circular test: the ISO 230-4 figures, the diagnostics table ranked by contribution, and
a polar plot read like ballbar software's: radial deviation magnified about the nominal circle with a
scale in µm per division, the G band (minimum and maximum circles), start and direction markers of both
runs, a test-conditions panel and the diagnostics ranked by their contribution to the circular deviation."""
from __future__ import annotations

import numpy as np

from fitbench.plots import report_figure

LABELS = {"squareness": "squareness", "scale_mismatch": "scale mismatch X-Y", "servo_mismatch": "servo mismatch X-Y",
          "backlash_x": "backlash X", "backlash_y": "backlash Y", "reversal_spike_x": "reversal spike X",
          "reversal_spike_y": "reversal spike Y", "cyclic_error": "cyclic error"}
#: human unit of each diagnostics unit, and the factor to the JSON's (mm, rad, s, ratio)
HUMAN_UNIT = {"um": "µm", "urad": "µrad", "um/m": "µm/m", "ms": "ms"}
TO_JSON = {"um": (1e-3, "mm"), "urad": (1e-6, "rad"), "um/m": (1e-6, "1 (m/m)"), "ms": (1e-3, "s")}


def contribution_um(name: str, item: dict, R_mm: float, feed_mm_min: float | None) -> float | None:
    """Peak-to-valley of the radial deviation a source causes on the circle (µm): the ranking of the report.
    Squareness a and scale mismatch s give R a / 2 and R s / 2 amplitude (peak-to-valley R a, R s); servo
    mismatch tau gives w R tau (w = feed / R) peak-to-valley; backlash b of an axis a step of b; a spike or
    cyclic error of amplitude h about h (spike) and 2 h (cyclic)."""
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
        return 2 * abs(v)
    if name == "cyclic_error":
        return 2 * abs(v)
    return abs(v)


def _label(name: str, plane: str | None) -> str:
    """The label with the plane's axis letters (X, Y for 'xy'; Z, X for 'zx'; Y, Z for 'yz')."""
    a, b = (plane or "xy").upper()[:2] if plane and len(plane) >= 2 else ("X", "Y")
    return LABELS[name].replace("X-Y", "#1-#2").replace(" X", " #1").replace(" Y", " #2").replace("#1", a).replace("#2", b)


def ranked(dg: dict, R_mm: float, feed_mm_min=None, plane: str | None = None) -> list:
    """[(label, item, contribution µm or None)] sorted by contribution, the largest first."""
    rows = [(_label(n, plane), dg[n], contribution_um(n, dg[n], R_mm, feed_mm_min)) for n in LABELS if n in dg]
    return sorted(rows, key=lambda r: (r[2] is None, -(r[2] or 0.0)))


def diagnostics_json(dg: dict) -> dict:
    """The diagnostics in the JSON's units (mm, rad, s, ratio)."""
    out = {}
    for k, item in dg.items():
        if k.startswith("_"):
            continue
        f, unit = TO_JSON[item["unit"]]
        d = {"value": None if item["value"] is None else item["value"] * f, "unit": unit,
             "u": None if item["u"] is None else item["u"] * f}
        if "note" in item:
            d["note"] = item["note"]
        out[k] = d
    return out


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
             f"  mean radial deviation   {ev.figures['mean_radial_deviation'] * um:+.2f} µm"]
    if dg:
        feed = ev.conditions.get("feed_mm_min")
        lines += ["diagnostics (least squares on the error signatures; value +- standard uncertainty), ranked by "
                  "their contribution to the circular deviation (peak-to-valley, µm)"]
        plane = ev.conditions.get("plane")
        for label, item, contrib in ranked(dg, ev.nominal_radius, feed, plane):
            if item["value"] is None:
                lines.append(f"  {label:<22}  {item.get('note', 'not estimated')}")
            else:
                unit = HUMAN_UNIT.get(item["unit"], item["unit"])
                lines.append(f"  {label:<22}  {item['value']:+10.3f} +- {item['u']:.3f} {unit:<5}  "
                             f"contribution {contrib:7.2f} µm")
        m = dg["_model"]
        lines.append(f"  residual RMS {m['residual_rms_um']:.2f} µm; spike decay {m['spike_decay_deg']:.2f}°")
    return "\n".join(lines)


def _nice_division(span_um: float) -> float:
    """A 1-2-5 step (µm) so that the span covers about 4 divisions."""
    raw = max(span_um / 4.0, 1e-6)
    exp = np.floor(np.log10(raw))
    for m in (1, 2, 5, 10):
        if m * 10 ** exp >= raw:
            return float(m * 10 ** exp)
    return float(10 ** (exp + 1))


def polar_plot(cw, ccw, ev, path, title: str = "", *, diagnostics=None, conditions=None, save=None, into=None):
    """Both runs as radial deviation (µm) about the evaluation centre, drawn on a polar grid whose
    rings are a fixed number of µm apart (the scale is printed: µm per division); the nominal circle is
    the ring 0; the G band (min and max radius of both runs) shaded; start (o) and direction (arrow)
    markers; a panel of test conditions and the ranked diagnostics. Returns the figure's scale dict
    {'um_per_division', 'divisions'}."""
    with report_figure(path, dpi=120, save=save, into=into, figsize=(11.5, 7.2)) as fig:
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
        ax = fig.add_axes([0.04, 0.08, 0.56, 0.84], projection="polar")
        ring = np.linspace(0, 2 * np.pi, 721)
        ax.fill_between(ring, lo - base, hi - base, color="0.88", alpha=0.5, lw=0)
        ax.plot(ring, np.full_like(ring, lo - base), color="0.55", lw=0.8)
        ax.plot(ring, np.full_like(ring, hi - base), color="0.55", lw=0.8,
                label=f"G band, min/max circles: {hi - lo:.2f} µm")
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
        ax.set_yticklabels([f"{base + t:+.3g} µm" for t in ticks], fontsize=7)
        ax.set_rlim(0, outer)
        ax.set_rlabel_position(112.5)
        ax.set_thetagrids(np.arange(0, 360, 45), labels=[f"{a}°" for a in range(0, 360, 45)])
        ax.set_title((title + "\n" if title else "") + f"radial deviation about the {ev.center_kind} centre: "
                     f"scale {div:g} µm/div", fontsize=10)
        handles, labels = ax.get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower left", fontsize=8, bbox_to_anchor=(0.64, 0.02), frameon=False)
        # the panel: test conditions, results, diagnostics ranked
        um = 1e3
        arc = ev.arc_deg
        centre = cond.get("nominal_center_mm") or cond.get("nominal_center")
        lines = ["Test conditions",
                 f"  machine      {cond.get('machine') or '-'}",
                 f"  date         {cond.get('date') or '-'}",
                 f"  plane        {str(cond.get('plane') or 'xy').upper()}",
                 f"  radius       {R:g} mm",
                 f"  centre       {'(' + ', '.join(f'{v:g}' for v in centre) + ') mm' if centre else '-'}",
                 f"  feed         {str(cond.get('feed_mm_min')) + ' mm/min' if cond.get('feed_mm_min') else '-'}",
                 f"  arc          CW {arc.get('cw', 360):.0f}°, CCW {arc.get('ccw', 360):.0f}°",
                 f"  scale        {div:g} µm/div",
                 "",
                 "Results (ISO 230-4)",
                 f"  G CW / CCW   {ev.figures['G_cw'] * um:.2f} / {ev.figures['G_ccw'] * um:.2f} µm",
                 f"  G(b)         {ev.figures['G_b'] * um:.2f} µm",
                 f"  H            {ev.figures['H'] * um:.2f} µm",
                 f"  F max / min  {ev.figures['F_max'] * um:+.2f} / {ev.figures['F_min'] * um:+.2f} µm"]
        if diagnostics:
            lines += ["", "Diagnostics (ranked, contribution µm)"]
            for label, item, contrib in ranked(diagnostics, R, cond.get("feed_mm_min"), cond.get("plane")):
                if item["value"] is None:
                    lines.append(f"  {label:<20} n/a")
                else:
                    unit = HUMAN_UNIT.get(item["unit"], item["unit"])
                    lines.append(f"  {label:<20} {item['value']:+8.2f} {unit:<5} {contrib:6.2f}")
        fig.text(0.64, 0.92, "\n".join(lines), va="top", ha="left", family="monospace", fontsize=8.5)
        return {"um_per_division": div, "divisions": n_div, "figure_text": lines}
