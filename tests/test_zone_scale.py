"""Zone methods at the ends of float64: radii 1e-300 ... 1e300 give the same circle as the
unit-size data scaled, and a certificate only where the result is right.

Reference: the same point set at size 1 (every zone method is equivariant under scaling: the optimum
of the scaled data is the scaled optimum); the certified flags must agree with the unit-size fit."""
import warnings

import numpy as np
import pytest

import methods

ZONE_METHODS = ("circle.minimum_zone", "circle.max_inscribed", "circle.min_circumscribed", "circle.chebyshev_lp")
SIZES = (1e-300, 1e-150, 1e150, 1e300)


def lobed_profile(n=40, seed=1):
    """A 3-lobed profile with noise about the origin, size 1 (no exact ties)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return (np.column_stack([np.cos(t), np.sin(t)]) * (1 + 0.01 * np.cos(3 * t))[:, None]
            + 1e-3 * rng.standard_normal((n, 2)))


@pytest.mark.parametrize("method", ZONE_METHODS)
@pytest.mark.parametrize("size", SIZES)
def test_zone_methods_at_extreme_scales(method, size):
    base = lobed_profile()
    ref = methods.fit(method, base)
    assert ref.converged and ref.extra["certified"] == "global"
    offset = np.array([2.0, -1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow / underflow warning may escape
        fit = methods.fit(method, (base + offset) * size)
    rel = 1e-9
    assert fit.radius == pytest.approx(ref.radius * size, rel=rel)
    assert fit.form_error == pytest.approx(ref.form_error * size, rel=1e-7)
    assert fit.inner_radius == pytest.approx(ref.inner_radius * size, rel=rel)
    assert fit.outer_radius == pytest.approx(ref.outer_radius * size, rel=rel)
    centre = np.array(fit.center) / size - offset
    assert np.abs(centre - np.array(ref.center)).max() <= 1e-9
    assert np.all(np.isfinite(fit.residuals))
    assert np.abs(fit.residuals / size - ref.residuals).max() <= 1e-9
    # the flag is a promise: here it is true (same optimum as the certified unit-size fit)
    assert fit.converged and fit.extra["certified"] == "global"
    assert "inf" not in fit.message and "nan" not in fit.message


@pytest.mark.parametrize("method", ZONE_METHODS)
def test_no_certificate_with_a_non_finite_radius(method):
    """Whatever the scale, a certified result has a finite, positive radius and finite residuals."""
    base = lobed_profile(n=24, seed=3)
    for size in (1e-307, 1e307):
        fit = methods.fit(method, base * size)
        if fit.converged:
            assert np.isfinite(fit.radius) and fit.radius > 0
            assert np.all(np.isfinite(fit.residuals))
            assert fit.radius == pytest.approx(methods.fit(method, base).radius * size, rel=1e-9)
        else:
            assert fit.extra["certified"] is False
