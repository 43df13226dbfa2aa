"""One shared validation, one exception type, messages that say what to do."""
import numpy as np
import pytest

import methods
from methods import InvalidInputError
from method_ids import method_ids

ALL = method_ids("circle")


@pytest.mark.parametrize("method_id", ALL)
@pytest.mark.parametrize("points, match", [
    ([[0, 0], [1, 1], [np.nan, 2]], "NaN or inf"),
    ([[0, 0], [1, 1], [np.inf, 2], [3, 1]], "NaN or inf"),
    ([[0, 0], [1, 1]], "at least 3 points"),
    ([[2, 3]] * 5, "identical"),
    ([[0, 0], [1, 1], [2, 2], [5, 5]], "straight line"),
    (np.zeros((5, 3)), r"\(N, 2\)"),
    (np.arange(10.0).reshape(2, 5), "transposed"),
    ([["a", "b"], ["c", "d"], ["e", "f"]], "not numeric"),
])
def test_bad_input_raises_one_clear_error(method_id, points, match):
    with pytest.raises(InvalidInputError, match=match):
        methods.fit(method_id, points)


def test_collinear_far_from_origin_and_duplicates_are_handled():
    line = np.column_stack([1e6 + np.arange(5.0), 2e6 + 2 * np.arange(5.0)])
    with pytest.raises(InvalidInputError, match="straight line"):
        methods.fit("circle.kasa", line)
    # duplicates are fine as long as three distinct non-collinear points remain
    pts = np.array([[1, 0], [0, 1], [-1, 0], [1, 0], [1, 0]], dtype=float)
    res = methods.fit("circle.gauss_newton", pts)
    assert res.converged and res.radius == pytest.approx(1.0, abs=1e-12)


def test_error_is_a_value_error():
    assert issubclass(InvalidInputError, ValueError)
