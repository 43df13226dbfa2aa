"""The result gate checks a zone's radii and contacts against the points: a plugin returning fitbench's ``ZoneFit``
with made-up ``inner_radius``/``outer_radius`` (row columns) was accepted with a zone of 2e-6 beside a form error
of 0.03; every built-in zone method's result still passes."""
from dataclasses import dataclass

import numpy as np
import pytest

import methods
from experiments.rows import fit_row
from methods import check_result, results
from plugin_methods import registered

T = np.linspace(0.0, 2 * np.pi, 30, endpoint=False)
PTS = np.column_stack([2.0 * np.cos(T), 2.0 * np.sin(T)]) + np.random.default_rng(3).normal(scale=0.01, size=(30, 2))
R = np.hypot(PTS[:, 0], PTS[:, 1])   # radial distances about the origin, the centre every zone below returns
TRUTH = {"center": (0.0, 0.0), "radius": 2.0}


def _zone(points, *, lie="none"):
    """A zone about the origin (the review's circle.zonelie plugin, and variants of its lie)."""
    r = np.hypot(points[:, 0], points[:, 1])
    contacts = {"outer": [int(np.argmax(r))], "inner": [int(np.argmin(r))]}
    z = results.zone_result(points, (0.0, 0.0), float(r.mean()), contacts, converged=True, message="zone")
    if lie == "radii":
        z.inner_radius, z.outer_radius = z.radius - 1e-6, z.radius + 1e-6
    elif lie == "outer radius":
        z.outer_radius += 1e-6
    elif lie == "contact not extreme":
        z.contacts = {"outer": [int(np.argsort(r)[-2])], "inner": contacts["inner"]}
    elif lie == "contact out of range":
        z.contacts = {"outer": [len(points)], "inner": contacts["inner"]}
    elif lie == "contacts not a dict":
        z.contacts = [1, 2]
    elif lie == "contact not an index":
        z.contacts = {"outer": [1.5], "inner": []}
    return z


LIES = {"radii": "inner_radius = ", "outer radius": "outer_radius = ",
        "contact not extreme": "not at the outer radius", "contact out of range": "not one of the 30 points",
        "contacts not a dict": "contacts must be {'outer'", "contact not an index": "must be a list of point indices"}


@pytest.fixture
def zone_plugin():
    methods.list_methods()
    with registered({"circle.test_gate_zone": _zone}, kind="closed form", summary="a zone", reference="gate test"):
        yield "circle.test_gate_zone"


def _task(method, **params):
    return {"study": "gate", "dataset": {"label": "ring"}, "repetition": 0, "seed": 1, "stream": (0,),
            "method": method, "params": params}


@pytest.mark.parametrize("lie", list(LIES))
def test_made_up_zone_radii_or_contacts_are_an_invalid_row(zone_plugin, lie):
    res = methods.get(zone_plugin).unchecked(PTS, lie=lie)
    problem = check_result(res, PTS)
    assert problem is not None and LIES[lie] in problem and "\n" not in problem, problem
    row = fit_row(_task(zone_plugin, lie=lie), PTS, TRUTH)
    assert row["status"] == "invalid" and LIES[lie] in row["message"], row


def test_an_honest_zone_passes(zone_plugin):
    res = methods.get(zone_plugin).unchecked(PTS)
    assert check_result(res, PTS) is None
    assert res.inner_radius == pytest.approx(R.min(), rel=1e-12) and res.outer_radius == pytest.approx(R.max(), rel=1e-12)
    row = fit_row(_task(zone_plugin), PTS, TRUTH)
    assert row["status"] == "ok" and row["outer_radius"] - row["inner_radius"] == pytest.approx(np.ptp(R), rel=1e-9)


def test_a_plugin_subclass_of_the_zone_is_held_to_it():
    """A plugin's subclass of ZoneFit (its own lenient consistency) is checked by ZoneFit's, in the gate and on the
    copy the engine makes of it."""
    @dataclass(kw_only=True)
    class Lenient(results.ZoneFit):
        consistency = staticmethod(lambda result, data: None)

    base = _zone(PTS, lie="radii")
    res = Lenient(**{k: getattr(base, k) for k in base.__dataclass_fields__})
    res.method = "circle.test_gate_zone"
    assert "inner_radius = " in check_result(res, PTS)
    from methods import result_base
    assert "inner_radius = " in check_result(result_base.family_copy(res), PTS)


ZONE_METHODS = ("circle.minimum_zone", "circle.max_inscribed", "circle.min_circumscribed", "circle.chebyshev_lp")


def _lobed(size, arc=360.0, n=40):
    t = np.radians(np.linspace(0.0, arc, n, endpoint=arc != 360.0))
    base = np.column_stack([np.cos(t), np.sin(t)]) * (1 + 0.01 * np.cos(3 * t))[:, None]
    return (base + 1e-3 * np.random.default_rng(1).standard_normal((n, 2)) + [2.0, -1.0]) * size


@pytest.mark.parametrize("data", ["size 1e-150", "size 1", "size 1e150", "half circle", "machine circle"])
@pytest.mark.parametrize("method_id", ZONE_METHODS)
def test_every_built_in_zone_passes(method_id, data):
    pts = {"size 1e-150": _lobed(1e-150), "size 1": _lobed(1.0), "size 1e150": _lobed(1e150),
           "half circle": _lobed(1.0, arc=180.0),
           "machine circle": np.column_stack([1200 + 299 * np.cos(T), 650 + 299 * np.sin(T)])
           + np.random.default_rng(2).normal(scale=1e-3, size=(30, 2))}[data]
    pts = methods.immutable(np.ascontiguousarray(pts))
    res = methods.get(method_id).unchecked(pts)
    assert isinstance(res, results.ZoneFit)
    assert check_result(res, pts) is None
