"""Result objects, the public import point: the result contract (:mod:`methods.result_base`: the base class
:class:`FitResult`, the column declarations :class:`Column` and :class:`Tolerance`, the registry of the families'
result classes and the gate :func:`check_result`) and every built-in family's result classes and builders, each
defined in its family's package (``methods/<family>/results.py``).

A method (built in or a plugin) builds its result with::

    from methods import register
    from methods.results import circle_result

A new family declares its own result class (a :class:`FitResult` subclass with ``FAMILY``, ``COLUMNS`` and
``SHAPES``) in its own package; the engine, the summary and verify find it there (:func:`row_columns`,
:func:`tolerances`, :func:`truth_error_columns`).
"""
from methods.result_base import (CENTER_COLUMNS, CENTER_ERROR_COLUMNS, ERRORS, EXACT, GEOMETRY, UNITS, Column,
                                 DeclarationError, FitResult, Tolerance, center_errors, check_result, contract,
                                 error_columns, family_modules, geometry_columns, jsonable, load_families,
                                 number_text, radial_distances, result_classes, row_columns, tolerances,
                                 truth_error_columns)
from methods.circle.results import CircleFit, ZoneFit, circle_result, zone_result
from methods.circular_test.results import CircularTestFit
from methods.ellipse.results import EllipseFit, ellipse_result
from methods.magnify.results import MagnifyFit
from methods.multilateration.results import MultilaterationFit
from methods.positioning.results import PositioningFit
from methods.roundness.results import RoundnessFit

__all__ = [
    # the contract (methods.result_base)
    "FitResult", "Column", "Tolerance", "DeclarationError", "EXACT", "GEOMETRY", "ERRORS", "UNITS", "CENTER_COLUMNS",
    "CENTER_ERROR_COLUMNS", "geometry_columns", "error_columns", "center_errors", "radial_distances", "jsonable",
    "number_text", "check_result", "contract", "result_classes", "row_columns", "truth_error_columns", "tolerances",
    "family_modules", "load_families",
    # the families (methods/<family>/results.py)
    "CircleFit", "ZoneFit", "circle_result", "zone_result", "CircularTestFit", "EllipseFit", "ellipse_result",
    "MagnifyFit", "MultilaterationFit", "PositioningFit", "RoundnessFit",
]
