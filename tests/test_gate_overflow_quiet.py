"""The result gate tells an overflowing residual RMS in its message, never by a stray RuntimeWarning: pytest's
warnings-as-errors (and a user's ``-W error``) turned a plugin's result on data at 1e300 into a crash of the gate."""
import warnings

import numpy as np

from methods.results import check_result, circle_result


def test_an_overflowing_residual_sum_is_told_without_a_warning():
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    pts = np.c_[1e300 * np.cos(t), 1e300 * np.sin(t)] * 0.5
    pts[::2] *= 1.2                                 # residuals of ~1e299: their squares overflow float64
    res = circle_result(pts, np.zeros(2), 0.5e300, converged=True, message="ok")
    res.method = "circle.kasa"
    with np.errstate(over="warn"), warnings.catch_warnings():
        warnings.simplefilter("error")
        problem = check_result(res, pts)
    assert problem.startswith("the residual RMS overflows float64"), problem
