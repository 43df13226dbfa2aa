"""The quick paths of one benchmark row give the very bits of the general code they stand in for: the residual
RMS without np.mean's overhead, the JSON-ready row, the generated circles built on cached noise-free arcs."""
import math

import numpy as np
import pytest

from datasets import sources, synthetic
from experiments import metrics, rows


def _rms_by_mean(r):
    return float(np.sqrt(np.mean(np.square(r)))) if len(r) else np.nan


@pytest.mark.parametrize("n", [1, 2, 3, 7, 8, 9, 16, 17, 100, 127, 128, 129, 255, 1000, 4097, 100_003])
def test_residual_rms_is_np_mean_s_bits(n):
    rng = np.random.default_rng(n)
    for scale in (1e-9, 1e-3, 1.0, 1e3, 1e150):
        r = rng.normal(size=n) * scale
        assert metrics.residual_rms(r) == _rms_by_mean(r)


def test_residual_rms_of_other_inputs():
    r = np.random.default_rng(0).normal(size=50)
    r_nan = r.copy()
    r_nan[3] = np.nan
    for given in (r.astype(np.float32), r.reshape(5, 10), r[::2], list(r), r_nan):
        got, want = metrics.residual_rms(given), _rms_by_mean(given)
        assert got == want or (math.isnan(got) and math.isnan(want))
    assert math.isnan(metrics.residual_rms(np.empty(0)))


def test_center_error_is_np_hypot_s_bits():
    """The centre error's hypot of two Python floats (C's hypot through abs(complex), no ufunc call) gives
    np.hypot's bits at every scale, zeros, subnormals, overflow, inf and NaN; other types take np.hypot."""
    from methods.result_base import _hypot, center_errors
    rng = np.random.default_rng(7)
    # centre errors of unit-sized data (math.hypot differs from C's hypot in about 0.6 % of them), every scale
    a = np.concatenate([rng.normal(size=20000), rng.normal(size=20000) * 10.0 ** rng.integers(-320, 308, size=20000),
                        [0.0, -0.0, 5e-324, -5e-324, 1e308, -1.7e308, np.inf, -np.inf, np.nan, 3.0, 1e-300]])
    b = np.concatenate([rng.normal(size=20000), rng.normal(size=20000) * 10.0 ** rng.integers(-320, 308, size=20000),
                        [0.0, 0.0, 5e-324, 1e-310, 1e308, 1.7e308, np.nan, 2.0, np.inf, 4.0, 1e-300]])
    with np.errstate(over="ignore"):
        want = np.hypot(a, b)
        got = np.array([_hypot(x, y) for x, y in zip(a.tolist(), b.tolist())])
        assert got.tobytes() == want.tobytes()
        for x, y in ((np.float64(3.0), 4.0), (3, 4), (np.float32(0.1), 0.2), (1, 2.5)):
            assert _hypot(x, y) == float(np.hypot(x, y)) and type(_hypot(x, y)) is float
    row = center_errors((1.0, 2.0), {"center": (4.0, -2.0)})
    assert row == {"center_error_x": -3.0, "center_error_y": 4.0, "center_error": 5.0}


def _plain_reference(row):
    out = {}
    for k, v in row.items():
        if isinstance(v, np.generic):
            v = v.item()
        if isinstance(v, float) and not math.isfinite(v):
            v = None
        out[k] = v
    return out


def test_plain_row():
    row = {"a": 1.5, "b": float("nan"), "c": float("-inf"), "d": np.float64(2.5), "e": np.float64("nan"),
           "f": np.int64(3), "g": np.bool_(True), "h": "text", "i": 7, "j": True, "k": None, "l": np.float32(0.5),
           "m": [1.0, 2.0]}
    plain = {"a": 1.5, "b": "x", "c": 3, "d": True, "e": None, "f": -0.0, "g": 1e308}
    for given in (row, plain, {**plain, "h": 1e308}, {**plain, "h": float("inf")}, {**plain, "h": float("nan")},
                  {**plain, "h": np.float64(1.0)}, {"s": "only text"}, {}):
        want = _plain_reference(given)
        keys = list(given)
        got = rows._plain(given)
        assert got == want and list(got) == keys
        assert [type(v) for v in got.values()] == [type(v) for v in want.values()]


CIRCLES = [dict(), dict(center=[1200.0, 650.0], radius=299.0, n=40), dict(center=[0, 0], radius=1, n=7),
           dict(center=[-0.0, 0.0], arc_start_deg=-0.0, arc_deg=90.0, n=30), dict(arc_deg=90, arc_start_deg=45, n=12),
           dict(center=(1e6, -1e6), radius=1e-3, n=1000, arc_deg=359.0)]


def _circle_uncached(rng, *, center=(0.0, 0.0), radius=1.0, n=100, arc_deg=360.0, arc_start_deg=0.0, noise=0.0):
    start, span = np.radians(arc_start_deg), np.radians(arc_deg)
    pts = synthetic.circle_points(center, radius, n, arc=(start, start + span), endpoint=not arc_deg >= 360.0)
    return pts + rng.normal(0.0, noise, pts.shape) if noise else pts


@pytest.mark.parametrize("params", CIRCLES)
@pytest.mark.parametrize("noise", [0.0, 1e-3])
def test_generated_circles_keep_their_bits(params, noise):
    """The noise-free arc is built once per exact parameter set; every draw is the same as without the cache
    (twice: the second one comes from the cache), and -0.0 or an int parameter gets its own arc."""
    for _ in range(2):
        got, truth = synthetic._circle(np.random.default_rng(5), noise=noise, **params)
        want = _circle_uncached(np.random.default_rng(5), noise=noise, **params)
        assert got.tobytes() == want.tobytes() and got.shape == want.shape and truth["family"] == "circle"
        assert got.flags.writeable and got.flags.c_contiguous  # the caller's own array, as before


def test_a_caller_cannot_change_the_cached_arc():
    pts, _ = synthetic._circle(None, n=10)
    pts[:] = 0.0
    again, _ = synthetic._circle(None, n=10)
    assert again.tobytes() == _circle_uncached(None, n=10).tobytes()
    src, _ = sources.get_source("circle").load(np.random.default_rng(1), n=10, noise=0.1)
    with pytest.raises(ValueError):
        src[0, 0] = 1.0


def test_exact_keys():
    key = synthetic._exact_key
    assert key(0.0) != key(-0.0) and key(1) != key(1.0) and key([1.0, 2.0]) == key((1.0, 2.0))
    assert key(float("nan")) is None and key(True) is None and key(np.float64(1.0)) is None and key("1") is None


def test_the_kernel_choice_follows_os_environ_in_process(monkeypatch):
    """point_kernels reads FITBENCH_KERNELS through the C environment that os.environ writes (no KeyError per
    call): setting, changing and deleting it in process switches the path at the next call."""
    from methods import _frame
    from methods.circle import _ckernels
    monkeypatch.delenv("FITBENCH_KERNELS", raising=False)
    assert _frame.point_kernels() is _ckernels
    for value, path in (("numpy", None), ("compiled", _ckernels), (" NumPy ", None), ("", _ckernels)):
        monkeypatch.setenv("FITBENCH_KERNELS", value)
        assert _ckernels.env_value(b"FITBENCH_KERNELS") == value.encode()
        assert _frame.point_kernels() is path, value
    monkeypatch.delenv("FITBENCH_KERNELS")
    assert _ckernels.env_value(b"FITBENCH_KERNELS") is None and _frame.point_kernels() is _ckernels
    monkeypatch.setenv("FITBENCH_KERNELS", "cuda")
    with pytest.raises(ValueError, match="FITBENCH_KERNELS='cuda' is not one of"):
        _frame.point_kernels()


FORKER = '''
import os, sys
import numpy as np
import methods
from methods.results import circle_result
from experiments import chunkrows, config
from experiments.studies import study_of


@methods.register("circle.test_forker", kind="closed form", summary="forks and returns in both processes",
                  reference="test")
def forker(points):
    child = os.fork() == 0
    c = points.mean(axis=0)
    r = np.hypot(*(points - c).T).mean() * (2.0 if child else 1.0)
    return circle_result(points, c, r, converged=True, message="child" if child else "parent")


cfg = config.load(sys.argv[1])
tasks = list(study_of(cfg["kind"]).prepared_tasks(cfg))
out = chunkrows.run_chunk(tasks)
print("rows", os.getpid(), len(out["columns"]["row"]), sorted(set(r.split('"message":"')[1].split('"')[0][:6]
                                                                   for r in out["columns"]["row"])), flush=True)
'''


def test_a_method_that_forks_and_returns_in_the_child_leaves_one_process_making_rows(tmp_path):
    """A method that forks and returns in both processes (a library that forgets to end its child): the child ends
    where the method returns, so only the process the chunk was given to makes rows (the child ran on as a second
    worker and its rows, of twice the radius, were stored in place of others)."""
    from conftest import run_python
    study = tmp_path / "fork.toml"
    study.write_text('name = "fork"\ntitle = "fork"\nkind = "grid"\nseed = 1\nrepetitions = 3\n'
                     '[[datasets]]\ngenerator = "circle"\nparams = { radius = 5.0, noise = 0.01, n = 20 }\n'
                     '[[methods]]\nid = "circle.test_forker"\n[[methods]]\nid = "circle.kasa"\n', encoding="utf-8")
    script = tmp_path / "forker.py"
    script.write_text(FORKER, encoding="utf-8")
    out = run_python(script, study, timeout=120)
    assert out.returncode == 0, out.stderr
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("rows ")]
    assert len(lines) == 1, out.stdout  # one process made the rows: the children ended where the method returned
    assert lines[0].split()[2] == "6" and "child" not in lines[0] and "parent" in lines[0]
