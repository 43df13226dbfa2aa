"""A hostile plugin package (built and installed offline, registered through entry points) whose methods lie
about their results or try to change the caller's data: every lie becomes a row with status ``invalid`` and the
reason, never ``ok``; the data a method is given cannot be written (nor made writeable again), so the caller's
data cannot change; the study completes beside honest methods.

The package also registers the methods the engine's isolation tests use (a sleep, ``os._exit``, ``SystemExit``,
``KeyboardInterrupt``): :data:`HOSTILE` and :func:`hostile_site` are shared with those tests; nothing here runs
them.
"""
import json
import textwrap

import numpy as np
import pandas as pd
import pytest

from conftest import REPO, install_plugin, run_python
from study_kinds import circle_study

HOSTILE = '''
"""A plugin that lies (every method claims converged=True) and misbehaves."""
import os
import time

import numpy as np
from methods import register
from methods.results import CircleFit, circle_result


def _lie(points, **fields):
    base = dict(center=(0.0, 0.0), radius=1.0, form_error=0.0, residuals=np.zeros(len(points)), converged=True,
                message="trust me")
    return CircleFit(**{**base, **fields})


@register("circle.liar", kind="closed form", summary="negative radius, negative form error, centre at infinity",
          reference="hostile plugin test")
def liar(points):
    return _lie(points, center=(float("inf"), 1e308), radius=-5.0, form_error=-1.0)


@register("circle.negative_radius", kind="closed form", summary="a negative radius", reference="hostile plugin test")
def negative_radius(points):
    c = points.mean(axis=0)
    return circle_result(points, c, -abs(np.hypot(*(points - c).T).mean()), converged=True, message="closed form")


@register("circle.array_radius", kind="closed form", summary="a radius that is an array",
          reference="hostile plugin test")
def array_radius(points):
    res = circle_result(points, points.mean(axis=0), 1.0, converged=True, message="closed form")
    res.radius = np.array([1.0, 2.0])
    return res


@register("circle.flattering", kind="closed form", summary="claims a form error its points do not have",
          reference="hostile plugin test")
def flattering(points):
    c = points.mean(axis=0)
    res = circle_result(points, c, np.hypot(*(points - c).T).mean(), converged=True, message="closed form")
    res.form_error = res.form_error / 1000
    return res


@register("circle.unserialisable", kind="closed form", summary="an extra that is no JSON",
          reference="hostile plugin test")
def unserialisable(points):
    c = points.mean(axis=0)
    return circle_result(points, c, np.hypot(*(points - c).T).mean(), converged=True, message="closed form",
                         extra={"handle": object()})


@register("circle.not_a_result", kind="closed form", summary="returns a tuple", reference="hostile plugin test")
def not_a_result(points):
    return (0.0, 0.0, 1.0)


@register("circle.mutator", kind="closed form", summary="writes into its input, and then tries harder",
          reference="hostile plugin test")
def mutator(points):
    attempts = []
    try:
        points[0, 0] = 1e9
        attempts.append("direct write succeeded")
    except ValueError:
        attempts.append("direct write refused")
    try:
        points.flags.writeable = True
        points[:, :] = 1e9     # at most the method's own copy
        attempts.append("writeable again")
    except ValueError:
        attempts.append("writeable refused")
    c = points.mean(axis=0)
    res = circle_result(points, c, float(np.hypot(*(points - c).T).mean()) or 1.0, converged=True,
                        message="; ".join(attempts))
    return res


# Hooks of the engine's isolation tests (a row that never returns, a worker that exits): registered, never
# run by the result-gate tests.
@register("circle.sleeper", kind="iterative", summary="sleeps (isolation tests)", reference="hostile plugin test")
def sleeper(points, *, seconds=3600.0):
    time.sleep(seconds)
    return circle_result(points, points.mean(axis=0), 1.0, converged=True, message="woke up")


@register("circle.os_exit", kind="closed form", summary="os._exit (isolation tests)", reference="hostile plugin test")
def os_exit(points, *, code=3):
    os._exit(code)


@register("circle.system_exit", kind="closed form", summary="SystemExit (isolation tests)",
          reference="hostile plugin test")
def system_exit(points, *, code=4):
    raise SystemExit(code)


@register("circle.keyboard_interrupt", kind="closed form", summary="KeyboardInterrupt (isolation tests)",
          reference="hostile plugin test")
def keyboard_interrupt(points):
    raise KeyboardInterrupt
'''

#: the lying methods and the words their row's reason must contain
LIES = {"circle.liar": "form_error = -1 must be >= 0; center_x = inf is not finite in a converged result; radius = -5 must be > 0", "circle.negative_radius": "radius", "circle.array_radius": "radius must be a number",
        "circle.flattering": "form_error", "circle.unserialisable": "JSON", "circle.not_a_result": "not a methods.results"}


def hostile_site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("hostile"), "fitbench-hostile", {"fitbench_hostile": HOSTILE},
                          {"fitbench.methods": {"hostile": "fitbench_hostile"}}, version="6.6.6")


def write_hostile_study(folder, name: str, method_ids) -> object:
    """A grid study of two repetitions of one generated circle with these methods."""
    return circle_study(folder, name, "Hostile plugin", method_ids, repetitions=2)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    return hostile_site(tmp_path_factory)


@pytest.mark.slow
def test_lies_become_invalid_rows_and_the_study_completes(site, tmp_path):
    study = write_hostile_study(tmp_path, "hostile", [*LIES, "circle.mutator", "circle.kasa"])
    out = tmp_path / "out"
    proc = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "1", path_first=[site])
    assert proc.returncode == 0, proc.stderr
    df = pd.read_csv(out / "hostile" / "results.csv", keep_default_na=False, na_values=[""])
    for method, reason in LIES.items():
        rows = df[df["method"] == method]
        assert len(rows) == 2 and set(rows["status"]) == {"invalid"}, rows[["status", "message"]]
        assert all(reason in m and m.startswith("invalid result: ") for m in rows["message"]), rows["message"].tolist()
        assert rows["radius"].isna().all() and rows["form_error"].isna().all()
    assert set(df[df["method"] == "circle.kasa"]["status"]) == {"ok"}
    # the mutator can neither write into the data it is given nor make them writeable again: its result is honest
    mutator = df[df["method"] == "circle.mutator"]
    assert set(mutator["status"]) == {"ok"}
    assert set(mutator["message"]) == {"direct write refused; writeable refused"}
    meta = json.loads((out / "hostile" / "meta.json").read_text())
    assert meta["plugins"] == {"fitbench-hostile": "6.6.6"}
    assert meta["status_counts"] == {"invalid": 2 * len(LIES), "ok": 4}
    report = (out / "paper" / "report.md").read_text()
    assert "plugins: fitbench-hostile 6.6.6" in report
    assert f"**invalid results: {2 * len(LIES)} of {len(df)}**" in report


@pytest.mark.slow
def test_with_one_job_a_plugin_that_ends_its_process_ends_only_its_rows(site, tmp_path):
    """--jobs 1 runs fitbench's own rows in the run's process; a plugin's rows run in a worker process: a method
    calling os._exit labels its rows crashed and the built-in method's rows are kept (it used to end the run
    with exit 3, no message and no row stored, again on every rerun)."""
    study = write_hostile_study(tmp_path, "exits", ["circle.kasa", "circle.os_exit"])
    out = tmp_path / "out"
    proc = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "1", "--no-report", path_first=[site])
    assert proc.returncode == 0, proc.stderr
    df = pd.read_csv(out / "exits" / "results.csv")
    assert set(df[df["method"] == "circle.kasa"]["status"]) == {"ok"}
    exits = df[df["method"] == "circle.os_exit"]
    assert len(exits) == 2 and set(exits["status"]) == {"crashed"}
    assert all("exit code 3" in m for m in exits["message"])


def test_rows_of_a_plugin_method_or_source_are_rows_of_plugin_code(site):
    from experiments.engine import runs_plugin_code
    assert not runs_plugin_code({("circle.kasa", "circle"), ("circle.gauss_newton", "published")})
    assert not runs_plugin_code({("not-a-method", None)})  # a study's own rows: its code is fitbench's
    proc = run_python("-c", "from experiments.engine import runs_plugin_code; "
                            "print(runs_plugin_code({('circle.os_exit', 'circle')}))", path_first=[site])
    assert proc.stdout.strip() == "True", proc.stderr


def test_the_caller_s_array_cannot_be_changed_through_the_api(site):
    code = textwrap.dedent('''
        import numpy as np, methods
        pts = np.random.default_rng(1).normal(size=(20, 2))
        before = pts.copy()
        res = methods.fit("circle.mutator", pts)
        print(res.message, "|", bool((pts == before).all()), pts.flags.writeable)
        print(methods.check_result(methods.get("circle.liar").unchecked(pts), pts))
        try:
            methods.fit("circle.liar", pts)
        except methods.ResultContractError as exc:
            print(exc.problem)
    ''')
    proc = run_python("-c", code, path_first=[site])
    assert proc.returncode == 0, proc.stderr
    first, second, third = proc.stdout.splitlines()
    assert first == "direct write refused; writeable refused | True True"
    assert "not finite" in second and third == second  # methods.fit refuses the lie with the gate's reason
