"""The method registry: ids ``family.name`` mapped to functions with their metadata.

Adding a method = one module with one function decorated by :func:`register`. Third-party
packages register through the entry-point group ``fitbench.methods``: each entry point names a
module (or object) whose import runs ``@register``.
"""
from __future__ import annotations

import dataclasses
import difflib
import importlib
import inspect
import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from methods._errors import InvalidInputError, ResultContractError, UnknownMethodError
from methods._families import import_method_modules
from methods.plugins import add_entry, load_entry_points, own_entries
from methods._validation import validate_points
from methods import result_base
from methods.result_base import FitResult, check_result

ENTRY_POINT_GROUP = "fitbench.methods"
KINDS = ("closed form", "iterative", "convex program")
#: Minimum number of points a family's methods need (before a method's own stricter rule).
FAMILY_MIN_POINTS = {"circle": 3, "ellipse": 5}

#: the subpackages of ``methods`` holding the built-in methods (see :func:`load_builtins`)
BUILTIN_FAMILIES = ("circle", "ellipse", "magnify", "multilateration", "positioning", "roundness")
#: the families of one public module per method: :func:`load_builtins` imports every such module (adding a
#: method is adding a file); their package ``__init__`` imports none, so a method module may import
#: :mod:`methods.results` (which imports the families' ``results`` modules) without an import circle
ONE_MODULE_PER_METHOD = ("circle", "ellipse")

_REGISTRY: dict[str, "MethodSpec"] = {}
_builtins_loaded = False
#: the ids :func:`load_builtins` registered (what the manifest of the built-ins must hold, :mod:`methods._manifest`)
BUILTIN_IDS: set[str] = set()


@dataclass(frozen=True)
class MethodInfo:
    """What a user needs to know about a registered method (what ``list`` shows; the built-in ones are
    also stored in the manifest, :mod:`methods._manifest`)."""

    id: str
    family: str
    name: str
    summary: str
    reference: str
    kind: str
    defaults: dict
    min_points: int
    module: str


@dataclass(frozen=True, kw_only=True)
class MethodSpec(MethodInfo):
    """A registered method: its :class:`MethodInfo` and how to run it."""

    func: Callable = field(repr=False, compare=False)
    validator: Callable | None = field(default=None, repr=False, compare=False)
    param_checks: dict = field(default_factory=dict, repr=False, compare=False)

    def check_params(self, params: dict) -> None:
        """Refuse parameter values before any data is fitted (see :func:`check_param`), then by the checks the
        method's own code makes (:func:`body_checks`) of a parameter that declares none."""
        unknown = sorted(set(params) - set(self.defaults))
        if unknown:
            raise InvalidInputError(f"{self.id} has no parameter {', '.join(map(repr, unknown))}; "
                                    f"its parameters are: {', '.join(self.defaults) or 'none'}")
        for name, value in params.items():
            problem = check_param(name, value, self.defaults[name], self.param_checks.get(name))
            if not problem and name not in self.param_checks:  # then the checks its own code makes (a choice)
                own = body_checks(self.func).get(name)
                problem = own(value) if own is not None else None
            if problem:
                raise InvalidInputError(f"{self.id}: parameter {name}={value!r} {problem}")

    def __call__(self, points, **params):
        """The method's result; a plugin method's passes the gate: one that breaks its family's contract raises
        :class:`ResultContractError` (:func:`methods.check_result`). Built-in methods are held to the same
        contract by the test suite (every point-fitting built-in on a full circle and a short arc,
        tests/test_result_gate.py) and every benchmark row is gated by the engine; checking each API call again
        would cost passes over the points (at 10^5 points, four times the algebraic fit itself). The parameters are
        checked as a study's are (:meth:`check_params`: ``max_iter=2.5`` or ``xtol="1e-3"`` raise
        :class:`InvalidInputError`, never a TypeError from inside the method or a silently changed fit)."""
        if params:
            self.check_params(params)
        return _run(self, points, params, gate=self.id not in BUILTIN_IDS)

    def checked(self, points, **params):
        """The method's result through the gate whatever the method (:meth:`__call__` gates a plugin's only): what a
        single call such as ``fitbench fit`` uses, where the gate's cost does not matter and a method added to
        fitbench's own packages is not yet held to the contract by the test suite for every parameter."""
        if params:
            self.check_params(params)
        return _run(self, points, params, gate=True)

    @property
    def builtin(self) -> bool:
        """True for fitbench's own methods, False for a plugin's."""
        return self.id in BUILTIN_IDS

    def unchecked(self, points, **params):
        """The method's result without the gate, for a caller that applies :func:`methods.check_result` itself
        (the benchmark engine: such a result becomes an ``invalid`` row, and the timing measures the fit alone)."""
        return _run(self, points, params)


def _is_integer(v) -> bool:
    """A Python or NumPy integer, not a bool (``True`` is no iteration count)."""
    return isinstance(v, (int, np.integer)) and not isinstance(v, bool)


def _is_real(v) -> bool:
    """A Python or NumPy integer or float, not a bool."""
    return _is_integer(v) or isinstance(v, (float, np.floating))


def _positive(v):
    return None if _is_real(v) and v > 0 and math.isfinite(v) else "must be a positive finite number"


def _non_negative(v):
    return None if _is_real(v) and v >= 0 and math.isfinite(v) else "must be a finite number >= 0"


#: Checks by parameter-name convention, applied to every method (a method's own ``param_checks`` win):
#: tolerances are finite numbers >= 0 (0: the method's own rounding-noise floor decides, as Nelder-Mead's
#: fatol), iteration/evaluation budgets positive integers.
PARAM_CONVENTIONS: list[tuple[Callable[[str], bool], Callable]] = [
    (lambda n: n.endswith("tol"), _non_negative),
    (lambda n: n.startswith("max_") or n == "maxfev", _positive),
]


def check_param(name: str, value, default, check: Callable | None = None) -> str | None:
    """The problem with ``value`` for a parameter whose default is ``default`` (None when fine): the value
    must have the default's type (bool, int, float accepting ints, str; a None default accepts anything),
    be finite when numeric (NumPy's integer and float scalars count as int and float, a bool as neither), and
    pass ``check(value) -> problem | None`` (declared at :func:`register`) or the name convention of
    :data:`PARAM_CONVENTIONS`. A declared check speaks first, in the method's words, and alone on ``None`` (which
    may mean "off": roundness.iso12181's ``cutoff_upr=None``, no filter)."""
    judged = False
    if check is not None:
        try:
            problem, judged = check(value), True
        except (TypeError, ValueError):   # a check written for values of the default's type: the type check says it
            problem = None
        if problem or value is None:
            return problem
    if isinstance(default, bool):
        if not isinstance(value, bool):
            return f"must be true or false (the default is {default!r})"
    elif isinstance(default, int):
        if not _is_integer(value):
            return f"must be an integer (the default is {default!r})"
    elif isinstance(default, float):
        if not _is_real(value):
            return f"must be a number (the default is {default!r})"
        if not math.isfinite(value):
            return "must be finite"
    elif isinstance(default, str) and not isinstance(value, str):
        return f"must be a string (the default is {default!r})"
    if value is None or judged:
        return None
    if check is None:
        check = next((c for match, c in PARAM_CONVENTIONS if match(name)), None)
    return check(value) if check is not None else None


#: the value checks of :mod:`methods._validation` whose calls in a method's body :func:`body_checks` reads
_CHECK_HELPERS = ("check_choice", "check_positive", "check_vector")
_BODY_CHECKS: dict = {}


def body_checks(func: Callable) -> dict[str, Callable]:
    """{parameter: check(value) -> problem or None}: the checks a method's own code makes of its parameters' values,
    so that a study's config (:meth:`MethodSpec.check_params`) refuses before any row what the method would refuse
    when its rows run (``backend="bogus"``: was a ``skipped`` row). Read from the source of ``func``: every call of
    ``check_choice``, ``check_positive`` or ``check_vector`` (:mod:`methods._validation`) on a parameter itself,
    made by every call of the method (a statement of its body, not inside an ``if``, loop, ``try`` or ``with``; a loop
    over (name, parameter) pairs is read: ``for key, val in (("xtol", xtol), ...)``), or by a function of its own package that it so calls with the parameter (``_setup(points, name, backend,
    ...)``, two levels deep). Their other arguments (the choices, the length) are names and constants evaluated
    when checked; a call with others is not read. Nothing without readable source (a method made at run time)."""
    hit = _BODY_CHECKS.get(func)
    if hit is None:
        found: dict[str, list] = {}
        names = {p.name: p.name for p in inspect.signature(func).parameters.values()}
        _read_checks(func, names, found, depth=0, package=func.__module__.split(".")[0])
        hit = _BODY_CHECKS[func] = {p: _combined(p, checks) for p, checks in found.items()}
    return hit


def _read_checks(func: Callable, names: dict, found: dict, depth: int, package: str) -> None:
    """Add to ``found`` the checks ``func``'s body makes of its variables in ``names`` (variable -> the method's
    parameter it holds), following the calls that pass one of them to a function of ``package``."""
    import ast
    import textwrap
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError, SyntaxError):
        return
    node = next((n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
                 and n.name == func.__name__), None)
    if node is None:
        return
    env = getattr(func, "__globals__", {})
    for stmt in node.body:
        if isinstance(stmt, ast.For) and not stmt.orelse:   # for key, val in (("xtol", xtol), ...): check_positive(key, val)
            for label, variable in _pairs_looped(stmt):
                if variable in names:
                    for inner in stmt.body:
                        _read_statement(inner, env, {**names, stmt.target.elts[1].id: names[variable]}, found, depth,
                                        package, {stmt.target.elts[0].id: label})
            continue
        _read_statement(stmt, env, names, found, depth, package, {})


def _pairs_looped(loop) -> list[tuple[str, str]]:
    """(name, variable) of a loop ``for key, val in (("xtol", xtol), ("ftol", ftol)):``; [] for any other loop."""
    import ast
    target, items = loop.target, loop.iter
    if not (isinstance(target, ast.Tuple) and len(target.elts) == 2 and all(isinstance(e, ast.Name) for e in target.elts)
            and isinstance(items, (ast.Tuple, ast.List))):
        return []
    pairs = []
    for item in items.elts:
        if not (isinstance(item, ast.Tuple) and len(item.elts) == 2 and isinstance(item.elts[0], ast.Constant)
                and isinstance(item.elts[0].value, str) and isinstance(item.elts[1], ast.Name)):
            return []
        pairs.append((item.elts[0].value, item.elts[1].id))
    return pairs


def _read_statement(stmt, env: dict, names: dict, found: dict, depth: int, package: str, labels: dict) -> None:
    """The checks one statement always makes (none under an ``if``, a loop, ``try`` or ``with``); ``labels``: loop
    variables holding a parameter's name."""
    import ast
    if isinstance(stmt, (ast.If, ast.For, ast.AsyncFor, ast.While, ast.Try, ast.With, ast.AsyncWith,
                         ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) or type(stmt).__name__ == "TryStar":
        return
    for call in _unconditional_calls(stmt):
        callee = _resolve(call.func, env)
        if callee is None:
            continue
        helper = getattr(callee, "__name__", "") in _CHECK_HELPERS and \
            getattr(callee, "__module__", "") == "methods._validation"
        if any(isinstance(a, ast.Starred) for a in call.args) or any(k.arg is None for k in call.keywords):
            continue
        try:
            bound = inspect.signature(callee).bind(*call.args, **{k.arg: k.value for k in call.keywords})
        except (TypeError, ValueError):
            continue
        args = bound.arguments
        if helper:
            value, label = args.get("value"), args.get("name")
            label = (label.value if isinstance(label, ast.Constant) else
                     labels.get(label.id) if isinstance(label, ast.Name) else None)
            if isinstance(value, ast.Name) and value.id in names and isinstance(label, str):
                rest = {k: v for k, v in args.items() if k not in ("name", "value", "method")}
                if all(_plain_expression(v) for v in rest.values()):
                    found.setdefault(names[value.id], []).append((callee, label, rest, env))
        elif depth < 2 and inspect.isfunction(callee) and callee.__module__.split(".")[0] == package:
            passed = {k: names[v.id] for k, v in args.items() if isinstance(v, ast.Name) and v.id in names}
            if passed:
                _read_checks(callee, passed, found, depth + 1, package)


def _unconditional_calls(node):
    """The calls an expression or statement always makes (not inside a conditional expression, ``and``/``or``, a
    lambda or a comprehension)."""
    import ast
    if isinstance(node, (ast.IfExp, ast.BoolOp, ast.Lambda, ast.ListComp, ast.SetComp, ast.DictComp,
                         ast.GeneratorExp)):
        return
    if isinstance(node, ast.Call):
        yield node
    for child in ast.iter_child_nodes(node):
        yield from _unconditional_calls(child)


def _plain_expression(node) -> bool:
    """A constant, a name, an attribute of one, or a tuple/list of them: evaluated without running code."""
    import ast
    if isinstance(node, ast.Constant):
        return True
    if isinstance(node, ast.Name):
        return True
    if isinstance(node, ast.Attribute):
        return _plain_expression(node.value)
    if isinstance(node, (ast.Tuple, ast.List)):
        return all(_plain_expression(e.value if isinstance(e, ast.Starred) else e) for e in node.elts)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        return _plain_expression(node.operand)
    return False


def _evaluate(node, env: dict):
    import ast
    return eval(compile(ast.Expression(node), "<check>", "eval"), env)  # a _plain_expression: names and constants


def _resolve(node, env: dict):
    """The function a call names (``check_choice``, ``simplex.nelder_mead``), when it is a name or an attribute of
    one in ``env``; else None."""
    import ast
    if not isinstance(node, (ast.Name, ast.Attribute)) or not _plain_expression(node):
        return None
    try:
        return _evaluate(node, env)
    except Exception:  # a name defined later, a local variable: not a function this reading can follow
        return None


def _combined(param: str, checks: list) -> Callable:
    """One check(value) -> problem or None of a parameter from the helper calls :func:`body_checks` found."""
    def check(value):
        for helper, name, rest, env in checks:
            try:
                kwargs = {k: _evaluate(v, env) for k, v in rest.items()}
            except Exception:  # a name the module defines no more: this check cannot be made before the run
                continue
            try:
                helper(name, value, **kwargs)
            except InvalidInputError as exc:
                text = str(exc)
                for head in (f"parameter {name}={value!r} ", f"parameter {name} "):
                    if head in text:
                        return text[text.index(head) + len(head):]
                return text
        return None
    check.__qualname__ = f"body_check[{param}]"
    return check


def register(method_id: str, *, summary: str, reference: str, kind: str, min_points: int | None = None,
             validator: Callable | None = None, param_checks: dict | None = None):
    """Decorator registering ``func(points, **params)`` under ``method_id`` = ``family.name``.

    Default parameters are read from the function's keyword defaults (one source of truth).
    The decorated name becomes a callable that validates input, merges defaults, times the fit
    and fills ``method``, ``params`` and ``runtime_s`` of the result. Families whose input is not an
    (N, 2) point array (e.g. ``positioning``) pass their own ``validator(data, method_id)``.
    ``param_checks`` maps a parameter name to ``check(value) -> problem or None``, used by
    :meth:`MethodSpec.check_params` before a config runs (see :func:`check_param`).
    """
    family, dot, name = method_id.partition(".")
    if not dot or not family or not name or "." in name:
        raise ValueError(f"method id must be 'family.name', got {method_id!r}")
    if kind not in KINDS:
        raise ValueError(f"{method_id}: kind must be one of {KINDS}, got {kind!r}")
    if not summary or not reference:
        raise ValueError(f"{method_id}: a summary and a literature reference are required")

    def decorate(func):
        if not func.__module__.startswith("methods."):
            load_builtins()  # a plugin's id is checked against every built-in one
        sig = inspect.signature(func)
        defaults = {p.name: p.default for p in sig.parameters.values()
                    if p.kind == p.KEYWORD_ONLY and p.default is not p.empty}
        spec = MethodSpec(id=method_id, family=family, name=name, summary=summary, reference=reference,
                          kind=kind, defaults=defaults,
                          min_points=min_points or FAMILY_MIN_POINTS.get(family, 1),
                          func=func, module=func.__module__, validator=validator,
                          param_checks=dict(param_checks or {}))
        existing = _REGISTRY.get(method_id)
        if existing is not None and existing.module != spec.module:
            raise ValueError(f"method id {method_id!r} is already registered by {existing.module}")
        add_entry(_REGISTRY, method_id, spec)
        return spec

    return decorate


def _run(spec: MethodSpec, points, params: dict, gate: bool = False):
    """Validate, fit, time; with ``gate``, a result breaking its family's contract (:func:`check_result`
    against the validated data the method was given) raises :class:`ResultContractError`."""
    if params:
        unknown = sorted(set(params) - set(spec.defaults))
        if unknown:
            accepted = ", ".join(spec.defaults) or "none"
            raise InvalidInputError(f"{spec.id} has no parameter {', '.join(map(repr, unknown))}; "
                                    f"its parameters are: {accepted}")
        merged = {**spec.defaults, **params}
    else:
        merged = spec.defaults.copy()  # the result's own dict, as above
    if spec.validator is not None:
        pts = _read_only(spec.validator(points, spec.id), points)
    else:
        if isinstance(points, np.ndarray) and not is_immutable(points):
            points = immutable(points)  # the method gets a copy no one can write: the caller's array cannot change
        pts = validate_points(points, min_points=spec.min_points, method=spec.id)
        if pts.flags.writeable:  # converted from another type (a list, a DataFrame): a new array or a view
            if pts.base is None:
                pts.flags.writeable = False  # its own memory: the frame offered for it by validation stays valid
            else:
                pts = _read_only(pts, None)
    t0 = time.perf_counter()
    result = spec.func(pts, **merged)
    runtime = time.perf_counter() - t0
    if isinstance(result, FitResult):  # anything else is refused by the result gate (methods.check_result)
        result.runtime_s = runtime
        result.method = spec.id
        result.params = merged
    if gate:
        problem = check_result(result, pts)
        if problem:
            raise ResultContractError(spec.id, problem)
    return result


def is_immutable(a) -> bool:
    """True for an array no one can write through: read-only down to a buffer that is itself read-only
    (``bytes`` or a read-only ``memoryview``); a read-only array that owns its memory, or views a writeable
    array, can be made writeable again."""
    while isinstance(a, np.ndarray):
        if a.flags.writeable:
            return False
        a = a.base
    return isinstance(a, bytes) or (isinstance(a, memoryview) and a.readonly)


def immutable(a: np.ndarray) -> np.ndarray:
    """A read-only view of ``a`` that no one can make writeable: an array over a read-only ``memoryview`` of
    ``a``'s memory (``flags.writeable = True`` raises), without a copy for a C-contiguous array (other layouts
    are made contiguous first), so a fit's peak memory does not grow by the input; an ndarray subclass (a
    masked array) gets a read-only copy of its own class. Data that many fits read pass through this once."""
    if is_immutable(a):
        return a
    if type(a) is not np.ndarray:
        out = a.copy()
        out.flags.writeable = False
        return out
    return np.asarray(memoryview(np.ascontiguousarray(a)).toreadonly())


def _read_only(data, given):
    """``data`` as the method may see it: arrays as read-only views that cannot be made writeable (``given``:
    what the caller passed). Arrays inside a dataclass, dict, list or tuple are viewed the same way."""
    if isinstance(data, np.ndarray):
        return immutable(data)
    if dataclasses.is_dataclass(data) and not isinstance(data, type):
        changes = {f.name: _read_only(getattr(data, f.name), None) for f in dataclasses.fields(data) if f.init
                   and isinstance(getattr(data, f.name), (np.ndarray, dict, list, tuple))}
        return dataclasses.replace(data, **changes) if changes else data
    if isinstance(data, dict):
        return {k: _read_only(v, None) for k, v in data.items()}
    if isinstance(data, (list, tuple)) and any(isinstance(v, np.ndarray) for v in data):
        return type(data)(_read_only(v, None) for v in data)
    return data


def load_builtins() -> None:
    """Import the built-in method families once: each registers its methods on import. Done by the first
    :func:`get`, :func:`list_methods` or :func:`fit` (and by a plugin's :func:`register`), not by ``import
    methods``, so that ``python -m methods list`` can read the manifest instead (:mod:`methods._manifest`).
    The families import this module (``register``): importing them by name here keeps the import graph
    free of circles. The method modules of :data:`ONE_MODULE_PER_METHOD` families are imported here, not by
    their package."""
    global _builtins_loaded
    if _builtins_loaded:
        return
    _builtins_loaded = True
    try:
        with own_entries():  # loaded by a plugin's first register or not, they are no plugin's entries
            for family in BUILTIN_FAMILIES:
                package = importlib.import_module(f"methods.{family}")
                if family in ONE_MODULE_PER_METHOD:
                    import_method_modules(package.__name__, package.__path__)
        BUILTIN_IDS.update(k for k, s in _REGISTRY.items() if s.module.startswith("methods."))
    except BaseException:
        _builtins_loaded = False
        raise


def builtins_loaded() -> bool:
    return _builtins_loaded


def is_builtin(method_id: str) -> bool:
    """Whether ``method_id`` is one of fitbench's own methods (the built-ins are loaded first)."""
    load_builtins()
    return method_id in BUILTIN_IDS


result_base._builtin_method[0] = is_builtin  # the gate asks it of a certificate's claim (result_base imports no registry)


def load_plugins() -> None:
    """Import every entry point of the ``fitbench.methods`` group once (a broken plugin warns, see
    :func:`methods.plugins.load_entry_points`), after the built-ins when there is any."""
    load_entry_points(ENTRY_POINT_GROUP, "method", before=load_builtins)


def get(method_id: str) -> MethodSpec:
    """The :class:`MethodSpec` of ``method_id``; unknown ids raise with close suggestions. A built-in method's id
    needs no plugin loaded (a plugin cannot take a registered id): a command fitting only built-in methods imports
    no plugin and is not held up, or told about, an unrelated one."""
    load_builtins()
    spec = _REGISTRY.get(method_id)
    if spec is not None and spec.builtin:
        return spec
    load_plugins()
    try:
        return _REGISTRY[method_id]
    except KeyError:
        text = str(method_id)
        close = [m for m in _REGISTRY if m.startswith(text) or m.split(".", 1)[1].startswith(text)]
        close += [m for m in difflib.get_close_matches(text, _REGISTRY, n=3, cutoff=0.5) if m not in close]
        close = close[:3]
        hint = f"; did you mean {' or '.join(close)}?" if close else "; 'python -m methods list' shows them all"
        raise UnknownMethodError(f"unknown method id {method_id!r}{hint}") from None


def list_methods(family: str | None = None) -> list[MethodSpec]:
    """Registered methods, sorted by id, optionally of one family."""
    load_builtins()
    load_plugins()
    return [s for k, s in sorted(_REGISTRY.items()) if family is None or s.family == family]


def fit(method_id: str, points, **params):
    """Fit ``points`` with the registered method ``method_id`` and return its result object; a plugin method's
    result that breaks its family's contract (:func:`methods.check_result`, the gate of the benchmark's rows)
    raises :class:`ResultContractError`."""
    return get(method_id)(points, **params)


