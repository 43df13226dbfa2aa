"""A method raising GeneratorExit raised an exception: its row is ``error`` naming it, as for any other exception
(docs/results.md), not ``crashed`` (a row that raised SystemExit or KeyboardInterrupt, or whose process died),
whether the row runs alone (run_task) or in a batch (the generic rows of a chunk)."""
import pytest

from experiments import rows
from plugin_methods import plugin_here

CODE = '''
from methods import register


@register("circle.raise_generator_exit", kind="closed form", summary="raises GeneratorExit", reference="a test")
def raise_generator_exit(points):
    raise GeneratorExit("closed")


@register("circle.raise_system_exit", kind="closed form", summary="raises SystemExit", reference="a test")
def raise_system_exit(points):
    raise SystemExit(3)
'''


@pytest.fixture
def raisers():
    with plugin_here(CODE, "fitbench_generator_exit_test") as namespace:
        yield namespace


def _task(method, index=0):
    spec = {"label": "ring", "source": "circle", "params": {"radius": 5.0, "noise": 0.01, "n": 30}}
    return {"study": "raisers", "kind": "grid", "dataset": spec, "repetition": 0, "stream": [0, 0, 0], "seed": 3,
            "params": {}, "method": method, "timing": None, "index": index}


def test_a_row_raising_generator_exit_is_an_error_alone_and_in_a_batch(raisers):
    alone = rows.run_task(_task("circle.raise_generator_exit"))
    assert (alone["status"], alone["message"]) == ("error", "GeneratorExit: closed")
    batch = rows._generic_rows([_task("circle.kasa", 0), _task("circle.raise_generator_exit", 1)], 0, None)
    assert [r["status"] for r in batch] == ["ok", "error"]
    assert batch[1]["message"] == "GeneratorExit: closed"


def test_a_row_raising_system_exit_is_still_crashed(raisers):
    row = rows.run_task(_task("circle.raise_system_exit"))
    assert (row["status"], row["message"]) == ("crashed", "the row raised SystemExit(3)")
