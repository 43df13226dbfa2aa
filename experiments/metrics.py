"""Benchmark metrics: computed from a result and the truth, never inside a method."""
from __future__ import annotations

import math

import numpy as np

from methods import result_base
from methods.result_base import EXACT, Tolerance


def metrics(result, truth: dict | None, own: dict | None = None) -> dict:
    """Columns for one fit: form error, residual RMS, the fitted geometry and its errors against the truth
    where known, all read through the result interface (``FitResult.geometry`` / ``truth_errors``). ``result`` is one
    of fitbench's own classes, or :func:`methods.result_base.family_copy` of a plugin's result (its class's code
    computes them); ``own``: the columns a plugin's class adds (:func:`methods.result_base.own_columns`), after the
    geometry."""
    row = {"form_error": result.form_error, "residual_rms": residual_rms(result.residuals), **result.geometry()}
    if own:
        for k, v in own.items():
            row.setdefault(k, v)
    if truth:
        row.update(result.truth_errors(truth))
    return row


def residual_rms(residuals) -> float:
    """sqrt(mean(r_i^2)) of the residuals (NaN for none): for a float64 vector the sum and the division of
    ``np.mean`` (one ``np.add.reduce``, then / N) without its per-call overhead, hence the same bits."""
    n = len(residuals)
    if not n:
        return np.nan
    if type(residuals) is np.ndarray and residuals.ndim == 1 and (residuals.dtype is _FLOAT64
                                                                  or residuals.dtype == _FLOAT64):
        return math.sqrt(float(_add_reduce(_square(residuals))) / n)
    return float(np.sqrt(np.mean(np.square(residuals))))


_FLOAT64 = np.dtype(np.float64)
_add_reduce, _square = np.add.reduce, np.square


# ---------------------------------------------------------------- tolerances of the verify command

#: The row columns' tolerances are declared by the families' result classes (each class's ``COLUMNS``, read through
#: ``methods.result_base.tolerances``); this table adds the engine's own columns. The columns of a study that computes
#: its own rows are declared by its class (``experiments.study.Study.tolerances``), read with ``own``.
TOLERANCES: dict[str, Tolerance | None] = {
    "status": EXACT, "converged": EXACT, "iterations": EXACT, "nfev": EXACT,
    **result_base.tolerances(),
    "message": None,
}
DEFAULT_TOLERANCE = Tolerance(1e-9, 1e-12, "a numeric study column not declared here: the geometric fits' 1e-9")
#: Wider tolerances of methods or studies that are chaotic by nature: (study glob, method glob, column) -> Tolerance.
#: Each entry says why; verify prints them with the verdict. None is needed: every method meets the column's
#: tolerance above between OpenBLAS's kernels and NumPy's SIMD levels (tests/test_cpu_independence.py).
CHAOTIC: dict[tuple[str, str, str], Tolerance] = {}


def tolerance(column: str, study: str = "", method: str = "", own: dict | None = None) -> Tolerance | None:
    """The tolerance of ``column`` (None: not compared) for a row of ``study`` and ``method``; ``own``: the
    tolerances the studies declare for the columns of their own rows (``experiments.studies.tolerances``)."""
    from fnmatch import fnmatch
    for (s, m, c), tol in CHAOTIC.items():
        if c == column and fnmatch(study, s) and fnmatch(method, m):
            return tol
    if column.startswith("time_"):
        return None  # timing: measured, never reproducible
    if own and column in own:
        return own[column]
    if column in TOLERANCES:
        return TOLERANCES[column]
    declared = result_base.row_columns().get(column)  # a result class defined after this import (a plugin's)
    return declared.tolerance if declared is not None else DEFAULT_TOLERANCE
