"""Data sources: a registry like the methods' one. A study's ``[[datasets]]`` entry names a source and
its parameters; the source returns ``(data, truth)`` — the data a method fits (an (N, 2) array of points
for circles and ellipses) and the known truth as a dict (``None`` for measured data).

Built in: ``circle`` and ``ellipse`` (synthetic generators with known truth, ``datasets.synthetic``),
``published`` (a published set shipped with fitbench), ``file`` (any file ``datasets.read_points``
reads; a relative path is relative to the study's TOML) and ``nist`` (one set of the NIST Circle2d
folder given by ``FITBENCH_NIST_DIR``, truth = NIST's reference least-squares circle).

A random source draws only from the ``rng`` it is given (the engine derives it from the study seed and
the (entry, grid point, repetition) stream), so every method sees the same data; a non-random source
gets one repetition. Adding a source::

    from datasets.sources import register_source

    @register_source("outliers", random=True, summary="circle with 10 % gross outliers", gives=np.ndarray,
                     family="circle")
    def outliers(rng, *, n=100, share=0.1):
        ...
        return points, {"family": "circle", "center": (0.0, 0.0), "radius": 1.0}

A source declares its parameters' types as a method does: by annotation (``n: int = 100``, ``share: float``,
``path: Literal["cw", "ccw"]``, ``Annotated[float, pydantic.Field(gt=0)]``), else by the type of the default (an
int default takes integers, a float default numbers, a str default strings, a tuple of numbers a list of them;
no default or None: anything). A study's values are checked against them before any row runs
(``experiments.schema.check_values``): ``n = 30.5`` or ``radius = "5"`` is refused in one line, never coerced.

A source declares what its data are with ``gives`` (a type: ``numpy.ndarray`` for an (N, 2) array of points, the
default of none: not declared): a study pairing it with a method that takes other data (the type its family's
validator returns, ``methods.register(validator=...)``; a method without one takes points) is refused when the
config is loaded (``experiments.schema.check_data_kinds``), never run into ``skipped`` rows. A source whose truth
names a shape (``truth["family"]``) declares it with ``family`` (``"circle"``): a study pairing it with a method of
another family (a circle fit on a square outline) is refused the same way, unless the method's entry says
``any_family = true``; whatever is declared, a row never gets errors against a truth of another family
(``experiments.rows``: its message says so).

Third-party packages register sources through the entry-point group ``fitbench.datasets`` (the entry
point names a module that registers on import); the engine loads them before it checks any config.
"""
from __future__ import annotations

import inspect
import json
import os
import typing
from dataclasses import dataclass, field
from decimal import Decimal
from pathlib import Path
from typing import Any, Callable, Literal

import numpy as np

from datasets.synthetic import NonNegative
from methods import immutable
from methods.plugins import add_entry, load_entry_points

ENTRY_POINT_GROUP = "fitbench.datasets"


@dataclass(frozen=True)
class DataSource:
    """A registered data source: ``load(rng, **params) -> (data, truth | None)``; data that is an array comes
    back immutable (``methods.immutable``): no method can change it, and the fits of a row copy nothing."""

    name: str
    func: Callable = field(repr=False)
    random: bool
    summary: str
    module: str
    #: data files the output depends on, given the params (hashed into the cache key)
    files: Callable[..., list] | None = field(default=None, repr=False)
    #: the type of the data it gives (``numpy.ndarray``: an (N, 2) array of points); None: not declared
    gives: type | None = None
    #: the family of the shape its data are drawn from, as its truth names it (``truth["family"]``); None: not declared
    family: str | None = None

    def load(self, rng, **params):
        data, truth = self.func(rng, **params)
        return (immutable(data) if isinstance(data, np.ndarray) else data), truth

    @property
    def builtin(self) -> bool:
        """True for fitbench's own sources (the ``datasets`` package), False for a plugin's."""
        return self.module == "datasets" or self.module.startswith("datasets.")

    @property
    def parameters(self) -> list[str]:
        return [p for p in inspect.signature(self.func).parameters if p != "rng"]

    def parameter_types(self) -> dict[str, tuple]:
        """{parameter: (type, default)}: the type its annotation declares, else the type of its default (as a
        method's parameters, ``methods.check_param``: bool, int, float taking ints too, str, a list of them);
        ``typing.Any`` when neither says. The default is ``inspect.Parameter.empty`` for a required parameter.
        Raises ValueError when an annotation cannot be resolved."""
        try:
            hints = typing.get_type_hints(self.func, include_extras=True)
        except Exception as exc:  # a string annotation naming what the source's module does not define
            raise ValueError(f"data source {self.name!r}: its parameter annotations cannot be resolved "
                             f"({type(exc).__name__}: {exc})") from None
        params = inspect.signature(self.func).parameters
        return {name: (hints.get(name, type_of_default(p.default)), p.default) for name, p in params.items()
                if name != "rng" and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)}


def type_of_default(value):
    """The type a parameter's default declares when the parameter has no annotation (``typing.Any`` for none)."""
    if value is inspect.Parameter.empty or value is None:
        return Any
    for kind in (bool, int, float, str):
        if isinstance(value, kind):
            return kind
    if isinstance(value, (list, tuple)):
        kinds = {type_of_default(v) for v in value}
        if kinds == {int, float}:
            kinds = {float}
        return list[kinds.pop()] if len(kinds) == 1 else list
    if isinstance(value, dict):
        return dict
    return Any


_REGISTRY: dict[str, DataSource] = {}


def register_source(name: str, *, random: bool, summary: str, files: Callable | None = None,
                    gives: type | None = None, family: str | None = None):
    """Register ``func(rng, **params) -> (data, truth)`` as data source ``name``; ``gives``: the type of its data
    (``numpy.ndarray`` for points), ``family``: the family its truth names (``"circle"``), both checked against the
    methods a study pairs it with before any row runs."""
    if gives is not None and not isinstance(gives, type):
        raise ValueError(f"data source {name!r}: gives must be a type (numpy.ndarray for points), got {gives!r}")
    if family is not None and (not isinstance(family, str) or not family.isidentifier()):
        raise ValueError(f"data source {name!r}: family must be a family name as methods' ids begin with it "
                         f"('circle'), got {family!r}")

    def deco(func):
        if name in _REGISTRY and _REGISTRY[name].func is not func:
            raise ValueError(f"data source {name!r} is already registered (by {_REGISTRY[name].module})")
        add_entry(_REGISTRY, name, DataSource(name=name, func=func, random=random, summary=summary,
                                              module=func.__module__, files=files, gives=gives, family=family))
        return func
    return deco


def load_plugins() -> None:
    """Import every entry point of ``fitbench.datasets`` once (a broken plugin warns, see
    :func:`methods.plugins.load_entry_points`)."""
    load_entry_points(ENTRY_POINT_GROUP, "data source")


def get_source(name: str) -> DataSource:
    load_plugins()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise KeyError(f"unknown data source {name!r}; known: {', '.join(sorted(_REGISTRY))}") from None


def list_sources() -> list[DataSource]:
    load_plugins()
    return [s for _, s in sorted(_REGISTRY.items())]


# ---------------------------------------------------------------- built-in sources

def _register_builtins():
    import datasets
    from datasets.io import read_points
    from datasets.synthetic import GENERATORS

    for gen_name, gen in GENERATORS.items():  # each draws the shape it is named after (its truth's family)
        register_source(gen_name, random=True, summary=(gen.__doc__ or "").strip().splitlines()[0],
                        gives=np.ndarray, family={"circle": "circle", "ellipse": "ellipse"}.get(gen_name))(gen)

    def _published_files(name, variant=None):
        return [datasets.PUBLISHED_DIR / f"{name}.csv", datasets.PUBLISHED_DIR / f"{name}.json"]

    @register_source("published", random=False, summary="a published data set shipped with fitbench",
                     files=_published_files, gives=np.ndarray)
    def published(rng=None, *, name: str, variant: Literal["drop_repeated_closing_point"] | None = None):
        """Points of a published set (``variant = "drop_repeated_closing_point"`` drops a repeated last point)."""
        ds = datasets.load(name, drop_repeated_closing_point=variant == "drop_repeated_closing_point")
        return ds.points, None

    @register_source("file", random=False, summary="points read from a file (CSV, whitespace, ...)",
                     files=lambda path, **reading: [path], gives=np.ndarray)
    def file(rng=None, *, path, truth=None, columns=None, plane=None, unit=None, skip_rows=0):
        """Points of ``path`` (any format ``datasets.read_points`` reads, with its options: by default x, y from the
        header, and a header naming x, y and z needs ``plane`` or ``columns``), with an optional truth table."""
        return read_points(path, None if columns is None else tuple(columns), plane=plane, unit=unit,
                           skip_rows=skip_rows), truth

    def _nist_files(name):
        folder = nist_folder()
        return [folder / f"{name}.csv", folder / f"{name}.json"]

    @register_source("nist", random=False, summary="a NIST Circle2d set (FITBENCH_NIST_DIR)", files=_nist_files,
                     gives=np.ndarray, family="circle")
    def nist(rng=None, *, name: str):
        """Points of NIST set ``name``; truth = NIST's reference least-squares circle (certified digits)."""
        folder = nist_folder()
        meta = json.loads((folder / f"{name}.json").read_text())
        ref = meta["reference_least_squares"]
        truth = {"family": "circle", "center": [float(Decimal(v)) for v in ref["center"]],
                 "radius": float(Decimal(ref["diameter"])) / 2}
        return read_points(folder / f"{name}.csv"), truth

    _register_simulators()


def _register_simulators():
    """The machine-tool simulators: their data are the inputs of the circular-test, positioning,
    magnification and multilateration methods (truth: what the simulator injected)."""
    from datasets import circular_test as ct
    from datasets import contouring
    from datasets import multilateration as ml
    from datasets import positioning as pos

    @register_source("circular_test", random=True,
                     summary="ISO 230-4 circular test of the LOLA HBG 130 scenario (both runs, or one path)",
                     gives=np.ndarray)
    def circular_test(rng, *, scenario: Literal["lola_hbg130"] = "lola_hbg130",
                      path: Literal["both", "cw", "ccw"] = "both"):
        """Points of a simulated circular test; ``path`` is 'both', 'cw' or 'ccw'."""
        if scenario != "lola_hbg130" or path not in ("both", "cw", "ccw"):
            raise ValueError("circular_test: scenario must be 'lola_hbg130' and path 'both', 'cw' or 'ccw'")
        cond, err = ct.lola_hbg130()
        cw, ccw, truth = ct.circular_test(cond, err, seed=int(rng.integers(2 ** 63)))
        return {"both": np.vstack([cw, ccw]), "cw": cw, "ccw": ccw}[path], truth

    def positioning(rng, **params):
        """A simulated axis test (``datasets.positioning.axis_test`` parameters)."""
        return pos.axis_test(rng=rng, **params)

    positioning.__signature__ = inspect.signature(pos.axis_test)
    register_source("positioning", random=True, summary="ISO 230-2 positioning test of a simulated axis",
                    gives=pos.PositioningData)(positioning)

    from methods.magnify.data import MagnifyInput

    @register_source("contouring", random=False, summary="a reference and a measured contouring trajectory",
                     gives=MagnifyInput)
    def contouring_example(rng=None, *, example: str):
        """Example ``example`` of ``datasets.contouring.EXAMPLES`` as a magnify input."""
        ref, meas = contouring.EXAMPLES[example]()
        return MagnifyInput(ref, meas), None

    contouring_example.__annotations__["example"] = Literal[tuple(contouring.EXAMPLES)]  # the names it knows

    @register_source("multilateration", random=True, summary="a simulated multilateration campaign",
                     gives=ml.MultilaterationData)
    def multilateration(rng, *, stations: int | list[int] = 6, grid: tuple[int, int, int] = (5, 4, 4),
                        noise: NonNegative = 1.0, errors: Literal["default", "none"] = "default"):
        """A simulated campaign (``datasets.multilateration.simulate``; errors = 'none' for a perfect machine)."""
        return ml.simulate(rng=rng, stations=tuple(stations) if isinstance(stations, list) else stations,
                           grid=tuple(grid), noise=noise, errors=None if errors == "none" else errors)


def nist_folder() -> Path:
    """The NIST Circle2d folder (``FITBENCH_NIST_DIR``)."""
    folder = os.environ.get("FITBENCH_NIST_DIR")
    if not folder or not Path(folder).is_dir():
        raise FileNotFoundError("set FITBENCH_NIST_DIR to the folder of the NIST Circle2d sets "
                                "(nist_cir2d_*.csv with their .json, made by python -m datasets.nist_circle2d "
                                "from NIST's Circle2d reference pairs; docs/methods.md)")
    return Path(folder)


_register_builtins()
