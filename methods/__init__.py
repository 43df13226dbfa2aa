"""fitbench methods: the registry and the fitting algorithms, one subpackage per family.

>>> import methods
>>> res = methods.fit("circle.gauss_newton", points)      # doctest: +SKIP
>>> res.center, res.radius, res.form_error                # doctest: +SKIP
"""
from methods._errors import (InvalidInputError, ResultContractError, UnknownMethodError, exception_call,
                             exception_text)
from methods._registry import (ENTRY_POINT_GROUP, KINDS, MethodSpec, fit, get, immutable, list_methods,
                               load_plugins, register)
from methods.result_base import FitResult, check_result
from methods._validation import validate_points
from methods._manifest import describe_methods
from methods._compiled import kernel_path


#: the families' result classes, defined in their packages (``methods.results`` re-exports them)
_RESULT_CLASSES = ("CircleFit", "ZoneFit", "EllipseFit", "MagnifyFit", "MultilaterationFit", "PositioningFit")


def __getattr__(name: str):
    """The family subpackages (``methods.circle``, ...) and :mod:`methods.results`, which imports them all, load on
    first use (PEP 562): ``import methods`` stays light; the registry imports the families on its first lookup
    (:func:`methods._registry.load_builtins`). They are imported by name: they import this package."""
    import importlib
    if name == "results" or name in _RESULT_CLASSES:
        results = importlib.import_module("methods.results")
        return results if name == "results" else getattr(results, name)
    from methods._registry import BUILTIN_FAMILIES, load_builtins
    if name not in BUILTIN_FAMILIES:
        raise AttributeError(f"module 'methods' has no attribute {name!r}")
    load_builtins()
    return globals()[name]


__all__ = ["InvalidInputError", "UnknownMethodError", "MethodSpec", "register", "get", "list_methods",
           "fit", "ResultContractError", "immutable", "load_plugins", "results", "check_result", "FitResult", "CircleFit", "ZoneFit", "EllipseFit",
           "validate_points", "describe_methods", "kernel_path", "ENTRY_POINT_GROUP", "KINDS", "exception_text",
           "exception_call"]
