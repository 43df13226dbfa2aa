"""``methods.fit`` checks its parameters as a study's TOML does (``MethodSpec.check_params``): a value of the wrong
type is an :class:`~methods.InvalidInputError` saying what is expected, never a TypeError from inside the method
(``xtol="1e-3"``) nor a fit silently run with another value (``max_iter=2.5`` ran 2 iterations, ``max_iter=True`` one,
``gtol="1"`` was accepted). NumPy's integer and float scalars are numbers (a grid made with ``np.arange``)."""
import numpy as np
import pytest

import methods
from methods import InvalidInputError


@pytest.fixture(scope="module")
def arc():
    t = np.linspace(0.0, np.pi / 2, 25)
    wobble = 1e-3 * np.cos(5 * t)
    return np.c_[1200 + (299 + wobble) * np.cos(t), 650 + (299 + wobble) * np.sin(t)]


@pytest.mark.parametrize("param, value, expected", [
    ("xtol", "1e-3", "must be a number"), ("gtol", "1", "must be a number"), ("xtol", [1e-3], "must be a number"),
    ("xtol", True, "must be a number"), ("xtol", np.bool_(True), "must be a number"), ("xtol", None, "must be a number"),
    ("xtol", float("nan"), "must be finite"), ("xtol", -1.0, "must be a finite number >= 0"),
    ("max_iter", 2.5, "must be an integer"), ("max_iter", 2.0, "must be an integer"), ("max_iter", True, "must be an integer"),
    ("max_iter", "5", "must be an integer"), ("max_iter", np.float64(5), "must be an integer"),
    ("max_iter", 0, "must be a positive finite number")])
def test_a_parameter_of_the_wrong_type_is_refused_saying_what_is_expected(arc, param, value, expected):
    spec = methods.get("circle.gauss_newton")
    default = spec.defaults[param]
    for call in (lambda: methods.fit("circle.gauss_newton", arc, **{param: value}),
                 lambda: spec(arc, **{param: value})):
        with pytest.raises(InvalidInputError) as info:
            call()
        text = str(info.value)
        assert text.startswith(f"circle.gauss_newton: parameter {param}={value!r} {expected}"), text
        assert "\n" not in text
        if "integer" in expected or "number (" in expected:
            assert f"(the default is {default!r})" in text


def test_numpy_numbers_are_numbers_and_give_the_same_fit(arc):
    plain = methods.fit("circle.gauss_newton", arc, max_iter=5, xtol=float(np.float32(1e-6)), gtol=1e-8)
    numpy = methods.fit("circle.gauss_newton", arc, max_iter=np.int64(5), xtol=np.float32(1e-6),
                        gtol=np.float64(1e-8))
    assert numpy.radius == plain.radius and numpy.iterations == plain.iterations
    as_int = methods.fit("circle.gauss_newton", arc, xtol=1)   # an int for a float parameter, as in a TOML
    assert as_int.radius == methods.fit("circle.gauss_newton", arc, xtol=1.0).radius


def test_none_is_a_value_where_the_method_declares_it(arc):
    """roundness.iso12181's ``cutoff_upr=None`` means no filter (what ``fitbench roundness --cutoff none`` passes);
    a string or a bool there is refused like any other number parameter's."""
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    ring = np.c_[(10 + 1e-3 * np.cos(7 * t)) * np.cos(t), (10 + 1e-3 * np.cos(7 * t)) * np.sin(t)]
    assert methods.fit("roundness.iso12181", ring, cutoff_upr=None).cutoff_upr is None
    for bad in ("abc", True, -50.0):
        with pytest.raises(InvalidInputError, match=r"roundness.iso12181: parameter cutoff_upr="):
            methods.fit("roundness.iso12181", ring, cutoff_upr=bad)
