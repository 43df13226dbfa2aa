"""Report of one circular test: the ISO 230-4 figures, the diagnostics table, and a polar plot of
both runs with magnified radial deviation."""
from __future__ import annotations

import numpy as np

LABELS = {"squareness": "squareness", "scale_mismatch": "scale mismatch X-Y", "servo_mismatch": "servo mismatch X-Y",
          "backlash_x": "backlash X", "backlash_y": "backlash Y", "reversal_spike_x": "reversal spike X",
          "reversal_spike_y": "reversal spike Y", "cyclic_error": "cyclic error"}


def text(ev: dict, dg: dict | None) -> str:
    um = 1e3
    lines = ["ISO 230-4 circular test",
             f"  nominal radius          {ev['nominal_radius']:.6g}",
             f"  centre ({ev['center_kind']})          ({ev['center'][0]:.6f}, {ev['center'][1]:.6f})",
             f"  G  CW / CCW             {ev['G_cw'] * um:.2f} / {ev['G_ccw'] * um:.2f} um",
             f"  G(b)                    {ev['G_b'] * um:.2f} um",
             f"  H (1996)                {ev['H'] * um:.2f} um",
             f"  F max / F min           {ev['F_max'] * um:+.2f} / {ev['F_min'] * um:+.2f} um ({ev['F_about']})",
             f"  mean radial deviation   {ev['mean_radial_deviation'] * um:+.2f} um"]
    if dg:
        lines += ["diagnostics (least squares on the error signatures; value +- standard uncertainty)"]
        for name, label in LABELS.items():
            item = dg[name]
            if item["value"] is None:
                lines.append(f"  {label:<22}  {item.get('note', 'not estimated')}")
            else:
                lines.append(f"  {label:<22}  {item['value']:+10.3f} +- {item['u']:.3f} {item['unit']}")
        m = dg["_model"]
        lines.append(f"  residual RMS {m['residual_rms_um']:.2f} um; spike decay {m['spike_decay_deg']:.2f} deg")
    return "\n".join(lines)


def polar_plot(cw, ccw, ev: dict, path, magnification: float | None = None, title: str = "") -> float:
    """Both runs as radial deviation from the nominal radius, magnified, around the nominal circle.
    Returns the magnification used."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c = ev["center"]  # about the least-squares (or minimum-zone) centre of both runs, as ballbar reports
    R = ev["nominal_radius"]
    devs = []
    for pts in (cw, ccw):
        ang = np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0])
        devs.append((ang, np.hypot(pts[:, 0] - c[0], pts[:, 1] - c[1]) - R))
    span = max(np.abs(d).max() for _, d in devs) or 1e-9
    if magnification is None:
        magnification = 0.25 * R / span  # the largest deviation drawn at a quarter of the plot radius
    fig = plt.figure(figsize=(6, 6))
    ax = fig.add_subplot(projection="polar")
    ring = np.linspace(0, 2 * np.pi, 721)
    ax.plot(ring, np.ones_like(ring), color="0.5", lw=0.8, label=f"nominal circle R = {R:g}")
    for (ang, dev), label, colour in zip(devs, ("CW (G02)", "CCW (G03)"), ("tab:blue", "tab:red")):
        order = np.argsort(ang)
        ax.plot(ang[order], 1 + magnification * dev[order] / R, lw=0.8, color=colour, label=label)
    ax.set_rticks([])
    ax.set_ylim(0, 1.35)
    ax.set_title((title + "\n" if title else "") +
                 f"radial deviation magnified x{magnification:.0f} about the {ev['center_kind']} centre\n"
                 f"G = {ev['G_cw'] * 1e3:.1f} / {ev['G_ccw'] * 1e3:.1f} um (CW/CCW), G(b) = {ev['G_b'] * 1e3:.1f} um, "
                 f"H = {ev['H'] * 1e3:.1f} um", fontsize=9)
    ax.legend(loc="lower left", fontsize=8, bbox_to_anchor=(-0.1, -0.1))
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return magnification
