"""The result gate's quick paths (methods.check_result: Python floats and ints, tuples of two floats, float64
arrays, a dict geometry, the validated points) decide exactly as its general code: every lie and every honest
value gets the same verdict, word for word, whether it comes in the type a built-in result holds or in another
type that takes the general code (a float subclass, numpy scalars, a list, an ndarray subclass, a mapping that
is no dict, a subclass result)."""
import re
from dataclasses import dataclass, fields
from types import MappingProxyType

import numpy as np
import pytest

import methods
from methods import results

ANGLES = np.linspace(0, 2 * np.pi, 40, endpoint=False)
RADII = 299 + np.random.default_rng(2).normal(scale=1e-3, size=40)   # mm: a machine-tool circle, µm deviations
CIRCLE = np.column_stack([1200 + RADII * np.cos(ANGLES), 650 + RADII * np.sin(ANGLES)])
NAN, INF = float("nan"), float("inf")


class Real(float):
    """A float of another type: the quick paths take only ``float`` itself."""


class Array(np.ndarray):
    """An ndarray of another type: the quick paths take only ``np.ndarray`` itself."""


class Text(str):
    """A method id of another type."""


@dataclass(kw_only=True)
class MappedCircleFit(results.CircleFit):
    """A plugin's circle whose geometry is a read-only mapping, not a dict: the general path of the values."""

    def geometry(self):
        return MappingProxyType(super().geometry())


@dataclass(kw_only=True)
class LobedCircleFit(results.CircleFit):
    """A plugin's circle with a column of its own (and the family's declarations over its own)."""

    lobes: int = 3
    COLUMNS = (*results.CircleFit.COLUMNS, results.Column("gate_fast_lobes", "count", results.EXACT, "nonnegative"))

    def geometry(self):
        return {**super().geometry(), "gate_fast_lobes": self.lobes}


def honest(cls=results.CircleFit, **changes):
    base = results.circle_result(CIRCLE, (1200.0, 650.0), 299.0, converged=True, message="exact")
    res = cls(**{f.name: getattr(base, f.name) for f in fields(base)})
    res.method = "circle.test"
    for k, v in changes.items():
        setattr(res, k, v)
    return res


def _twins(value):
    """``value`` (as a built-in result holds it) and the same value in types that take the general code."""
    if type(value) is float:
        same32 = float(np.float32(value)) == value or value != value  # float32 only where it holds the same number
        return [value, Real(value), np.float64(value)] + ([np.float32(value)] if same32 else [])
    if type(value) is tuple:
        return [value, list(value), np.array(value), tuple(map(np.float64, value)), tuple(map(Real, value))]
    if type(value) is np.ndarray:
        return [value, value.view(Array), np.repeat(value, 2)[::2]]
    if value is True or value is False:
        return [value, np.bool_(value)]
    if type(value) is int:
        return [value, np.int64(value), np.int32(value)]
    raise AssertionError(type(value))


HONEST = honest()
BAD_RESIDUALS = HONEST.residuals.copy()
BAD_RESIDUALS[7] = NAN
#: field -> values (honest ones and lies) in the type a built-in result holds them
CASES = {
    "radius": [299.0, -5.0, 0.0, -0.0, NAN, INF, -INF, 1e-300, 300.0],
    "form_error": [HONEST.form_error, -1.0, 0.0, NAN, INF, 1e-9],
    "center": [(1200.0, 650.0), (INF, 1e308), (NAN, 650.0), (1200.0, -INF), (1200.0, 650.001), (1.0, 2.0, 3.0), (1.0,)],
    "residuals": [HONEST.residuals, BAD_RESIDUALS, np.full(40, INF), HONEST.residuals + 1e-3, np.zeros(3),
                  np.nextafter(HONEST.residuals, np.inf)],
    "converged": [True, False],
    "iterations": [None, 0, 3, -3, True],
    "nfev": [None, 4, -1],
}
ITEMS = [(field, i) for field, values in CASES.items() for i in range(len(values))]


def _verdicts(field, value, converged=True, cls=results.CircleFit, points=CIRCLE):
    """The gate's verdicts on ``value`` in each of its types (a reason that names the value's type, "got int -3",
    names it "got <type>")."""
    twins = _twins(value) if value is not None else [None]
    out = [methods.check_result(honest(cls, **{"converged": converged, field: v}), points) for v in twins]
    return [v if v is None else re.sub(r", got \w+ .*$", ", got <type>", v) for v in out]


@pytest.mark.parametrize("converged", [True, False])
@pytest.mark.parametrize("field,i", ITEMS)
def test_a_value_gets_the_same_verdict_in_every_type(field, i, converged):
    value = CASES[field][i]
    if field == "converged":
        converged = value
    got = _verdicts(field, value, converged)
    assert all(v == got[0] for v in got[1:]), got
    lie = (field == "radius" and not (isinstance(value, float) and value > 0 and value < INF)
           or field == "iterations" and value in (-3, True) or field == "nfev" and value == -1
           or field == "center" and len(value) != 2 or field == "residuals" and len(value) != 40)
    if lie and converged:
        assert got[0] is not None and "\n" not in got[0]


def test_the_lies_of_a_converged_result_are_refused_whatever_their_type():
    """Every quick path refuses what the general code refuses: NaN, inf, a negative radius, a wrong shape."""
    for field, value, reason in (("radius", NAN, "radius = nan is not finite in a converged result"),
                                 ("radius", -INF, "radius = -inf is not finite in a converged result"),
                                 ("radius", -5.0, "radius = -5 must be > 0"),
                                 ("radius", -0.0, "radius = -0 must be > 0"),
                                 ("form_error", -1.0, "form_error = -1 must be >= 0"),
                                 ("form_error", 1e-9, "form_error = 1e-09 but the points' radial span"),
                                 ("center", (NAN, 650.0), "center_x = nan is not finite"),
                                 ("center", (1200.0, -INF), "center_y = -inf is not finite"),
                                 ("center", (1.0, 2.0, 3.0), "center must have shape (2,), got (3,)"),
                                 ("residuals", BAD_RESIDUALS, "residuals are not finite in a converged result"),
                                 ("residuals", np.zeros(3), "residuals must have shape (40,), got (3,)"),
                                 ("residuals", HONEST.residuals + 1e-3, "residuals are not the radial distances"),
                                 ("iterations", -3, "iterations must be None or a count >= 0, got <type>"),
                                 ("iterations", True, "iterations must be None or a count >= 0, got <type>")):
        for verdict in _verdicts(field, value):
            assert verdict is not None and reason in verdict, (field, value, verdict)


@pytest.mark.parametrize("field,i", [item for item in ITEMS if item[0] in ("radius", "form_error", "center")])
def test_a_geometry_that_is_no_dict_and_a_subclass_get_the_same_verdicts(field, i):
    """A mapping geometry (the general path of the values) and a plugin's subclass with a column of its own."""
    value = CASES[field][i]
    for converged in (True, False):
        want = _verdicts(field, value, converged)
        assert _verdicts(field, value, converged, cls=MappedCircleFit) == want
        assert _verdicts(field, value, converged, cls=LobedCircleFit) == want


def test_a_subclass_s_own_column_is_checked_in_every_type():
    for lobes, ok in ((3, True), (0, True), (-1, False), (3.5, True), (NAN, False), (INF, False)):
        for v in ([lobes, np.float64(lobes)] if isinstance(lobes, float) else [lobes, np.int64(lobes), float(lobes)]):
            verdict = methods.check_result(honest(LobedCircleFit, lobes=v), CIRCLE)
            assert (verdict is None) == ok, (v, verdict)
            if not ok:
                assert verdict.startswith("gate_fast_lobes = ")
    verdict = methods.check_result(honest(LobedCircleFit, lobes="3"), CIRCLE)
    assert verdict == "gate_fast_lobes must be a number, got str '3'"


def test_the_method_id_and_the_flags_in_other_types():
    assert methods.check_result(honest(method=Text("circle.test")), CIRCLE) is None
    ellipse_id = honest(method=Text("ellipse.test"))
    assert methods.check_result(ellipse_id, CIRCLE) == methods.check_result(honest(method="ellipse.test"), CIRCLE)
    assert "must return a EllipseFit" in methods.check_result(ellipse_id, CIRCLE)
    for converged in ("yes", 1, None, np.array([True])):
        assert methods.check_result(honest(converged=converged), CIRCLE).startswith("converged must be True or False")
    assert methods.check_result(honest(message=Text("exact")), CIRCLE) is None
    assert methods.check_result(honest(message=b"exact"), CIRCLE) == "message must be a string, got bytes b'exact'"
    assert methods.check_result(honest(extra=[]), CIRCLE) == "extra and params must be dicts"
    assert methods.check_result(honest(params=None), CIRCLE) == "extra and params must be dicts"


def test_points_of_another_type_get_the_same_verdicts():
    """The consistency's sweep takes the validated points (a C-contiguous float64 array) on its quick check; an
    ndarray subclass or another layout of the same points is checked as before."""
    for field, values in CASES.items():
        for value in values:
            want = _verdicts(field, value)
            for points in (CIRCLE.view(Array), np.asfortranarray(CIRCLE), CIRCLE.astype(">f8")):
                assert _verdicts(field, value, points=points) == want, (field, value)
