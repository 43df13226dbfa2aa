"""``roundness.iso12181``: the registered ISO 12181 evaluation (filter, four reference circles, spectrum)."""
from __future__ import annotations

import numpy as np

from methods._errors import InvalidInputError
from methods._registry import register
from methods.roundness.filter import parse_cutoff
from methods.roundness.evaluation import MIN_POINTS, evaluate, summary_form_error
from methods.roundness.results import RoundnessFit


def _cutoff_problem(value) -> str | None:
    """A parameter check (:func:`methods.register`): None (no filter) or a positive number of UPR."""
    if value is None:
        return None
    try:
        parse_cutoff(float(value))
    except InvalidInputError:   # a ValueError: first
        return "must be a positive number of UPR (e.g. 15, 50, 150, 500, 1500), or None (no filter)"
    except (TypeError, ValueError):
        return "is not a number of UPR; give e.g. 50, or None (no filter)"
    return None


@register("roundness.iso12181", kind="convex program", min_points=MIN_POINTS,
          param_checks={"cutoff_upr": _cutoff_problem},
          summary="ISO 12181 roundness: ISO 16610-21 Gaussian filter (UPR), RONt/p/v/q about LSCI, MZCI, MICI, MCCI, harmonics",
          reference="ISO 12181-1:2011 clause 3 (parameters, reference circles); ISO 12181-2:2011; "
                    "ISO 16610-21:2011 clause 5 (closed-profile Gaussian filter)")
def iso12181(points, *, cutoff_upr=50.0, reference="all"):
    """Filter the profile at ``cutoff_upr`` UPR (None: unfiltered; 15, 50, 150, 500, 1500 or any positive
    value) and evaluate RONt/RONp/RONv/RONq about ``reference`` (lsci, mzci, mici, mcci or all)."""
    ev = evaluate(points, cutoff_upr=cutoff_upr, reference=reference)
    first = next(iter(ev["references"].values()))
    res_r = np.hypot(ev["points"][:, 0] - first["center"][0], ev["points"][:, 1] - first["center"][1])
    return RoundnessFit(form_error=summary_form_error(ev["references"]), residuals=res_r - first["radius"],
                        converged=ev["converged"], message=ev["message"] + (f"; warning: {ev['warnings'][0]}" if ev["warnings"] else ""),
                        cutoff_upr=ev["cutoff_upr"], filter_path=ev["filter_path"], n_points=ev["n_points"],
                        raw_lsci=ev["raw_lsci"], references=ev["references"], spectrum=ev["spectrum"],
                        dominant_lobes=ev["dominant_lobes"], warnings=ev["warnings"], points=ev["points"],
                        angles=ev["angles"], deviations=ev["deviations"],
                        extra={"order": ev["order"]})
