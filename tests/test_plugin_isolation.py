"""A plugin's method cannot change the rows of other methods, nor their cache, nor get 'ok' rows for lies by
patching fitbench in its process: its rows are fitted in a child process of the worker (which ends with the chunk)
and gated and measured by the worker's own code; a method writing into its read-only input through C gets an
'invalid' row and the methods after it get the data unchanged."""
from __future__ import annotations

import ctypes

import numpy as np
import pandas as pd
import pytest

from conftest import install_plugin, run_python
from experiments import chunkrows, rows
from methods import register
from methods._registry import _REGISTRY
from methods.results import circle_result
from study_kinds import circle_study

PATCHER = '''
"""A plugin whose methods patch fitbench in the process they run in."""
import ctypes

import numpy as np
from methods import register
from methods.results import circle_result


def _centroid(points):
    c = points.mean(axis=0)
    return c, float(np.hypot(*(points - c).T).mean())


@register("circle.iso_poison", kind="closed form", summary="patches circle.kasa's function in its process",
          reference="isolation test")
def poison(points):
    import methods
    spec = methods.get("circle.kasa")
    orig = spec.func
    if not getattr(orig, "_poisoned", False):
        def kasa(points, **kw):
            res = orig(points, **kw)
            return circle_result(points, res.center, res.radius * 1.001, converged=True, message=res.message)
        kasa._poisoned = True
        object.__setattr__(spec, "func", kasa)
    c, r = _centroid(points)
    return circle_result(points, c, r, converged=True, message="closed form")


@register("circle.iso_patch_gate", kind="closed form", summary="disables the gate, then lies",
          reference="isolation test")
def patch_gate(points):
    import methods
    import methods.result_base as rb
    import methods.results as mr
    import experiments.chunkrows as chunkrows
    import experiments.rows as rows
    for mod in (rb, mr, methods, rows, chunkrows):
        for name in dir(mod):
            if "check" in name and callable(getattr(mod, name)):
                setattr(mod, name, lambda *a, **k: None)
    c, r = _centroid(points)
    return circle_result(points, c, -r, converged=True, message="lie after patch")


@register("circle.iso_c_writer", kind="closed form", summary="writes into its read-only input through C",
          reference="isolation test")
def c_writer(points):
    c, r = _centroid(points)
    res = circle_result(points, c, r, converged=True, message="closed form")
    scaled = np.ascontiguousarray(points * 1.01)
    ctypes.memmove(points.ctypes.data, scaled.ctypes.data, scaled.nbytes)
    return res


@register("circle.iso_patch_other", kind="closed form", summary="moves the centre of another plugin's method",
          reference="isolation test")
def patch_other(points):
    import methods
    spec = methods.get("circle.iso_honest")  # a method of another distribution (fitbench-cheater)

    def moved(pts, **kw):  # self-consistent: the gate cannot see it
        c = pts.mean(axis=0) + 0.5
        return circle_result(pts, c, float(np.hypot(*(pts - c).T).mean()), converged=True, message="closed form")
    object.__setattr__(spec, "func", moved)
    c, r = _centroid(points)
    return circle_result(points, c, r, converged=True, message="closed form")
'''


CHEATER = '''
"""A plugin whose methods cheat the worker that gates their rows."""
import os

import numpy as np
import methods
from methods import register
from methods.results import circle_result


@register("circle.iso_exit_zero", kind="closed form", summary="ends its process with status 0",
          reference="isolation test")
def exit_zero(points):
    os._exit(0)


@register("circle.iso_honest", kind="closed form", summary="the centroid circle", reference="isolation test")
def honest(points):
    c = points.mean(axis=0)
    return circle_result(points, c, float(np.hypot(*(points - c).T).mean()), converged=True, message="closed form")


@register("circle.iso_ellipse", kind="closed form", summary="returns an ellipse for a circle",
          reference="isolation test")
def ellipse(points):
    return methods.fit("ellipse.fitzgibbon", points)


@register("circle.iso_swap_data", kind="closed form", summary="sends the worker a perfect circle as the data",
          reference="isolation test")
def swap_data(points):
    import experiments.chunkrows as chunkrows
    from methods.result_base import family_copy
    t = np.linspace(0, 2 * np.pi, len(points), endpoint=False)
    perfect = np.column_stack([5.0 * np.cos(t), 5.0 * np.sin(t)])
    fake = circle_result(perfect, (0.0, 0.0), 5.0, converged=True, message="perfect")

    def child_item(task, row_timeout, progress, pos):
        return "fit", family_copy(fake), {}, None, (perfect, {"family": "circle", "center": (0.0, 0.0), "radius": 5.0})
    chunkrows._child_item = child_item
    return honest(points)


_CALLS = [0]


@register("circle.iso_close_second", kind="closed form", summary="closes every file of its process on its second call",
          reference="isolation test")
def close_second(points):
    _CALLS[0] += 1
    if _CALLS[0] == 2:
        os.closerange(3, 1 << 16)
    return honest(points)
'''


@pytest.fixture(scope="module")
def cheater(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("cheater"), "fitbench-cheater", {"fitbench_cheater": CHEATER},
                          {"fitbench.methods": {"cheater": "fitbench_cheater"}})


@pytest.mark.slow
def test_a_plugin_cannot_send_its_own_data_nor_another_family_s_result_nor_lose_rows_by_exiting(cheater, tmp_path):
    """The worker gates a plugin's result against the data it makes itself (a built-in source), as the result of the
    task's method (its family's class), and a child that ends with status 0 before it sends the rows is a crash of the
    row it was running (the others run again): no 'ok' row for a perfect circle the plugin sent as the data, none for
    an ellipse, and the honest rows of the chunk kept."""
    out = tmp_path / "out"
    study = _study(tmp_path / "a", "cheat", ["circle.iso_honest", "circle.iso_ellipse", "circle.iso_exit_zero",
                                             "circle.kasa"], repetitions=3)
    proc = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "2", "--no-report", path_first=[cheater],
                      timeout=300)
    assert proc.returncode == 0, proc.stderr
    df = _rows(out, "cheat").set_index(["method", "repetition"])
    assert (df.loc["circle.iso_honest", "status"] == "ok").all() and (df.loc["circle.kasa", "status"] == "ok").all()
    assert (df.loc["circle.iso_ellipse", "status"] == "invalid").all()
    assert df.loc["circle.iso_ellipse", "message"].str.contains("must return a CircleFit").all()
    exits = df.loc["circle.iso_exit_zero"]
    assert (exits["status"] == "crashed").all(), exits[["status", "message"]]
    # the plugin replaces what its process sends for the rows after its own: a perfect circle as the data and the fit
    study = _study(tmp_path / "b", "swap", ["circle.iso_swap_data", "circle.iso_honest", "circle.kasa"])
    proc = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "2", "--no-report", path_first=[cheater],
                      timeout=300)
    assert proc.returncode == 0, proc.stderr
    df = _rows(out, "swap")
    assert not ((df["status"] == "ok") & (df["form_error"] < 1e-9)).any(), df[["method", "status", "form_error"]]
    assert (df[df["method"] == "circle.kasa"]["status"] == "ok").all()


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("patcher"), "fitbench-patcher", {"fitbench_patcher": PATCHER},
                          {"fitbench.methods": {"patcher": "fitbench_patcher"}})


def _study(folder, name: str, method_ids, repetitions=3, chunk_rows=None):
    folder.mkdir(parents=True, exist_ok=True)
    return circle_study(folder, name, "Isolation", method_ids, repetitions,
                        f"chunk_rows = {chunk_rows}\n" if chunk_rows else "")


def _rows(out, name):
    return pd.read_csv(out / name / "results.csv", keep_default_na=False, na_values=[""])


@pytest.mark.slow
@pytest.mark.parametrize("executor", [[], ["--executor", "dask"]], ids=["local", "dask"])
def test_a_plugin_patching_fitbench_changes_no_other_row_nor_its_cache(site, tmp_path, executor):
    out, clean = tmp_path / "out", tmp_path / "clean"
    study = _study(tmp_path / "a", "iso", ["circle.iso_poison", "circle.iso_patch_gate", "circle.iso_c_writer",
                                           "circle.kasa"])
    proc = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "1", "--no-report", *executor,
                      path_first=[site])
    assert proc.returncode == 0, proc.stderr
    df = _rows(out, "iso")
    # the same kasa rows, without the plugin, into the same folder (served from the cache) and into a new one
    only_kasa = _study(tmp_path / "b", "iso", ["circle.kasa"])
    for folder in (out, clean):
        proc = run_python("-m", "experiments.run", only_kasa, "--out", folder, "--jobs", "1", "--no-report")
        assert proc.returncode == 0, proc.stderr
    reference = _rows(clean, "iso").set_index("repetition")["radius"]
    kasa = df[df["method"] == "circle.kasa"].set_index("repetition")
    assert (kasa["status"] == "ok").all() and kasa["radius"].tolist() == reference.tolist()
    assert _rows(out, "iso").set_index("repetition")["radius"].tolist() == reference.tolist()
    lies = df[df["method"] == "circle.iso_patch_gate"]
    assert (lies["status"] == "invalid").all() and lies["message"].str.contains("must be > 0").all(), lies
    writer = df[df["method"] == "circle.iso_c_writer"]
    assert (writer["status"] == "invalid").all() and writer["message"].str.contains("wrote into the points").all()


def _writer(points):
    c = points.mean(axis=0)
    res = circle_result(points, c, float(np.hypot(*(points - c).T).mean()), converged=True, message="closed form")
    scaled = np.ascontiguousarray(points * 1.01)
    ctypes.memmove(points.ctypes.data, scaled.ctypes.data, scaled.nbytes)
    return res


def test_a_method_writing_into_its_input_through_c_changes_no_data_of_the_methods_after_it():
    """In the engine's own process (a method the running program registers): the batch of a repetition's rows."""
    register("circle.iso_local_writer", kind="closed form", summary="writes into its input through C",
             reference="isolation test")(_writer)
    try:
        t = np.linspace(0, 2 * np.pi, 30, endpoint=False)
        points = np.c_[1 + 5 * np.cos(t), 2 + 5 * np.sin(t)]
        truth = {"center": (1.0, 2.0), "radius": 5.0}
        import methods
        data = methods.immutable(points)
        before = data.copy()
        task = {"study": "iso", "dataset": {"label": "c"}, "repetition": 0, "seed": 1, "stream": (0,), "params": {}}
        writer = rows.fit_row({**task, "method": "circle.iso_local_writer"}, data, truth)
        assert writer["status"] == "invalid" and "wrote into the points" in writer["message"], writer
        assert np.array_equal(data, before)
        # a method that writes nothing is not blamed, NaN in the data included
        register("circle.iso_local_reader", kind="closed form", summary="reads its input",
                 reference="isolation test")(lambda p: circle_result(p, (1.0, 2.0), 5.0, converged=False, message="m"))
        with_nan = methods.immutable(np.r_[points, [[np.nan, 0.0]]])
        reader = rows.fit_row({**task, "method": "circle.iso_local_reader"}, with_nan, truth)
        assert reader["status"] == "skipped" and "wrote into" not in reader["message"], reader  # NaN: refused
        kasa = rows.fit_row({**task, "method": "circle.kasa"}, data, truth)
        assert kasa == rows.fit_row({**task, "method": "circle.kasa"}, methods.immutable(before), truth)
    finally:
        _REGISTRY.pop("circle.iso_local_writer", None)
        _REGISTRY.pop("circle.iso_local_reader", None)


def test_what_a_plugin_s_process_sends_can_name_no_code():
    """The worker reads the child's bytes with an unpickler that makes Python's values, NumPy arrays, fitbench's result
    classes and data classes, and nothing else: a pickle naming a function (os.system) is refused, not called."""
    import os
    import pickle

    from datasets.circular_test import TestConditions
    t = np.linspace(0, 2 * np.pi, 30, endpoint=False)
    points = np.c_[np.cos(t), np.sin(t)]
    res = circle_result(points, (0.0, 0.0), 1.0, converged=True, message="exact")
    item = ("fit", res, {"lobes": 3.0}, None, (points.astype(np.float32), {"radius": np.float64(1.0)}))
    back = chunkrows._ResultUnpickler(pickle.dumps(item, protocol=pickle.HIGHEST_PROTOCOL)).load()
    assert back[1].radius == 1.0 and np.array_equal(back[1].residuals, res.residuals)
    assert back[4][0].dtype == np.float32 and np.array_equal(back[4][0], points.astype(np.float32))
    conditions = chunkrows._ResultUnpickler(pickle.dumps(TestConditions.__new__(TestConditions))).load()
    assert type(conditions) is TestConditions

    class Evil:
        def __reduce__(self):
            return os.system, ("echo pwned",)
    with pytest.raises(pickle.UnpicklingError, match="posix.system is not a value fitbench reads"):
        chunkrows._ResultUnpickler(pickle.dumps(("fit", Evil()))).load()


@pytest.mark.slow
def test_a_plugin_s_method_changes_no_row_of_another_plugin_s_method_in_its_chunk(site, cheater, tmp_path):
    """The rows of each (method, data source) of a chunk run in a child of their own: a method of one distribution
    that patches another's (a self-consistent moved centre, which no gate can see) changes none of its rows, and the
    cache keeps the true ones."""
    out, clean = tmp_path / "out", tmp_path / "clean"
    study = _study(tmp_path / "a", "pair", ["circle.iso_patch_other", "circle.iso_honest"], chunk_rows=6)
    proc = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "1", "--no-report",
                      path_first=[site, cheater])
    assert proc.returncode == 0, proc.stderr
    alone = _study(tmp_path / "b", "pair", ["circle.iso_honest"], chunk_rows=6)
    proc = run_python("-m", "experiments.run", alone, "--out", clean, "--jobs", "1", "--no-report",
                      path_first=[cheater])
    assert proc.returncode == 0, proc.stderr
    reference = _rows(clean, "pair").set_index("repetition")
    victim = _rows(out, "pair").query("method == 'circle.iso_honest'").set_index("repetition")
    assert (victim["status"] == "ok").all()
    assert victim["center_x"].tolist() == reference["center_x"].tolist(), victim["center_error"]


@pytest.mark.slow
def test_a_child_that_breaks_is_blamed_on_the_row_it_did_not_send(cheater, tmp_path):
    """A child sends each row as soon as it is made: a method that closes its process's files on its second call
    (the pipe to the worker among them) gets that row 'crashed'; its other rows and another method's are ok."""
    out = tmp_path / "out"
    study = _study(tmp_path / "a", "blame", ["circle.iso_close_second", "circle.iso_honest"], chunk_rows=6)
    proc = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "1", "--no-report",
                      path_first=[cheater])
    assert proc.returncode == 0, proc.stderr
    df = _rows(out, "blame").set_index(["method", "repetition"])["status"]
    assert df.to_dict() == {("circle.iso_close_second", 0): "ok", ("circle.iso_honest", 0): "ok",
                            ("circle.iso_close_second", 1): "crashed", ("circle.iso_honest", 1): "ok",
                            ("circle.iso_close_second", 2): "ok", ("circle.iso_honest", 2): "ok"}
