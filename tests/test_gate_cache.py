"""The result gate remembers each family's contract class and column declarations (it runs for every row):
what it remembers must follow the classes defined, collected or re-declared since."""
import gc
from dataclasses import dataclass

import numpy as np

from methods import result_base, results


def test_contract_follows_classes_defined_and_collected():
    assert result_base.contract("gatecachefam") is None  # remembered as none

    @dataclass(kw_only=True)
    class GateCacheFit(results.FitResult):
        FAMILY = "gatecachefam"

    assert result_base.contract("gatecachefam") is GateCacheFit  # a class defined since is found
    bad = results.FitResult(method="gatecachefam.x", converged=True, form_error=0.0)
    assert "must return a GateCacheFit" in result_base.check_result(bad)
    del GateCacheFit, bad
    gc.collect()
    assert result_base.contract("gatecachefam") is None  # a collected class is no longer the contract


def test_declarations_follow_a_redeclared_columns_tuple():
    @dataclass(kw_only=True)
    class GateCacheCols(results.FitResult):
        side: float = 1.0
        FAMILY = "gatecachecols"
        # a column name of its own: the class lives on until the next garbage collection, and the first
        # declaration of a name is the row column's (tests/test_family_columns.py declares a "side")
        COLUMNS = (*results.FitResult.COLUMNS, *results.geometry_columns("gate_cache_side", check="positive"))

        def geometry(self):
            return {"gate_cache_side": self.side}

    res = GateCacheCols(method="gatecachecols.x", converged=True, form_error=0.0, side=-1.0)
    assert "gate_cache_side = -1 must be > 0" in result_base.check_result(res)
    GateCacheCols.COLUMNS = (*results.FitResult.COLUMNS, *results.geometry_columns("gate_cache_side", check="finite"))
    assert result_base.check_result(res) is None


def test_extra_fast_path_and_full_serialisation_agree():
    @dataclass(kw_only=True)
    class GateCacheExtra(results.FitResult):   # the gate refuses a family no result class declares
        FAMILY = "gatecacheextra"

    base = dict(method="gatecacheextra.y", converged=True, form_error=0.0, residuals=np.zeros(0))
    plain = GateCacheExtra(**base, extra={"a": [1.0, np.float64(2.0), float("nan")], "b": True, "c": None})
    assert result_base.check_result(plain) is None
    for extra in ({"a": [object()]}, {"a": object()}, {1: {"x": {1, 2}}}):
        assert "extra is not JSON-serialisable" in result_base.check_result(GateCacheExtra(**base, extra=extra))
