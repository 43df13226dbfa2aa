"""Baselines the circle benchmarks measure fitbench against, defined once (tests/benchmarks/test_bench_circle.py
and test_bench_circle_limits.py import them; pytest puts this directory on sys.path)."""
import warnings

import pytest


def circle_model():
    """``fit(points) -> (center, radius)`` by scikit-image's ``CircleModel`` (``from_estimate`` where the
    installed version has it, else ``estimate``; its FutureWarning silenced); skips the test without
    scikit-image."""
    measure = pytest.importorskip("skimage.measure", reason="scikit-image is a test extra (pip install -e .[test])")

    def fit(points):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)
            if hasattr(measure.CircleModel, "from_estimate"):
                model = measure.CircleModel.from_estimate(points)
                return model.center, model.radius
            model = measure.CircleModel()
            model.estimate(points)
            return model.params[:2], model.params[2]

    return fit
