"""``fitbench fit`` gates every method's result, a method in fitbench's own packages too (the API gates a plugin's only,
trusting the test suite for fitbench's own, which runs them with their default parameters): the README's example
method copied into ``methods/circle/`` with ``--param shrink=-1`` printed 'radius -50 mm, converged yes'."""
from __future__ import annotations

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from methods import register, results
from methods._registry import _REGISTRY, BUILTIN_IDS


@pytest.fixture
def in_repo_method():
    mid = "circle.test_in_repo_shrink"

    def shrink_fit(points, *, shrink=1.0):
        """The README's example: the centroid circle, its radius times ``shrink``."""
        c = points.mean(axis=0)
        r = float(np.hypot(*(points - c).T).mean())
        return results.circle_result(points, c, r * shrink, converged=True, message="closed form")
    register(mid, kind="closed form", summary="the README's example, in the repository", reference="fitbench tests")(
        shrink_fit)
    BUILTIN_IDS.add(mid)  # as a module under methods/ is
    try:
        yield mid
    finally:
        BUILTIN_IDS.discard(mid)
        _REGISTRY.pop(mid, None)


def test_fit_refuses_a_lying_result_of_a_method_in_fitbench_s_packages(in_repo_method, tmp_path):
    t = np.linspace(0.0, 2 * np.pi, 40, endpoint=False)
    trace = tmp_path / "trace.csv"
    trace.write_text("x [mm],y [mm]\n" + "".join(f"{float(50 * np.cos(a))!r},{float(50 * np.sin(a))!r}\n" for a in t))
    ok = cli("fit", in_repo_method, trace)
    assert ok.returncode == 0 and "converged" in ok.stdout, ok.stderr
    for shrink, said in (("-1", "must be > 0"), ("0", "must be > 0")):
        one_error_line(cli("fit", in_repo_method, trace, "--param", f"shrink={shrink}"), in_repo_method, said)
