"""Benchmark metrics: computed from a result and the truth, never inside a method."""
from __future__ import annotations

import numpy as np

from methods import result_base
from methods.result_base import EXACT, Tolerance


def metrics(result, truth: dict | None) -> dict:
    """Columns for one fit: form error, residual RMS, the fitted geometry and its errors against the truth
    where known, all read through the result interface (``FitResult.geometry`` / ``truth_errors``)."""
    row = {"form_error": result.form_error,
           "residual_rms": float(np.sqrt(np.mean(np.square(result.residuals)))) if len(result.residuals) else np.nan,
           **result.geometry()}
    if truth:
        row.update(result.truth_errors(truth))
    return row


# ---------------------------------------------------------------- tolerances of the verify command

#: The row columns' tolerances are declared by the families' result classes (each class's ``COLUMNS``, read through
#: ``methods.result_base.tolerances``); this table adds the engine's own columns and the columns of studies that
#: compute their own rows.
TOLERANCES: dict[str, Tolerance | None] = {
    "status": EXACT, "converged": EXACT, "iterations": EXACT, "nfev": EXACT,
    **result_base.tolerances(),
    "message": None,
    # multilateration (lengths in µm of a 1000-mm machine): least-squares adjustments with condition numbers 1e4-1e8 (4-6
    # stations) and up to 9e11 (4 stations within 1.3 mm of a plane, the paper's bad case). Between OpenBLAS's
    # Haswell and Sandybridge kernels (tests/test_cpu_independence.py) the near-planar case's values moved by up to
    # 1e-5 relative (1.1e-3 µm of 116 µm), the identified coefficients' relative error by 1e-4 of itself, the others
    # by 3e-8 relative or 1.2e-4 µm; the exact-length check measures the published scheme's own rounding (~1e-4 µm).
    # Declared: 1e-4 relative and 1e-2 µm (10 nm), a margin of 10.
    **dict.fromkeys(("station_error_um", "dead_path_error_um", "volumetric_error_rms_um", "volumetric_error_max_um",
                     "aligned_error_rms_um", "model_error_rms_um", "published_vs_centred_um", "case_a_vs_truth_um",
                     "case_b_vs_truth_um"),
                    Tolerance(1e-4, 1e-2, "a µm length of an adjustment with condition numbers up to 9e11: CPU rounding")),
    "identified_max_relative_error": Tolerance(1e-3, 1e-7, "relative error of 21 identified coefficients: moved 1e-4 "
                                                           "of itself between BLAS kernels (near-planar stations)"),
    # roundness (ISO 12181): RONt/RONq in µm of profiles up to D 25 mm (2.5e4 µm) after the ISO 16610-21 filter; at a
    # cut-off of 1 UPR the filtered profile of a near-perfect part is ~1e-4 µm, rounding itself, and its MCC/MZ moved
    # by up to 1.5e-7 µm between BLAS kernels: 1e-9 relative and 1e-5 µm (10 pm) absolute
    **{f"RON{q}_{k}_um": Tolerance(1e-9, 1e-5, "a µm roundness of a filtered profile: absolute resolution 1e-5 µm")
       for q in ("t", "q") for k in ("lsci", "mzci", "mici", "mcci")},
    # condition numbers by SVD: sigma_min carries an absolute error of eps sigma_max (seen: 2e-7 relative)
    **dict.fromkeys(("kappa_stations", "kappa_stations_max", "kappa_points", "kappa_points_max",
                     "kappa_stations_theorem1", "kappa_points_theorem1"),
                    Tolerance(1e-5, 0.0, "a condition number sigma_max / sigma_min: sigma_min is known to eps sigma_max")),
    # the per-station deltas as a JSON list for the report, rounded to 1e-6 µm: their size is station_error_um
    "station_deltas_um": None,
    # ISO 230-4 diagnostics (µm, µrad, µm/m, ms) and their standard uncertainties u: a Gauss-Newton fit of every source
    # on the exact geometry whose reversal-spike decay direction is nearly flat, so the last bits of the data (NumPy's
    # SIMD sin/cos) and of BLAS move the estimates by up to 8.4e-7 u between OpenBLAS's Haswell and Sandybridge
    # kernels (1.9e-7 µm of a 4.3 µm spike with u 0.23 µm); iterating on to a 1e-15 decrease moves them more (up to
    # 8e-6 u: along the flat direction), so this is the estimator's resolution, not its stopping rule's. Declared:
    # 1e-6 relative and 1e-6 absolute in the column's unit (1 pm, 1 prad, 1 ns): well below every u.
    **{f"diag_{s}{suffix}": Tolerance(1e-6, 1e-6, "an ISO 230-4 diagnostic fitted to a relative decrease of 1e-12 of "
                                                  "its residuals: resolved to ~1e-6 of its uncertainty")
       for s in ("squareness", "scale_mismatch", "servo_mismatch", "backlash_x", "backlash_y", "reversal_spike_x",
                 "reversal_spike_y", "cyclic_error") for suffix in ("", "_u")},
}
DEFAULT_TOLERANCE = Tolerance(1e-9, 1e-12, "a numeric study column not declared here: the geometric fits' 1e-9")
#: Wider tolerances of methods or studies that are chaotic by nature: (study glob, method glob, column) -> Tolerance.
#: Each entry says why; verify prints them with the verdict. None is needed: every method meets the column's
#: tolerance above between OpenBLAS's kernels and NumPy's SIMD levels (tests/test_cpu_independence.py).
CHAOTIC: dict[tuple[str, str, str], Tolerance] = {}


def tolerance(column: str, study: str = "", method: str = "") -> Tolerance | None:
    """The tolerance of ``column`` (None: not compared) for a row of ``study`` and ``method``."""
    from fnmatch import fnmatch
    for (s, m, c), tol in CHAOTIC.items():
        if c == column and fnmatch(study, s) and fnmatch(method, m):
            return tol
    if column.startswith("time_"):
        return None  # timing: measured, never reproducible
    if column in TOLERANCES:
        return TOLERANCES[column]
    declared = result_base.row_columns().get(column)  # a result class defined after this import (a plugin's)
    return declared.tolerance if declared is not None else DEFAULT_TOLERANCE
