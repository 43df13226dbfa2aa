"""A plugin's result class cannot compute the row's family columns: the errors against the truth and the geometry of
a row come from fitbench's own class on the values the gate checked (a subclass adds columns of its own only)."""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
import pytest

from experiments.rows import fit_row
from methods import check_result, results
from plugin_methods import registered

T = np.linspace(0.0, np.pi / 2, 30)
ARC = np.c_[1.0 + 5.0 * np.cos(T), 2.0 + 5.0 * np.sin(T)]  # a 90-degree arc of a circle of radius 5 about (1, 2)
TRUTH = {"center": (1.0, 2.0), "radius": 5.0}


def _task(method: str) -> dict:
    return {"study": "plugin_result_class", "dataset": {"label": "arc"}, "repetition": 0, "seed": 1, "stream": (0,),
            "method": method, "params": {}}


def _centroid(points, cls=results.CircleFit, **extra):
    """An honest but poor fit (the centroid of an arc and the mean distance from it) as ``cls``."""
    c = points.mean(axis=0)
    base = results.circle_result(points, c, float(np.hypot(*(points - c).T).mean()), converged=True,
                                 message="closed form")
    return cls(**{f.name: getattr(base, f.name) for f in fields(base)}, **extra)


@dataclass(kw_only=True)
class FlatteringFit(results.CircleFit):
    """Reports zero errors against the truth, and one column of its own."""

    def truth_errors(self, truth):
        out = {k: 0.0 for k in super().truth_errors(truth)}
        return {**out, "radius_error": 0.0, "flattery": 1.0}


@dataclass(kw_only=True)
class TwoFacedFit(results.CircleFit):
    """Reports a geometry other than its checked fields."""

    def geometry(self):
        g = super().geometry()
        return {**g, "radius": g["radius"] * 1.5, "center_x": g["center_x"] + 1.0}


@dataclass(kw_only=True)
class ExtraColumnFit(results.CircleFit):
    """An honest subclass adding a column (what docs/plugins.md shows)."""

    lobes: int = 3
    COLUMNS = (*results.CircleFit.COLUMNS, results.Column("plugin_class_lobes", "count", results.EXACT))

    def geometry(self):
        return {**super().geometry(), "plugin_class_lobes": self.lobes}


class LyingFloat(float):
    """A float whose arithmetic lies: radius - truth is always 0."""

    def __sub__(self, other):
        return 0.0


@pytest.fixture
def methods_of_a_plugin():
    ids = {"circle.pr_zero_error": lambda p: _centroid(p, FlatteringFit),
           "circle.pr_two_faced": lambda p: _centroid(p, TwoFacedFit),
           "circle.pr_extra": lambda p: _centroid(p, ExtraColumnFit),
           "circle.pr_honest": lambda p: _centroid(p)}

    def lying(points):
        res = _centroid(points)
        res.radius = LyingFloat(res.radius)
        return res
    ids["circle.pr_lying_float"] = lying
    with registered(ids, kind="closed form", summary="a test plugin's centroid fit", reference="fitbench tests"):
        yield


def test_a_subclass_cannot_compute_its_own_errors_against_the_truth(methods_of_a_plugin):
    honest = fit_row(_task("circle.pr_honest"), ARC, TRUTH)
    assert honest["status"] == "ok" and abs(honest["radius_error"]) > 1.0  # the centroid of an arc is far off
    for mid in ("circle.pr_zero_error", "circle.pr_lying_float"):
        row = fit_row(_task(mid), ARC, TRUTH)
        assert row["status"] == "ok", row
        for col in ("radius_error", "center_error", "center_error_x", "center_error_y"):
            assert row[col] == honest[col], (mid, col, row[col], honest[col])
    # its own column is kept; it cannot add a family column the truth does not give
    row = fit_row(_task("circle.pr_zero_error"), ARC, {"center": (1.0, 2.0)})
    assert row["flattery"] == 1.0 and "radius_error" not in row


def test_the_geometry_of_a_row_is_what_the_gate_checked(methods_of_a_plugin):
    row = fit_row(_task("circle.pr_two_faced"), ARC, TRUTH)
    assert row["status"] == "invalid", row
    assert "reports center_x = " in row["message"] and "which the gate checks against the data" in row["message"], row
    # the API's gate says the same (methods.fit of a plugin's method)
    res = _centroid(ARC, TwoFacedFit)
    res.method = "circle.pr_two_faced"
    assert "reports center_x" in check_result(res, ARC)


def test_a_subclass_adds_its_own_columns(methods_of_a_plugin):
    row = fit_row(_task("circle.pr_extra"), ARC, TRUTH)
    honest = fit_row(_task("circle.pr_honest"), ARC, TRUTH)
    assert row["status"] == "ok" and row["plugin_class_lobes"] == 3
    assert {k: v for k, v in row.items() if k not in ("plugin_class_lobes", "method")} == \
        {k: v for k, v in honest.items() if k != "method"}
    assert list(row).index("plugin_class_lobes") == list(row).index("radius") + 1  # after the geometry, as it came
