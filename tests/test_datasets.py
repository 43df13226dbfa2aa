"""Published data sets and the reader for users' files."""
import numpy as np
import pytest

import datasets
import methods
from datasets import DataFileError, read_points


def test_published_sets_listed_with_metadata():
    assert datasets.list() == ["roundness_set1", "roundness_set2", "roundness_set3"]
    for name in datasets.list():
        d = datasets.load(name)
        assert d.points.shape == (d.meta["n_points"], 2)
        assert d.meta["units"] == "mm" and "Pınar" in d.meta["citation"]
        assert "LSQ (paper's Gauss-Newton)" in d.published


def test_set2_reproduces_published_lsq_circularity():
    """Roundness paper, table 1: LSQ circularity of set 2 is 1.7487 (Rapidform: 1.74867)."""
    d = datasets.load("roundness_set2")
    for method_id in ("circle.gauss_newton", "circle.levenberg_marquardt", "circle.nelder_mead"):
        res = methods.fit(method_id, d.points)
        assert round(res.form_error, 4) == d.published["LSQ (paper's Gauss-Newton)"]
        assert round(res.form_error, 5) == d.published["Rapidform 2004"]


def test_set3_repeated_closing_point_is_explicit():
    as_published = datasets.load("roundness_set3")
    assert as_published.meta["repeated_closing_point"] and len(as_published.points) == 13
    np.testing.assert_array_equal(as_published.points[0], as_published.points[-1])
    dropped = datasets.load("roundness_set3", drop_repeated_closing_point=True)
    assert len(dropped.points) == 12
    np.testing.assert_array_equal(dropped.points, as_published.points[:-1])
    # the repeat counts twice in least squares: the two variants differ measurably
    a = methods.fit("circle.gauss_newton", as_published.points).form_error
    b = methods.fit("circle.gauss_newton", dropped.points).form_error
    assert abs(a - b) > 1e-3


def test_unknown_dataset_suggests():
    with pytest.raises(DataFileError, match="roundness_set2"):
        datasets.load("roundness_set")


def write(tmp_path, text, name="pts.txt"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


@pytest.mark.parametrize("text", [
    "x,y\n1,2\n3,4\n5,7\n",
    "# a comment\n1, 2\n3, 4\n\n5, 7\n",
    "X;Y\n1;2\n3;4\n5;7\n",
    "1;2,0\n3;4\n5;7,0\n",            # semicolons with decimal commas
    "% measured 2026-11-21\n1 2\n3\t4\n5   7\n",
    "id,y,x\n0,2,1\n1,4,3\n2,7,5\n",  # named columns in another order
])
def test_reader_accepts_common_layouts(tmp_path, text):
    pts = read_points(write(tmp_path, text))
    np.testing.assert_array_equal(pts, [[1, 2], [3, 4], [5, 7]])


@pytest.mark.parametrize("text, match", [
    ("x,y\n1,2\n3,abc\n5,7\n", "line 3: 'abc' is not a number"),
    ("1,2\n3,4,5\n", "line 2: 3 fields"),
    ("x,y\n1,2\n3,nan\n", "line 3: 'nan' is not a finite number"),
    ("# only a comment\n\n", "no data lines"),
    ("x,y\n", "header but no data"),
    ("1,2,3\n4,5,6\n", "3 columns and no header"),
])
def test_reader_refuses_malformed_input_naming_the_line(tmp_path, text, match):
    with pytest.raises(DataFileError, match=match):
        read_points(write(tmp_path, text))


def test_reader_missing_and_binary_files(tmp_path):
    with pytest.raises(DataFileError, match="no such file"):
        read_points(tmp_path / "absent.csv")
    p = tmp_path / "bin.dat"
    p.write_bytes(b"\xff\xfe\x00\x01\x80\x81")
    with pytest.raises(DataFileError):
        read_points(p)


def test_reader_is_an_invalid_input_error():
    assert issubclass(DataFileError, methods.InvalidInputError)


def test_reader_large_file_round_trip(tmp_path, rng):
    pts = rng.normal(size=(200_000, 2))
    p = tmp_path / "big.csv"
    np.savetxt(p, pts, delimiter=",", header="x,y", comments="", fmt="%.17g")
    np.testing.assert_array_equal(read_points(p), pts)
