"""Roundness parameters of ISO 12181-1:2011 about the four reference circles of the filtered profile.

The pipeline (ISO 12181-2:2011 complete specification operator, filtration per ISO 16610-21):
1. the least-squares (LSCI) centre c0 and radius R0 of the raw profile (``circle.gauss_newton``: the circle
   minimising the sum of squared radial deviations, which is ISO 12181-1's LSCI);
2. the local radial deviations d_i = |p_i - c0| - R0 at the polar angles theta_i about c0, in angle order;
3. the ISO 16610-21 closed-profile Gaussian filter of d (``filter.gaussian_filter``), giving d_f;
4. the filtered profile rebuilt as points c0 + (R0 + d_f,i)(cos theta_i, sin theta_i) (unfiltered: the
   measured points themselves, unchanged);
5. each reference circle fitted to the filtered profile: LSCI (``circle.gauss_newton``), MZCI
   (``circle.minimum_zone``), MICI (``circle.max_inscribed``), MCCI (``circle.min_circumscribed``);
6. about each circle's centre c with radii r_i = |q_i - c| and reference radius R (the local roundness
   deviation r_i - R; ISO 12181-1:2011 clause 3, terms and definitions of the reference circles and parameters):
     RONt = max r_i - min r_i       (peak-to-valley roundness deviation)
     RONp = max r_i - R             (peak-to-reference roundness deviation)
     RONv = R - min r_i             (reference-to-valley roundness deviation)
     RONq = sqrt(mean (r_i - R)^2)  (root mean square roundness deviation)
   with R = the least-squares radius (LSCI), the mean of the two zone circles (MZCI), the inscribed radius
   min r_i (MICI: RONv = 0) and the circumscribed radius max r_i (MCCI: RONp = 0). So RONp + RONv = RONt
   for every circle, and MZCI's RONt is the smallest (its centre minimises max - min).
The harmonic spectrum is that of the filtered deviations d_f about c0 (step 3).
"""
from __future__ import annotations

import math
import warnings

import numpy as np

import methods
from methods._errors import InvalidInputError
from methods.result_base import radial_distances
from methods._validation import check_choice
from methods.roundness import filter as rfilter

REFERENCES = {"lsci": "circle.gauss_newton", "mzci": "circle.minimum_zone", "mici": "circle.max_inscribed",
              "mcci": "circle.min_circumscribed"}
REFERENCE_NAMES = {"lsci": "least-squares circle (LSCI)", "mzci": "minimum zone circles (MZCI)",
                   "mici": "maximum inscribed circle (MICI)", "mcci": "minimum circumscribed circle (MCCI)"}
MIN_POINTS = 8


def ron_parameters(points: np.ndarray, center, kind: str) -> dict:
    """RONt, RONp, RONv, RONq of ``points`` about ``center`` for reference ``kind`` (module docstring, step 6)."""
    r = radial_distances(points, center)
    r_min, r_max = float(r.min()), float(r.max())
    if kind == "lsci":
        radius = float(r.mean())           # the least-squares radius for a given centre is the mean radius
    elif kind == "mzci":
        radius = 0.5 * (r_min + r_max)
    elif kind == "mici":
        radius = r_min
    else:
        radius = r_max
    dev = r - radius
    return {"center": (float(center[0]), float(center[1])), "radius": radius, "RONt": r_max - r_min,
            "RONp": r_max - radius, "RONv": radius - r_min, "RONq": float(np.sqrt(np.mean(dev * dev))),
            "inner_radius": r_min, "outer_radius": r_max}


def filtered_profile(points: np.ndarray, cutoff_upr: float | None) -> dict:
    """Steps 1-4 of the module docstring: the raw LSCI, the angle order, the filtered deviations and the
    rebuilt points (in the input's order; ``order`` sorts them by angle)."""
    raw = methods.fit("circle.gauss_newton", points)
    if not raw.converged:
        raise InvalidInputError(f"roundness: the least-squares centre of the raw profile failed: {raw.message}")
    c0 = np.array(raw.center)
    ang = np.arctan2(points[:, 1] - c0[1], points[:, 0] - c0[0])
    order, theta = rfilter.order_by_angle(ang)
    rfilter.check_closed(theta, cutoff_upr)
    r = radial_distances(points, c0)[order]
    dev = r - raw.radius
    dev_f, path = rfilter.gaussian_filter(theta, dev, cutoff_upr)
    if cutoff_upr is None:
        pts = points                      # unfiltered: the measured points, bit for bit
    else:
        rr = raw.radius + dev_f
        pts = np.empty_like(points)
        pts[order] = np.column_stack([c0[0] + rr * np.cos(theta), c0[1] + rr * np.sin(theta)])
    return {"center": (float(c0[0]), float(c0[1])), "radius": float(raw.radius), "order": order, "angles": theta,
            "deviations_raw": dev, "deviations": dev_f, "points": pts, "path": path}


def evaluate(points: np.ndarray, cutoff_upr=50, reference: str = "all", lobes: int = 5) -> dict:
    """The whole ISO 12181 evaluation as a plain dict (see the module docstring); lengths in data units."""
    points = methods.validate_points(points, min_points=MIN_POINTS, method="roundness")
    cutoff = rfilter.parse_cutoff(cutoff_upr)
    check_choice("reference", reference, ("all", *REFERENCES), "roundness")
    prof = filtered_profile(points, cutoff)   # refuses an open profile before any warning about its sampling
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", rfilter.UndersampledWarning)
        note = rfilter.check_sampling(points.shape[0], cutoff)
    for w in caught:  # re-issue to the caller's filters, keep the text for the result
        warnings.warn(w.message, w.category, stacklevel=2)
    kinds = list(REFERENCES) if reference == "all" else [reference]
    refs, ok, messages = {}, True, []
    for kind in kinds:
        fit = methods.fit(REFERENCES[kind], prof["points"])
        row = ron_parameters(prof["points"], fit.center, kind)
        row.update(method=REFERENCES[kind], converged=bool(fit.converged), message=fit.message)
        refs[kind] = row
        ok &= bool(fit.converged)
        if not fit.converged:
            messages.append(f"{kind}: {fit.message}")
    spectrum = rfilter.harmonic_spectrum(prof["angles"], prof["deviations"])
    return {"cutoff_upr": cutoff, "n_points": int(points.shape[0]), "filter_path": prof["path"],
            "raw_lsci": {"center": prof["center"], "radius": prof["radius"]}, "references": refs,
            "spectrum": spectrum, "dominant_lobes": rfilter.dominant_lobes(spectrum, lobes),
            "angles": prof["angles"], "deviations": prof["deviations"], "deviations_raw": prof["deviations_raw"],
            "points": prof["points"], "order": prof["order"], "warnings": [note] if note else [],
            "converged": ok, "message": "; ".join(messages) or "all reference circles converged"}


def summary_form_error(references: dict) -> float:
    """RONt of MZCI when computed (ISO 1101's tolerance zone), else of the one reference evaluated."""
    if "mzci" in references:
        return references["mzci"]["RONt"]
    return next(iter(references.values()))["RONt"] if references else math.nan
