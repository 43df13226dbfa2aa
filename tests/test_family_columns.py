"""Families own their results and columns: a plugin family, and a plugin method of a built-in family with a column
of its own, declare their columns the way the built-in families do (``COLUMNS`` of their result class), and the
registry, the engine's rows, verify's tolerances, the summary and the gate read them from there. A column has one
declaration: a class that redeclares one with another unit or tolerance is refused when it is defined."""
from __future__ import annotations

import ast
import gc
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from experiments import metrics, summary
from experiments.rows import fit_row
from methods import register, result_base, results
from methods._registry import _REGISTRY

REPO = Path(__file__).resolve().parents[1]
SQUARE = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0], [1.0, 0.0], [2.0, 1.0], [1.0, 2.0], [0.0, 1.0]])


def _task(method: str) -> dict:
    return {"study": "plugin_columns", "dataset": {"label": "square"}, "repetition": 0, "seed": 1, "stream": (0,),
            "method": method, "params": {}}


@pytest.fixture
def plugin_family():
    """A family 'square' from outside fitbench: its result class declares a side (positive, geometry tolerance) and
    the side's error against the truth; two methods, an honest one and one that returns a negative side."""

    @dataclass(kw_only=True)
    class SquareFit(results.FitResult):
        center: tuple
        side: float

        FAMILY = "square"
        COLUMNS = (*results.FitResult.COLUMNS, *results.geometry_columns("side", check="positive"),
                   *results.error_columns("side_error"), *results.CENTER_ERROR_COLUMNS)
        SHAPES = {"center": (2,)}

        def geometry(self) -> dict:
            return {"side": self.side}

        def truth_errors(self, truth: dict) -> dict:
            return {**results.center_errors(self.center, truth), "side_error": self.side - truth["side"]}

    def square(points, shrink=1.0):
        lo, hi = points.min(axis=0), points.max(axis=0)
        side = float((hi - lo).mean()) * shrink
        return SquareFit(center=tuple((lo + hi) / 2), side=side, form_error=0.0, residuals=np.zeros(len(points)),
                         converged=True, message="bounding box")

    register("square.bounding_box", kind="closed form", summary="the bounding box's mean side (test plugin)",
             reference="fitbench tests")(square)
    register("square.negative", kind="closed form", summary="a negative side (test plugin)",
             reference="fitbench tests")(lambda points: square(points, shrink=-1.0))
    yield SquareFit
    for method_id in ("square.bounding_box", "square.negative"):
        _REGISTRY.pop(method_id, None)
    del SquareFit, square
    gc.collect()  # the class leaves FitResult.__subclasses__() and so the registry of columns


def test_a_plugin_family_declares_its_columns_like_a_built_in_one(plugin_family):
    assert results.contract("square") is plugin_family
    side = result_base.row_columns()["side"]
    assert (side.unit, side.tolerance, side.check, side.truth_error) == ("mm", results.GEOMETRY, "positive", False)
    assert "side_error" in result_base.truth_error_columns()
    assert metrics.tolerance("side") == results.GEOMETRY and metrics.tolerance("side_error") == results.ERRORS
    # the engine's row carries the declared columns, the summary reports the declared errors' bias and RMSE; the
    # centre error is declared as the length of (center_error_x, center_error_y): its bias is the mean vector's length
    rows = [fit_row(_task("square.bounding_box"), SQUARE * scale, {"side": 2.0, "center": center})
            for scale, center in ((1.0, (0.5, 1.0)), (1.5, (2.0, 1.5)))]
    assert [r["status"] for r in rows] == ["ok", "ok"] and [r["side"] for r in rows] == [2.0, 3.0]
    assert [r["side_error"] for r in rows] == [0.0, 1.0] and [r["center_error_x"] for r in rows] == [0.5, -0.5]
    table = summary.summarise(pd.DataFrame(rows), ["method"])
    assert table.loc[0, "side_bias"] == 0.5 and table.loc[0, "side_rmse"] == pytest.approx(np.sqrt(0.5))
    assert table.loc[0, "center_bias"] == 0.0 and table.loc[0, "center_rmse"] == 0.5
    # the gate holds the family to its declarations
    bad = fit_row(_task("square.negative"), SQUARE, {"side": 2.0, "center": (1.0, 1.0)})
    assert bad["status"] == "invalid" and "side = -2 must be > 0" in bad["message"], bad


def test_a_plugin_method_of_a_built_in_family_adds_its_own_column():
    @dataclass(kw_only=True)
    class LobedCircleFit(results.CircleFit):
        lobes: int

        COLUMNS = (*results.CircleFit.COLUMNS, results.Column("lobes", "count", results.EXACT))

        def geometry(self) -> dict:
            return {**super().geometry(), "lobes": self.lobes}

    @register("circle.lobed_centroid", kind="closed form", summary="centroid circle and its lobes (test plugin)",
              reference="fitbench tests")
    def lobed(points):
        c = points.mean(axis=0)
        base = results.circle_result(points, c, float(np.hypot(*(points - c).T).mean()), converged=True,
                                     message="closed form")
        return LobedCircleFit(**{f.name: getattr(base, f.name) for f in fields(base)}, lobes=3)

    try:
        t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
        points = np.c_[5 + 2 * np.cos(t), -1 + 2 * np.sin(t)]
        row = fit_row(_task("circle.lobed_centroid"), points, {"center": (5.0, -1.0), "radius": 2.0})
        assert row["status"] == "ok" and row["lobes"] == 3 and row["radius"] == pytest.approx(2.0)
        lobes = result_base.row_columns()["lobes"]
        assert (lobes.unit, lobes.tolerance) == ("", results.EXACT) and metrics.tolerance("lobes") == results.EXACT
        assert results.contract("circle") is results.CircleFit  # the family's contract stays the built-in one
    finally:
        _REGISTRY.pop("circle.lobed_centroid", None)


def test_a_column_has_one_declaration():
    """A class that redeclares a built-in column with another tolerance, unit or summary role is refused when it
    is defined, with what to do; the same declaration (or another ``check``, which the family's gate overrides)
    is accepted."""
    with pytest.raises(results.DeclarationError, match=r"'radius'.*not compared.*methods\.circle\.results\.CircleFit"
                                                        r".*another name"):
        @dataclass(kw_only=True)
        class LooseRadius(results.CircleFit):
            COLUMNS = (results.Column("radius", "length", None),)
    with pytest.raises(results.DeclarationError, match="'center_error'"):
        @dataclass(kw_only=True)
        class CentreErrorInDegrees(results.FitResult):
            COLUMNS = (results.Column("center_error", "angle", results.ERRORS, "", truth_error=True),)

    @dataclass(kw_only=True)
    class SameRadius(results.CircleFit):
        COLUMNS = (*results.CircleFit.COLUMNS, results.Column("radius", "length", results.GEOMETRY, ""))
    assert result_base.row_columns()["radius"].check == "positive"


def test_a_plugin_class_defined_before_the_families_is_checked_when_they_load():
    """A class defined on the contract alone (no family loaded yet) is checked again once the families load."""
    from conftest import run_python
    probe = ("from dataclasses import dataclass\n"
             "from methods import result_base as rb\n"
             "@dataclass(kw_only=True)\n"
             "class Early(rb.FitResult):\n"
             "    COLUMNS = (rb.Column('radius', 'length', None),)\n"
             "try:\n    rb.row_columns()\nexcept rb.DeclarationError as exc:\n    print('refused:', exc)\n")
    out = run_python("-c", probe)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("refused: __main__.Early declares the column 'radius'"), out.stdout


def test_the_families_own_their_result_classes():
    """The contract names no family: every built-in result class is defined in its family's own results module
    (``methods/<family>/results.py``), every family with registered methods has one, and methods.results
    re-exports what each of them exports."""
    import importlib

    import methods
    tree = ast.parse((REPO / "methods" / "result_base.py").read_text(encoding="utf-8"))
    assert [n.name for n in ast.walk(tree) if isinstance(n, ast.ClassDef)] == ["Tolerance", "Column",
                                                                               "DeclarationError", "FitResult"]
    modules = result_base.family_modules()
    families = {m.split(".")[1] for m in modules}
    assert {s.family for s in methods.list_methods() if s.module.startswith("methods.")} <= families
    for cls in result_base.result_classes():
        if cls.__module__.startswith("methods.") and cls is not results.FitResult:
            assert cls.__module__ in modules and cls.FAMILY == cls.__module__.split(".")[1], cls
    for name in modules:
        module = importlib.import_module(name)
        assert module.__all__ and all(getattr(results, public) is getattr(module, public) for public in module.__all__)


@pytest.mark.parametrize("source", ["experiments/metrics.py", "experiments/summary.py", "experiments/engine.py",
                                    "experiments/rows.py", "experiments/compare.py", "experiments/verify.py"])
def test_the_framework_names_no_family_column(source):
    """The engine, the metrics, the summary and verify read the families' columns from their declarations: no
    string in them names a column a family declares (the base class's form error and residual RMS aside)."""
    family_columns = set(result_base.row_columns()) - {c.name for c in results.FitResult.COLUMNS}
    tree = ast.parse((REPO / source).read_text(encoding="utf-8"))
    named = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)}
    assert not named & family_columns, sorted(named & family_columns)
