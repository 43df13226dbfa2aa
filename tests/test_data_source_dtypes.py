"""Points a data source gives as float32, integers or a masked array: converted once where the source's points are
checked (the float64 array the methods and the gate both see), so honest methods are not called liars; a masked
array with masked points is refused naming the source."""
import numpy as np
import pytest

from experiments.rows import DataSourceError, fit_row, load_data
from plugin_methods import sources_registered

T = np.linspace(0.0, 2 * np.pi, 30, endpoint=False)
CIRCLE = np.c_[1200.0 + 299.0 * np.cos(T), 650.0 + 299.0 * np.sin(T)] + 0.003 * np.cos(5 * T)[:, None]
TRUTH = {"center": (1200.0, 650.0), "radius": 299.0}


def _float32(rng):
    return CIRCLE.astype(np.float32), TRUTH


def _masked_clean(rng):
    return np.ma.masked_array(CIRCLE, mask=np.zeros_like(CIRCLE, dtype=bool)), TRUTH


def _masked(rng):
    points = np.ma.masked_array(np.r_[CIRCLE, [[1e9, -1e9]]], mask=False)
    points[-1] = np.ma.masked  # a garbage point under the mask
    return points, TRUTH


@pytest.fixture
def dtype_sources():
    with sources_registered({"test_dtype_float32": _float32, "test_dtype_masked_clean": _masked_clean,
                             "test_dtype_masked": _masked}, random=False,
                            summary="a circle in another array type (dtype test)"):
        yield


def _task(method, source):
    return {"study": "dtypes", "dataset": {"label": source, "source": source, "params": {}}, "repetition": 0,
            "seed": 1, "stream": (0,), "method": method, "params": {}}


@pytest.mark.parametrize("source", ["test_dtype_float32", "test_dtype_masked_clean"])
def test_points_of_another_float_type_or_a_masked_array_make_ok_rows(dtype_sources, source):
    for method in ("circle.kasa", "circle.gauss_newton"):
        task = _task(method, source)
        points, truth = load_data(task["dataset"], 1, [0])
        assert type(points) is np.ndarray and points.dtype == np.float64 and not points.flags.writeable
        row = fit_row(task, points, truth)
        assert row["status"] == "ok", row


def test_a_masked_array_with_masked_points_is_refused_naming_the_source(dtype_sources):
    with pytest.raises(DataSourceError, match=r"source 'test_dtype_masked'.* 1 of 31 points masked.*compress_rows"):
        load_data(_task("circle.kasa", "test_dtype_masked")["dataset"], 1, [0])


def test_a_truth_that_cannot_be_compared_is_the_source_s_error_not_the_methods(dtype_sources):
    points = load_data(_task("circle.kasa", "test_dtype_float32")["dataset"], 1, [0])[0]
    for method in ("circle.kasa", "circle.gauss_newton"):
        with pytest.raises(DataSourceError, match=r"data set 'test_dtype_float32' \(source 'test_dtype_float32'\) gave a "
                                                  r"truth that cannot be compared .*TypeError.*not the methods"):
            fit_row(_task(method, "test_dtype_float32"), points, {"center": ("a", "b"), "radius": "x"})


@pytest.mark.parametrize("truth, error", [({"center": (1200.0,), "radius": 299.0}, "IndexError"),
                                          ({"center": {"x": 1200.0}, "radius": 299.0}, "KeyError")])
def test_a_truth_of_the_wrong_shape_is_the_source_s_error_too(dtype_sources, truth, error):
    points = load_data(_task("circle.kasa", "test_dtype_float32")["dataset"], 1, [0])[0]
    with pytest.raises(DataSourceError, match=f"gave a truth that cannot be compared .*{error}.*not the methods"):
        fit_row(_task("circle.kasa", "test_dtype_float32"), points, truth)
