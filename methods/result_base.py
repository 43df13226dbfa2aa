"""The result contract every family builds on: the base result class, the declaration of a row column (unit,
tolerance, check, error against the truth), the registry of the families' result classes and the gate every result
passes before it becomes a row of the benchmark (:func:`check_result`).

A family owns its result classes in its own package (``methods/<family>/results.py``): each class declares

* ``FAMILY``  -- the method family whose contract it is (``"circle"``: every circle method returns a
  ``CircleFit`` or a subclass);
* ``COLUMNS`` -- the :class:`Column` s its rows have (name, quantity and unit, what a converged result
  must satisfy, the tolerance ``python -m experiments.verify`` allows on another CPU, whether it is an error
  against the truth);
* ``SHAPES``  -- the shapes of its array-like fields (``"n"``: one entry per data point);
* ``consistency(result, data)`` -- what a converged result must agree with in its data (None: it does).

The engine, the summary and verify read these declarations here (:func:`row_columns`, :func:`tolerances`,
:func:`truth_error_columns`), which finds the built-in families by their folders (:func:`load_families`) and a
plugin's classes as subclasses of :class:`FitResult`; this module names no family. Methods and plugins import the
result classes and builders from :mod:`methods.results`, which re-exports this module and every family's.
"""
from __future__ import annotations

import importlib
import json
import math
import pkgutil
import sys
import weakref
from dataclasses import dataclass, field, fields
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

import numpy as np


def jsonable(value):
    """numpy scalars/arrays and non-finite floats as plain JSON values (NaN/inf -> None), for a result's
    ``to_dict``."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    return value


def number_text(v) -> str:
    """A number as a person reads it in a result's ``report_lines``: 10 significant digits, "nan" for a
    non-finite value, "-" for None."""
    if v is None:
        return "-"
    v = float(v)
    return f"{v:.10g}" if math.isfinite(v) else "nan"


def center_errors(center, truth: dict) -> dict:
    """Signed components and distance of a fitted centre from the true one (none without a true centre): the
    ``truth_errors`` of every family with a planar centre."""
    if "center" not in truth:
        return {}
    dx, dy = center[0] - truth["center"][0], center[1] - truth["center"][1]
    return {"center_error_x": dx, "center_error_y": dy, "center_error": _hypot(dx, dy)}


def _hypot(x, y) -> float:
    """``float(np.hypot(x, y))``, without a ufunc call for two finite Python floats: CPython's ``abs(complex)``
    returns C's ``hypot`` of finite parts (OverflowError when it overflows), the function NumPy's hypot loop calls,
    hence the same bits (tests/test_row_quick_paths.py); ``math.hypot`` has an algorithm of its own."""
    if type(x) is float and type(y) is float and math.isfinite(x) and math.isfinite(y):
        try:
            return abs(complex(x, y))
        except OverflowError:
            pass
    return float(np.hypot(x, y))


def radial_distances(points: np.ndarray, center) -> np.ndarray:
    """Distances r_i of the points from ``center`` (vectorised; the circle results and the roundness evaluation
    measure with it); exact to rounding at any float64 scale (np.hypot, free of under/overflow, is used when a
    squared distance would leave the normal range)."""
    dx = points[:, 0] - center[0]
    dy = points[:, 1] - center[1]
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        r = dx * dx
        r += dy * dy
        np.sqrt(r, out=r)
    if r.size and not (1e-145 < r.min() and r.max() < 1e150):
        r = np.hypot(dx, dy)
    return r


# ---------------------------------------------------------------- column declarations


class Tolerance(NamedTuple):
    """How far a re-computed value may lie from the committed one: |new - old| <= atol + rtol * |old|
    (rtol = atol = 0: exact). ``why`` is the one-line justification from the method's resolution."""

    rtol: float
    atol: float
    why: str


EXACT = Tolerance(0.0, 0.0, "an identity, a status or a count of a deterministic method: must be identical")
#: Geometric fits stop at a step of <= 1e-12 (Gauss-Newton, LM, Powell hybrid; unit-frame coordinates) or are
#: closed forms / convex programs solved to 1e-9 relative gap; a different CPU changes the last bits of the BLAS
#: reductions (about 1e-16 relative per operation, amplified by the condition number, below 1e3 for the data sets
#: here), so 1e-9 relative leaves a margin of three decades over the observed differences.
GEOMETRY = Tolerance(1e-9, 1e-12, "fits converge to ~1e-12 relative in the unit frame; 1e-9 covers CPU rounding")
#: Errors against the truth are differences of two numbers of the data's size: their absolute resolution is that
#: of the fitted geometry (1e-9 relative of lengths of order 1 to 1e3 data units -> 1e-9 absolute for unit-sized
#: data, 1e-6 for the 1000-mm machine-tool data: atol 1e-9 with rtol 1e-6 on the error itself).
ERRORS = Tolerance(1e-6, 1e-9, "a difference of two fitted lengths: absolute resolution of the fit (1e-9 data units)")

#: quantity -> the unit a person reads: lengths are in the data's unit (mm for the machine-tool data)
UNITS = {"length": "mm", "angle": "rad", "count": "", "ratio": "", "time": "s"}


class Column(NamedTuple):
    """One row column a result class declares.

    ``quantity``: ``"length"`` (data units, mm for the machine-tool data), ``"angle"`` (rad), ``"count"``,
    ``"ratio"``; ``check``: what a converged result's value must be (``"finite"``, ``"positive"``,
    ``"nonnegative"``; ``""``: may be NaN, e.g. a figure a family does not define); ``truth_error``: an error
    against the truth whose bias and RMSE the summary reports; ``components``: the columns of an error vector
    whose length this column is (the summary's bias is then the length of their mean, not the mean length)."""

    name: str
    quantity: str
    tolerance: Tolerance | None
    check: str = "finite"
    truth_error: bool = False
    components: tuple[str, ...] = ()

    @property
    def unit(self) -> str:
        return UNITS.get(self.quantity, "")


def geometry_columns(*names, check="finite", quantity="length") -> tuple[Column, ...]:
    """Columns of fitted geometry (lengths unless ``quantity`` says otherwise), verified to :data:`GEOMETRY`."""
    return tuple(Column(n, quantity, GEOMETRY, check) for n in names)


def error_columns(*names, quantity="length", summary=True) -> tuple[Column, ...]:
    """Errors against the truth, verified to :data:`ERRORS`; ``summary``: the summary reports their bias and RMSE."""
    return tuple(Column(n, quantity, ERRORS, "", truth_error=summary) for n in names)


#: the columns of a fitted planar centre and of its errors against the truth (circles, ellipses, circular tests)
CENTER_COLUMNS = geometry_columns("center_x", "center_y")
CENTER_ERROR_COLUMNS = (*error_columns("center_error_x", "center_error_y", summary=False),
                        Column("center_error", "length", ERRORS, "", truth_error=True,
                               components=("center_error_x", "center_error_y")))


class DeclarationError(ValueError):
    """A result class that declares a column another class declares already, with another quantity (unit),
    tolerance or summary role (a row column has one declaration), or a column the engine writes itself
    (:data:`ENGINE_COLUMNS`)."""


#: the columns the engine writes in a row (``experiments/rows.py``: ``base_row``'s identity, ``_measured_row``'s status
#: and counts, ``_finished``'s task index), and the prefixes of those it writes per data set parameter, per method
#: parameter and per timing (``experiments/timing.py``): no result class may declare one (it would overwrite it)
ENGINE_COLUMNS = frozenset({"study", "dataset", "repetition", "seed", "data_stream", "method", "params", "status",
                            "message", "converged", "iterations", "nfev", "task_index"})
ENGINE_PREFIXES = ("data_", "param_", "time_")


def engine_column(name) -> bool:
    """Whether ``name`` is a row column the engine writes (:data:`ENGINE_COLUMNS`, :data:`ENGINE_PREFIXES`)."""
    return name in ENGINE_COLUMNS or (type(name) is str and name.startswith(ENGINE_PREFIXES))


@dataclass(kw_only=True)
class FitResult:
    """Fields shared by every method's result (cf. scipy's ``OptimizeResult``), and the one interface the
    engine, the metrics and the CLI read a result through (no family is recognised by its attributes):

    * :meth:`geometry` -- the fitted geometry as named row columns (lengths in data units, angles in rad);
    * :meth:`truth_errors` -- the errors of that geometry against a known truth;
    * :meth:`report_lines` -- (label, text with unit) lines the CLI prints for that geometry.

    ``form_error`` (in data units) and ``residuals`` have one meaning per family: each family's class says which.
    ``history`` holds the objective per iteration of iterative methods, in its objective's unit (a sum of squares in
    data units squared, a zone width in data units; docs/cli.md); ``extra`` holds method-specific diagnostics.
    """

    method: str = ""
    form_error: float = float("nan")
    residuals: np.ndarray = field(default_factory=lambda: np.empty(0))
    converged: bool
    iterations: int | None = None
    nfev: int | None = None
    history: list = field(default_factory=list)
    message: str = ""
    runtime_s: float = float("nan")
    params: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)

    #: the family whose contract this class is (None: a base class)
    FAMILY = None
    #: the row columns of a fit of this class (its geometry, errors against the truth, and these two)
    COLUMNS = (Column("form_error", "length", GEOMETRY, "nonnegative"),
               Column("residual_rms", "length", GEOMETRY, "nonnegative"))
    #: array-like fields and their shapes ("n": one entry per data point); checked by :func:`check_result`
    SHAPES = {}
    #: NaN residuals mark data that was not measured (multilateration's missing lengths): allowed in a converged
    #: result (infinite ones never are); checked by :func:`check_result`
    MISSING_RESIDUALS = False

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        _CONTRACTS.clear()  # a new class may be a family's contract
        _check_declarations(cls)

    def geometry(self) -> dict:
        """The fitted geometry as row columns (none for a family without a fitted curve)."""
        return {}

    def truth_errors(self, truth: dict) -> dict:
        """Errors of :meth:`geometry` against ``truth`` (keys the family knows; others are ignored)."""
        return {}

    def report_lines(self, unit: str = "mm") -> list[tuple[str, str]]:
        """(label, text) lines of the fitted geometry for a person to read, every length in ``unit`` (the
        data's unit: the CLI converts every input to mm), angles in rad. By default each value of
        :meth:`geometry` with the unit its column declares (``side 2 mm``): a new family's geometry is printed."""
        units = {c.name: unit if c.quantity == "length" else c.unit for c in type(self).COLUMNS}
        return [(k.replace("_", " "), f"{number_text(v)} {units.get(k, '')}".rstrip()) for k, v in self.geometry().items()]

    def to_dict(self, residuals: bool = True) -> dict:
        """The JSON-ready dict the CLI prints (``residuals=False`` leaves the per-point array out)."""
        out = {}
        for f in fields(self):
            if f.name == "residuals" and not residuals:
                continue
            out[f.name] = jsonable(getattr(self, f.name))
        return out

    @staticmethod
    def consistency(result, data) -> str | None:
        """What a converged result must agree with in its data (None: it does); checked by :func:`check_result`
        with the declarations of the result's family."""
        return None


# ------------------------------------------------------- the registry: what the engine, summary and verify read

#: the module of a built-in family's result classes: ``methods/<family>/results.py``
RESULTS_MODULE = "results"
_families_loaded = False


@lru_cache(maxsize=None)
def family_modules() -> tuple[str, ...]:
    """The result modules of the built-in families: every package of ``methods`` holding a ``results`` module,
    in the order of their names (a new family folder with a ``results.py`` is found with no other edit)."""
    root = Path(__file__).resolve().parent
    return tuple(f"{__package__}.{p.name}.{RESULTS_MODULE}"
                 for p in sorted(pkgutil.iter_modules([str(root)]), key=lambda p: p.name)
                 if p.ispkg and not p.name.startswith("_") and (root / p.name / f"{RESULTS_MODULE}.py").is_file())


def load_families() -> None:
    """Import the result modules of the built-in families once (by name: they import this module), so that
    the registry knows every family before a column, a tolerance or a contract is read."""
    global _families_loaded
    if _families_loaded:
        return
    _families_loaded = True
    try:
        for name in family_modules():
            importlib.import_module(name)
        for cls in _classes_so_far():  # a plugin's class defined before the families were loaded
            if cls.__module__ not in family_modules():
                _check_declarations(cls)
    except BaseException:
        _families_loaded = False
        raise


def result_classes() -> list[type]:
    """:class:`FitResult` and every subclass defined so far: the built-in families' (in the order of
    :func:`family_modules`, parents before children), then those of loaded plugins in definition order."""
    load_families()
    return _classes_so_far()


def _classes_so_far() -> list[type]:
    out, todo = [], [FitResult]
    while todo:
        cls = todo.pop(0)
        if cls not in out:
            out.append(cls)
            todo.extend(cls.__subclasses__())
    order = {name: i for i, name in enumerate(family_modules())}
    rank = {cls: (0 if cls is FitResult else 1 + order.get(cls.__module__, len(order)), i) for i, cls in enumerate(out)}
    return sorted(out, key=rank.__getitem__)


#: family -> (weak reference to its contract class or None, that class's FAMILY): what :func:`contract` found,
#: emptied whenever a result class is defined; an entry whose class was collected or whose FAMILY changed is
#: looked up again (the gate asks for every row: walking and sorting the classes cost most of its time)
_CONTRACTS: dict = {}


def contract(family: str) -> type | None:
    """The result class a method of ``family`` must return (the most general class declaring that
    ``FAMILY``; a built-in family's before a plugin's), or None for a family that declares none (any
    :class:`FitResult` then)."""
    hit = _CONTRACTS.get(family)
    if hit is not None and _families_loaded:
        ref, declared = hit
        if ref is None:
            return None
        cls = ref()
        if cls is not None and cls.__dict__.get("FAMILY") == declared:
            return cls
    found = None
    for cls in result_classes():
        if cls.__dict__.get("FAMILY") == family:
            found = cls
            break
    _CONTRACTS[family] = (None, None) if found is None else (weakref.ref(found), family)
    return found


def row_columns() -> dict[str, Column]:
    """Every row column a result class declares, by name (first declaration wins: a built-in family's over a
    plugin's)."""
    out: dict[str, Column] = {}
    for cls in result_classes():
        for col in cls.COLUMNS:
            out.setdefault(col.name, col)
    return out


def _declared_as(col: Column) -> str:
    tol = "not compared" if col.tolerance is None else f"rtol {col.tolerance.rtol:g}, atol {col.tolerance.atol:g}"
    return f"{col.quantity} ({tol}{', an error against the truth' if col.truth_error else ''})"


def _check_declarations(cls: type) -> None:
    """Refuse a class whose ``COLUMNS`` name a column the engine writes (:func:`engine_column`), or redeclare a
    column of another class with another quantity, tolerance or summary role (its ``check`` may differ: the gate applies the family's). Run when the class is defined (against
    the classes defined so far; a plugin's class defined before the built-in families is checked again when they
    are loaded): the declaration that counts is the first in :func:`result_classes`' order (a built-in family's
    before a plugin's)."""
    for col in cls.__dict__.get("COLUMNS", ()):
        if engine_column(col.name):
            what = ("the row's identity, status or counts" if col.name in ENGINE_COLUMNS else
                    "a data set's or a method's parameter, or a timing")
            raise DeclarationError(
                f"{cls.__module__}.{cls.__qualname__} declares the column {col.name!r}, which the engine writes ({what}): "
                f"a result cannot set it; rename the column (e.g. {cls.__dict__.get('FAMILY') or 'my'}_{col.name})")
    classes = _classes_so_far()
    earlier = classes[:classes.index(cls)] if cls in classes else classes
    for col in cls.__dict__.get("COLUMNS", ()):
        owner = next((c for c in earlier if any(d.name == col.name for d in c.COLUMNS)), None)
        if owner is None:
            continue
        first = next(d for d in owner.COLUMNS if d.name == col.name)
        same_tolerance = (first.tolerance is None) == (col.tolerance is None) and (
            first.tolerance is None or first.tolerance[:2] == col.tolerance[:2])
        if not (first.quantity == col.quantity and first.truth_error == col.truth_error and same_tolerance
                and first.components == col.components):
            raise DeclarationError(
                f"{cls.__module__}.{cls.__qualname__} declares the column {col.name!r} as {_declared_as(col)}, but "
                f"{owner.__module__}.{owner.__qualname__} declares it as {_declared_as(first)}: a row column has one "
                f"declaration; reuse it or give the new column another name")


def truth_error_columns() -> tuple[str, ...]:
    """The errors against the truth whose bias and RMSE the summary reports, in declaration order."""
    return tuple(name for name, col in row_columns().items() if col.truth_error)


def tolerances() -> dict[str, Tolerance | None]:
    """The verification tolerance of every declared row column."""
    return {name: col.tolerance for name, col in row_columns().items()}


# ---------------------------------------------------------------- the gate before a result becomes a row


def _is_real(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))


def _describe(v) -> str:
    if isinstance(v, np.ndarray):
        return f"an array of shape {v.shape}"
    text = repr(v)
    return f"{type(v).__name__} {text[:40] + '...' if len(text) > 40 else text}"


def _value_problem(name: str, v, check: str, converged: bool) -> str | None:
    if type(v) is not float:  # a Python float (what the built-in results hold) is a number as it is
        if not _is_real(v):
            return f"{name} must be a number, got {_describe(v)}"
        v = float(v)
    if not converged or not check:
        return None
    if not math.isfinite(v):
        return f"{name} = {v} is not finite in a converged result"
    if check == "positive" and not v > 0:
        return f"{name} = {v:.10g} must be > 0"
    if check == "nonnegative" and not v >= 0:
        return f"{name} = {v:.10g} must be >= 0"
    return None


def _undeclared_family(family: str) -> str:
    return (f"no result class declares FAMILY = {family!r}: a method of a new family returns a result class of its "
            f"own declaring it (docs/plugins.md), whose columns and checks the gate applies")


#: whether a method id is one of fitbench's own: set by ``methods._registry``, which knows them (this module, below the
#: registry, imports none of it); until then no id is
_builtin_method: list = [lambda method: False]


def _certificate_problem(method: str, claim) -> str | None:
    """A plugin's claim of a certificate (``extra['certified']`` "global" or "local"): refused. Only fitbench's own
    methods set it, each after checking its certificate (docs/certificates.md); the gate cannot check a claim of an
    objective it does not know (a zone fit's width, an inscribed or circumscribed radius)."""
    if claim is None or claim is False:
        return None
    if _builtin_method[0](method):
        return None
    return (f"extra['certified'] = {_describe(claim)} is a certificate only fitbench's own methods give (each checks "
            f"it before setting it); a plugin's claim cannot be checked here: leave 'certified' out (or False) and "
            f"say in the message what the method verified")


def _shape_problem(name: str, value, shape: tuple, n: int | None) -> str | None:
    t = type(value)
    if t is np.ndarray and value.dtype.kind in "fiu":
        got = value.shape  # what np.asarray(value, dtype=float) would have, without converting
    elif t is tuple and ((len(value) == 2 and type(value[0]) is float and type(value[1]) is float)
                         or all(type(v) is float for v in value)):  # a centre of two Python floats: no generator
        got = (len(value),)
    else:
        try:
            got = np.asarray(value, dtype=float).shape
        except (TypeError, ValueError):
            return f"{name} must be numbers of shape {shape}, got {_describe(value)}"
    if type(shape) is tuple and "n" not in shape:
        want = shape
    elif type(shape) is tuple and shape == _PER_POINT:
        want = (n,)
    else:
        want = tuple(n if s == "n" else s for s in shape)
    if None in want:
        want = tuple(a if w is None else w for a, w in zip(got, want)) if len(got) == len(want) else want
    if got != want:
        return f"{name} must have shape {want}, got {got}"
    return None


#: the shape of an array with one entry per data point
_PER_POINT = ("n",)

#: the scalar types :func:`jsonable` turns into a JSON value json.dumps writes (a non-finite float into None)
_PLAIN_SCALARS = frozenset({str, int, float, bool, type(None), np.float64, np.float32, np.int64, np.int32,
                            np.bool_})


def _plain_extra(extra: dict) -> bool:
    """True when ``extra`` holds only str keys and plain scalars or flat lists/tuples of them (what methods
    put there): JSON-serialisable without serialising it; anything else is left to json.dumps."""
    plain = _PLAIN_SCALARS
    for k, v in extra.items():
        if type(k) is not str:
            return False
        t = type(v)
        if t in plain:
            continue
        if (t is list or t is tuple) and plain.issuperset(map(type, v)):
            continue
        return False
    return True


_DECLARED: dict = {}


def _declared_checks(own, family) -> dict[str, str]:
    """The ``check`` of every column declaration that applies to a result, by column name: its class's ``COLUMNS``,
    overridden by its family's (cached while both are the same tuple objects: the gate asks for every row)."""
    hit = _DECLARED.get((id(own), id(family)))
    if hit is not None and hit[0] is own and hit[1] is family and type(own) is tuple and type(family) is tuple:
        return hit[2]
    out = {**{c.name: c.check for c in own}, **{c.name: c.check for c in family}}
    if len(_DECLARED) > 256:
        _DECLARED.clear()
    _DECLARED[(id(own), id(family))] = (own, family, out)
    return out


def _floats_meet_checks(form_error, geometry: dict, checks: dict, converged: bool) -> bool:
    """True when the form error and every value of a dict geometry are Python floats that meet their columns'
    checks in a converged result (finite; > 0 "positive", >= 0 "nonnegative"): :func:`_value_problem` would find
    no problem in them. False: it decides and explains."""
    if not converged:
        if type(form_error) is not float:
            return False
        for v in geometry.values():
            if type(v) is not float:
                return False
        return True
    get = checks.get
    check, v = get("form_error", "finite"), form_error
    if type(v) is not float or check and not (math.isfinite(v) and (check != "positive" or v > 0)
                                              and (check != "nonnegative" or v >= 0)):
        return False
    for name, v in geometry.items():  # the same test on each value
        if type(v) is not float:
            return False
        check = get(name, "finite")
        if check and not (math.isfinite(v) and (check != "positive" or v > 0) and (check != "nonnegative" or v >= 0)):
            return False
    return True


def _count_problem(name: str, v) -> str | None:
    if isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_)) and v >= 0:
        return None
    return f"{name} must be None or a count >= 0, got {_describe(v)}"


def check_result(result, data=None) -> str | None:
    """The gate every result passes before it becomes a row (None: it passes; else the reason, one line).

    Checks the contract of the result's family (:func:`contract` of the family of ``result.method``):
    the class; ``converged`` a bool, ``iterations``/``nfev`` None or counts, ``message`` a string; every
    declared column a number, and in a converged result finite and of the declared sign (radius > 0, form
    error >= 0); every declared shape (``"n"``: one per point of ``data``); ``extra`` JSON-serialisable;
    for circles and ellipses, the form error and residuals recomputed from ``data`` about the returned curve (a method
    cannot claim a form error its points do not have), and a zone's radii and contacts: the ``consistency`` of the
    family's class, or of fitbench's own subclass of it that the result is (``ZoneFit``).

    It runs for every row of the benchmark (a few µs beside a fit of tens): the types a built-in result holds
    (Python floats and ints, tuples of floats, float64 arrays, a ``dict`` geometry) take quick paths that decide
    exactly as the general code below them, which every other type takes (tests/test_gate_fast_paths.py)."""
    if not isinstance(result, FitResult):
        return f"the method returned {_describe(result)}, not a methods.results.FitResult"
    method = result.method
    if type(method) is not str:
        if not isinstance(method, str):
            return f"method must be the method id, got {_describe(method)}"
        method = str(method)
    family = method.partition(".")[0]
    cls = contract(family)
    if cls is None:
        return _undeclared_family(family)
    if not isinstance(result, cls):
        return f"a {family} method must return a {cls.__name__}, got a {type(result).__name__}"
    converged = result.converged
    if converged is not True and converged is not False:
        if not isinstance(converged, (bool, np.bool_)):
            return f"converged must be True or False, got {_describe(converged)}"
        converged = bool(converged)
    v = result.iterations
    if v is not None and not (type(v) is int and v >= 0):
        problem = _count_problem("iterations", v)
        if problem:
            return problem
    v = result.nfev
    if v is not None and not (type(v) is int and v >= 0):
        problem = _count_problem("nfev", v)
        if problem:
            return problem
    message = result.message
    if type(message) is not str and not isinstance(message, str):
        return f"message must be a string, got {_describe(message)}"
    extra, params = result.extra, result.params
    if not ((type(extra) is dict or isinstance(extra, dict)) and (type(params) is dict or isinstance(params, dict))):
        return "extra and params must be dicts"
    if not _plain_extra(extra):  # else serialised: what json cannot write is refused
        try:
            json.dumps(jsonable(extra), allow_nan=False)
        except (TypeError, ValueError) as exc:
            return f"extra is not JSON-serialisable ({type(exc).__name__}: {str(exc)[:80]})"
    claim = extra.get("certified")
    if claim is not None and claim is not False:
        problem = _certificate_problem(method, claim)
        if problem:
            return problem
    n = None
    if isinstance(data, np.ndarray) and data.ndim == 2:
        n = data.shape[0]
    own = type(result)
    rules = cls or own  # the family's declarations win over a subclass's own
    own_shapes, shapes = own.SHAPES, rules.SHAPES
    for name, shape in (shapes if own_shapes is shapes else {**own_shapes, **shapes}).items():
        problem = _shape_problem(name, getattr(result, name), shape, n)
        if problem:
            return problem
    try:
        values = None
        form_error = result.form_error
        geometry = result.geometry()
        if type(geometry) is not dict or "form_error" in geometry:  # as the dict display below orders them
            values, geometry = {"form_error": form_error, **geometry}, None
        if own.geometry is not rules.geometry and not builtin_class(own):  # a plugin's class with its own geometry()
            problem = _two_faced(result, values if geometry is None else geometry)
            if problem:
                return problem
    except Exception as exc:  # a geometry the class cannot even read out
        return f"the geometry cannot be read ({type(exc).__name__}: {str(exc)[:80]})"
    checks = _declared_checks(own.COLUMNS, rules.COLUMNS)
    if geometry is not None:  # Python floats that meet their checks pass here; any other value is told below
        if not _floats_meet_checks(form_error, geometry, checks, converged):
            values = {"form_error": form_error, **geometry}
    if values is not None:
        problems = [_value_problem(name, v, checks.get(name, "finite"), converged) for name, v in values.items()]
        if any(problems):
            return "; ".join(p for p in problems if p)
    residuals = result.residuals
    if not isinstance(residuals, np.ndarray) or residuals.dtype.kind not in "fiu":
        return f"residuals must be a numeric array, got {_describe(residuals)}"
    if not converged:
        return None
    if rules.MISSING_RESIDUALS and residuals.dtype.kind == "f":
        residuals = residuals[~np.isnan(residuals)]
    size = residuals.size
    if size:
        # one pass: a finite sum of squares means finite residuals and a finite residual RMS (the row's column);
        # NaN, inf or an overflow (|r| beyond ~1e154) is told apart below
        with np.errstate(over="ignore"):   # an overflow is told below, in the message, never as a warning
            squares = residuals.dot(residuals) if residuals.ndim == 1 and residuals.dtype.kind == "f" else None
        if squares is None or not math.isfinite(squares):
            if not np.isfinite(residuals).all():
                return "residuals are not finite in a converged result"
            with np.errstate(over="ignore"):
                total = float(np.add.reduce(np.square(residuals, dtype=np.float64), axis=None))
            if not math.isfinite(total):
                return (f"the residual RMS overflows float64 (residuals up to {float(np.abs(residuals).max()):.3g}) "
                        f"in a converged result; rescale the data (e.g. to another unit)")
    if n:
        if own is not rules:  # fitbench's own subclass of the family's class may refine its contract (ZoneFit's radii)
            base = builtin_base(own)
            if base is not rules and issubclass(base, rules):
                return base.consistency(result, data)
        return rules.consistency(result, data)
    return None


# ------------------------------------------------- fitbench's own classes: what a row's family columns are computed by


_BUILTIN_CLASS: dict = {}


def builtin_class(cls: type) -> bool:
    """Whether ``cls`` is one of fitbench's own result classes (:class:`FitResult`, or a class a built-in family's
    ``results`` module defines under its name), not a plugin's."""
    hit = _BUILTIN_CLASS.get(cls)
    if hit is None:
        load_families()
        name = getattr(cls, "__module__", None)
        hit = (name == __name__ or name in family_modules()) and \
            getattr(sys.modules.get(name), cls.__name__, None) is cls
        if len(_BUILTIN_CLASS) > 4096:
            _BUILTIN_CLASS.clear()
        _BUILTIN_CLASS[cls] = hit
    return hit


def builtin_base(cls: type) -> type:
    """The most derived of fitbench's own result classes that ``cls`` derives from (``cls`` itself for one of them):
    its code computes the family's columns of a plugin's result."""
    return next(c for c in cls.__mro__ if builtin_class(c))


def trusted(result, method: str) -> bool:
    """Whether a row of ``method`` giving ``result`` is fitbench's own code throughout: a built-in method returning one
    of fitbench's own classes (its columns are computed by its class, quickly); any other result's family columns
    are computed from :func:`family_copy`."""
    return builtin_class(type(result)) and _builtin_method[0](method)


def _two_faced(result, geometry) -> str | None:
    """Where a plugin class's ``geometry()`` reports other values than fitbench's own class it derives from reads
    from the result's fields (the values the gate checks against the data): a row reports what the gate checked,
    and a result that tells two stories is a lie (None: they agree)."""
    base = builtin_base(type(result))
    for name, value in base.geometry(result).items():
        if name not in geometry:
            return (f"geometry() of {type(result).__name__} leaves out {name} (the result's {name} is "
                    f"{number_text(_as_float(value))}): a row reports the values the gate checks against the data")
        mine = geometry[name]
        a, b = _as_float(mine), _as_float(value)
        if not (a == b or (a != a and b != b)):
            return (f"geometry() of {type(result).__name__} reports {name} = {number_text(a)} but the result's own "
                    f"value, which the gate checks against the data, is {number_text(b)}: a row reports the values "
                    f"the gate checked; a class of a plugin may add columns, not report others")
    return None


def _as_float(v) -> float:
    try:
        return float.__float__(v) if isinstance(v, float) else float(v)
    except (TypeError, ValueError, OverflowError):
        return float("nan")


def _plain_value(v):
    """``v`` in Python's and NumPy's own types (a float, int, bool or str subclass as the value it holds, an ndarray
    subclass as a copy in ``np.ndarray``, containers rebuilt of such values): nothing a plugin defines can run when
    the row reads it. Anything else is kept as it is (the gate refuses it where a number is due)."""
    t = type(v)
    if t is float or t is int or t is str or t is bool or v is None:
        return v
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, float):
        return float.__float__(v)  # the double it holds, whatever its class's __float__ says
    if isinstance(v, np.floating):
        return v.item() if t in (np.float64, np.float32, np.float16) else float(v)
    if isinstance(v, int):
        return int.__index__(v)
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, str):
        return str.__str__(v)
    if isinstance(v, np.ndarray):
        return np.array(v)  # a copy, in np.ndarray itself
    if isinstance(v, tuple):
        return tuple(_plain_value(x) for x in v)
    if isinstance(v, list):
        return [_plain_value(x) for x in v]
    if isinstance(v, dict):
        return {_plain_value(k): _plain_value(x) for k, x in v.items()}
    return v


def family_copy(result):
    """The result as the most derived of fitbench's own classes it derives from, its fields' values copied in plain
    types (:func:`_plain_value`): the gate checks this copy against the data and the row's family columns and errors
    against the truth are computed from it by that class's code, so a plugin's subclass cannot report other values
    than those checked, nor compute its own errors against the truth. A result of a family a plugin declares (its
    contract class is the plugin's) is returned as it is: its columns are its own."""
    base = builtin_base(type(result))
    if base is FitResult:
        return result
    values = {}
    for f in fields(base):
        values[f.name] = _plain_value(getattr(result, f.name))
    copy = object.__new__(base)  # no __init__ or __post_init__: the values as they are
    copy.__dict__.update(values)
    return copy


def own_columns(result, copy, truth: dict | None) -> dict:
    """The columns a plugin's class adds to its family's (its ``geometry()`` and ``truth_errors()`` entries that its
    family does not declare), as plain numbers; :class:`TypeError` for a value that is no number."""
    if copy is result:
        return {}
    family = {c.name for c in type(copy).COLUMNS}
    out = {}
    for kind, values in (("geometry", result.geometry()), ("truth_errors", result.truth_errors(truth) if truth else {})):
        for name, v in values.items():
            if name not in family:
                if not _is_real(v):
                    raise TypeError(f"{kind}() of {type(result).__name__} gave {name} = {_describe(v)}, not a number")
                out[name] = v
    return {k: _plain_value(v) for k, v in out.items()}
