"""fitbench methods: the registry and the fitting algorithms, one subpackage per family.

>>> import methods
>>> res = methods.fit("circle.gauss_newton", points)      # doctest: +SKIP
>>> res.center, res.radius, res.form_error                # doctest: +SKIP
"""
from methods._errors import InvalidInputError, UnknownMethodError
from methods._registry import (ENTRY_POINT_GROUP, KINDS, MethodSpec, fit, get, list_methods,
                               load_plugins, register)
from methods._result import (CircleFit, EllipseFit, FitResult, MagnifyFit, MultilaterationFit, PositioningFit,
                             ZoneFit)
from methods._validation import validate_points

from methods import circle, ellipse, magnify, multilateration, positioning, roundness  # noqa: E402,F401  (registers the built-in methods)

__all__ = ["InvalidInputError", "UnknownMethodError", "MethodSpec", "register", "get", "list_methods",
           "fit", "load_plugins", "FitResult", "CircleFit", "ZoneFit", "EllipseFit", "validate_points", "ENTRY_POINT_GROUP", "KINDS"]
