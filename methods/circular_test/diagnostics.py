"""Diagnostics of a circular test: the machine's error sources from the two runs, by linear least
squares on their radial signatures (the trace patterns of ISO 230-4 annex / Kakino et al. 1987,
ref. 6 of the circle/ellipse paper), with standard uncertainties.

For a point at angle theta of a run in direction d (+1 CCW, -1 CW), to first order the radial
deviation from the nominal radius is dr = dx cos(theta) + dy sin(theta), and each source gives
(R = nominal radius, w = feed / R):

* centre offset (cx, cy): cx cos + cy sin                            (nuisance)
* radius per run (mean scale, probe length): 1 for that run          (nuisance)
* scale mismatch s_x - s_y: (R / 2) cos 2theta
* squareness alpha: (R / 2) sin 2theta (the same in both directions)
* servo mismatch tau_x - tau_y: d (w R / 2) sin 2theta (the inclination flips with the direction)
* backlash b_x: (1/2) d sign(sin theta) cos theta;  b_y: -(1/2) d sign(cos theta) sin theta
* reversal spike h_x: d sign(sin theta) exp(-phi_x / phi_tau) cos theta, phi_x the angle travelled since
  the X reversal (theta = 0, 180 deg); h_y likewise at the Y reversals; the decay angle phi_tau is
  chosen by least squares over a grid (variable projection)
* cyclic error of pitch p: (a sin(2 pi x / p) + b cos(2 pi x / p)) cos theta and the same in y, x and
  y the nominal machine coordinates; amplitude = mean of the X and Y amplitudes.

The uncertainties are sigma^2 (X^T X)^-1 with sigma^2 from the residuals: they assume independent
residuals and are optimistic where vibration or unmodelled errors leave correlated residuals.

Partial arcs (ISO 230-4 arcs of 90 deg or more): a source is estimated only when the arc can tell it
apart from the others. Backlash and reversal spikes of an axis need a reversal of that axis inside the
arc (X reverses at 0 and 180 deg, Y at 90 and 270 deg); every other signature must keep at least
``IDENTIFIABLE_MIN`` of its norm after projection onto the span of the other columns (the inverse square
root of its variance-inflation factor); a source failing either test is reported as not identifiable with
the reason, and left out of the fit.
"""
from __future__ import annotations

import numpy as np

from methods._errors import InvalidInputError

SPIKE_DECAY_GRID_DEG = np.geomspace(0.2, 40.0, 16)
IDENTIFIABLE_MIN = 0.05   # fraction of a signature's norm left after projecting out the others
NUISANCE = ("center_x", "center_y", "radius_cw", "radius_ccw")
REVERSAL_TERMS = {"backlash_x": "x", "reversal_spike_x": "x", "backlash_y": "y", "reversal_spike_y": "y"}


def _has_reversal(theta, axis) -> bool:
    """Does the arc contain a reversal of ``axis`` (x: sin(theta) changes sign; y: cos(theta) does)?"""
    v = np.sin(theta) if axis == "x" else np.cos(theta)
    return bool(np.any(v > 0.05) and np.any(v < -0.05))


def _unidentifiable(X, names, keep_mask):
    """Index of the worst-determined non-nuisance column (or None): the smallest fraction of its norm
    left after a least-squares projection onto the other kept columns."""
    worst, worst_frac = None, IDENTIFIABLE_MIN
    cols = np.flatnonzero(keep_mask)
    for j in cols:
        if names[j] in NUISANCE:
            continue
        others = X[:, [c for c in cols if c != j]]
        coef, *_ = np.linalg.lstsq(others, X[:, j], rcond=None)
        frac = np.linalg.norm(X[:, j] - others @ coef) / max(np.linalg.norm(X[:, j]), 1e-300)
        if frac < worst_frac:
            worst, worst_frac = j, frac
    return worst


def _signatures(theta, d, R, omega, pitch, center, phi_tau):
    c, s = np.cos(theta), np.sin(theta)
    cols = {"center_x": c, "center_y": s,
            "radius_cw": (d < 0).astype(float), "radius_ccw": (d > 0).astype(float),
            "scale_mismatch": 0.5 * R * np.cos(2 * theta),
            "squareness": 0.5 * R * np.sin(2 * theta),
            "servo_mismatch": d * 0.5 * (omega * R if omega else 1.0) * np.sin(2 * theta),
            "backlash_x": 0.5 * d * np.sign(s) * c,
            "backlash_y": -0.5 * d * np.sign(c) * s}
    phi_x = np.mod(d * theta, np.pi)
    phi_y = np.mod(d * theta - np.pi / 2, np.pi)
    cols["reversal_spike_x"] = d * np.sign(s) * np.exp(-phi_x / phi_tau) * c
    cols["reversal_spike_y"] = -d * np.sign(c) * np.exp(-phi_y / phi_tau) * s
    if pitch:
        xm = center[0] + R * c
        ym = center[1] + R * s
        k = 2 * np.pi / pitch
        cols.update(cyc_xs=np.sin(k * xm) * c, cyc_xc=np.cos(k * xm) * c, cyc_ys=np.sin(k * ym) * s,
                    cyc_yc=np.cos(k * ym) * s)
    return cols


def diagnose(cw, ccw, nominal_radius: float, nominal_center, *, feed_mm_min: float | None = None,
             cyclic_pitch: float | None = None, partial: bool | None = None) -> dict:
    """Estimates of the error sources with standard uncertainties: name -> {value, unit, u}.

    ``nominal_center`` in machine coordinates (needed for the cyclic error's phase); ``feed_mm_min``
    turns the servo mismatch into a time (ms; else its radial amplitude in um); ``cyclic_pitch`` (mm)
    enables the cyclic-error estimate."""
    if nominal_center is None:
        raise InvalidInputError("diagnostics need the nominal centre (--nominal-center X Y)")
    for v, n in ((feed_mm_min, "feed"), (cyclic_pitch, "cyclic pitch")):
        if v is not None and not (np.isfinite(v) and v > 0):
            raise InvalidInputError(f"the {n} must be a positive number, got {v!r}")
    if not (np.isfinite(nominal_radius) and nominal_radius > 0):
        raise InvalidInputError(f"the nominal radius must be a positive number, got {nominal_radius!r}")
    if not np.all(np.isfinite(np.asarray(nominal_center, dtype=float))):
        raise InvalidInputError(f"the nominal centre must be two finite numbers, got {nominal_center!r}")
    cw, ccw = np.asarray(cw, float), np.asarray(ccw, float)
    R = float(nominal_radius)
    center = np.asarray(nominal_center, dtype=float)
    pts = np.vstack([cw, ccw])
    d = np.concatenate([-np.ones(len(cw)), np.ones(len(ccw))])
    theta = np.arctan2(pts[:, 1] - center[1], pts[:, 0] - center[0])
    dr = np.hypot(pts[:, 0] - center[0], pts[:, 1] - center[1]) - R
    omega = (feed_mm_min / 60.0) / R if feed_mm_min else None
    if partial is None:
        a = np.sort(np.degrees(theta))
        partial = max(np.diff(a).max(initial=0.0), 360.0 - (a[-1] - a[0])) > 30.0
    dropped = {}
    if partial:
        for term, axis in REVERSAL_TERMS.items():
            if not _has_reversal(theta, axis):
                dropped[term] = f"not identifiable from this arc: it contains no reversal of the {axis.upper()} axis"
        cols0 = _signatures(theta, d, R, omega, cyclic_pitch, center, np.radians(5.0))
        names0 = list(cols0)
        X0 = np.column_stack(list(cols0.values()))
        keep = np.array([n not in dropped for n in names0])
        while True:
            j = _unidentifiable(X0, names0, keep)
            if j is None:
                break
            keep[j] = False
            dropped[names0[j]] = ("not identifiable from this arc: its signature is (nearly) a combination of the "
                                  "others over the angles measured")

    def solve(phi_tau):
        cols = {k: v for k, v in _signatures(theta, d, R, omega, cyclic_pitch, center, phi_tau).items()
                if k not in dropped}
        X = np.column_stack(list(cols.values()))
        coef, *_ = np.linalg.lstsq(X, dr, rcond=None)
        return float(np.sum((dr - X @ coef) ** 2)), list(cols), X, coef

    # the spike decay angle: a grid, then a bounded 1-D search around the best grid value (log scale)
    grid = np.radians(SPIKE_DECAY_GRID_DEG)
    rss_grid = [solve(p)[0] for p in grid]
    k = int(np.argmin(rss_grid))
    lo, hi = np.log(grid[max(k - 1, 0)]), np.log(grid[min(k + 1, len(grid) - 1)])
    from scipy.optimize import minimize_scalar  # imported on first use (light import)

    opt = minimize_scalar(lambda lp: solve(np.exp(lp))[0], bounds=(lo, hi), method="bounded",
                          options={"xatol": 1e-4})
    phi_tau = float(np.exp(opt.x)) if opt.fun <= rss_grid[k] else float(grid[k])
    rss, names, X, coef = solve(phi_tau)
    dof = len(dr) - X.shape[1]
    if dof <= 0:
        raise InvalidInputError("too few points for the diagnostics' model")
    sigma2 = rss / dof
    cov = sigma2 * np.linalg.pinv(X.T @ X)
    u = np.sqrt(np.diag(cov))
    idx = {n: i for i, n in enumerate(names)}

    def item(name, scale, unit):
        if name in dropped:
            return {"value": None, "unit": unit, "u": None, "note": dropped[name]}
        i = idx[name]
        return {"value": float(coef[i] * scale), "unit": unit, "u": float(u[i] * abs(scale))}

    out = {"squareness": item("squareness", 1e6, "urad"),
           "scale_mismatch": item("scale_mismatch", 1e6, "um/m"),
           "servo_mismatch": item("servo_mismatch", 1e3, "ms") if omega else item("servo_mismatch", 1e3, "um"),
           "backlash_x": item("backlash_x", 1e3, "um"), "backlash_y": item("backlash_y", 1e3, "um"),
           "reversal_spike_x": item("reversal_spike_x", 1e3, "um"),
           "reversal_spike_y": item("reversal_spike_y", 1e3, "um")}
    cyc_dropped = [n for n in ("cyc_xs", "cyc_xc", "cyc_ys", "cyc_yc") if n in dropped]
    if cyclic_pitch and cyc_dropped:
        out["cyclic_error"] = {"value": None, "unit": "um", "u": None, "note": dropped[cyc_dropped[0]]}
    elif cyclic_pitch:
        amps, grads = [], []
        for a, b in (("cyc_xs", "cyc_xc"), ("cyc_ys", "cyc_yc")):
            va, vb = coef[idx[a]], coef[idx[b]]
            amp = float(np.hypot(va, vb))
            g = np.zeros(len(names))
            if amp > 0:
                g[idx[a]], g[idx[b]] = va / amp, vb / amp
            amps.append(amp)
            grads.append(g)
        g = 0.5 * (grads[0] + grads[1])
        out["cyclic_error"] = {"value": 1e3 * 0.5 * (amps[0] + amps[1]), "unit": "um",
                               "u": 1e3 * float(np.sqrt(g @ cov @ g))}
    else:
        out["cyclic_error"] = {"value": None, "unit": "um", "u": None,
                               "note": "not estimated: give the ball-screw pitch (--cyclic-pitch)"}
    out["_model"] = {"centre_offset_um": [float(coef[idx["center_x"]] * 1e3), float(coef[idx["center_y"]] * 1e3)],
                     "radius_offset_um": {"cw": float(coef[idx["radius_cw"]] * 1e3),
                                          "ccw": float(coef[idx["radius_ccw"]] * 1e3)},
                     "spike_decay_deg": float(np.degrees(phi_tau)),
                     "residual_rms_um": float(np.sqrt(rss / len(dr)) * 1e3), "points": int(len(dr)),
                     "partial_arc": bool(partial), "not_identifiable": sorted(dropped)}
    return out
