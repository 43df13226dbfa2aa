"""pytest-benchmark case: the points reader on 10^6 x, y rows (about 29 MB of text), the typed C-parser path.

Run:  python -m pytest tests/benchmarks/test_bench_reader.py --benchmark-enable
(the default test run executes it once, as a smoke test). Peak memory is tested in tests/test_frontdoor.py.
"""
import numpy as np
import pytest

from datasets.io import read_points


@pytest.fixture(scope="module")
def big_file(tmp_path_factory):
    rng = np.random.default_rng(0)
    pts = rng.normal(size=(1_000_000, 2)) * 100
    p = tmp_path_factory.mktemp("reader") / "big.csv"
    np.savetxt(p, pts, delimiter=",", header="x,y", comments="", fmt="%.9f")
    return p, pts


def test_bench_read_points_1e6(benchmark, big_file):
    path, pts = big_file
    out = benchmark(read_points, path)
    np.testing.assert_allclose(out, pts, atol=5e-10)
