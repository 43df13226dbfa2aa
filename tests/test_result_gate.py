"""The result gate (methods.check_result) in process: every kind of lie a result can tell is refused with a
one-line reason, every built-in method's result passes, and a method cannot change the caller's array."""
import numpy as np
import pytest

import methods
from methods import results
from methods._registry import _REGISTRY
from method_ids import method_specs

ANGLES = np.linspace(0, 2 * np.pi, 40, endpoint=False)
RADII = 299 + np.random.default_rng(2).normal(scale=1e-3, size=40)   # mm: a machine-tool circle, µm deviations
CIRCLE = np.column_stack([1200 + RADII * np.cos(ANGLES), 650 + RADII * np.sin(ANGLES)])


def honest(**changes):
    res = results.circle_result(CIRCLE, (1200.0, 650.0), 299.0, converged=True, message="exact")
    res.method = "circle.test"
    for k, v in changes.items():
        setattr(res, k, v)
    return res


LIES = {
    "negative radius": (dict(radius=-5.0), "radius = -5 must be > 0"),
    "negative form error": (dict(form_error=-1.0), "form_error = -1 must be >= 0"),
    "centre at infinity": (dict(center=(float("inf"), 1e308)), "center_x = inf is not finite"),
    "array radius": (dict(radius=np.array([1.0, 2.0])), "radius must be a number, got an array of shape (2,)"),
    "boolean radius": (dict(radius=True), "radius must be a number"),
    "text converged": (dict(converged="yes"), "converged must be True or False"),
    "negative iterations": (dict(iterations=-3), "iterations must be None or a count"),
    "centre of three": (dict(center=(1.0, 2.0, 3.0)), "center must have shape (2,)"),
    "residuals of another size": (dict(residuals=np.zeros(3)), "residuals must have shape (40,)"),
    "object in extra": (dict(extra={"f": open}), "extra is not JSON-serialisable"),
    "flattering form error": (dict(form_error=1e-9), "radial span"),
    "non-finite residuals": (dict(residuals=np.full(40, np.nan)), "residuals are not finite"),
    "residuals off by a micrometre": (dict(residuals=honest().residuals + 1e-3), "residuals are not the radial"),
    "one residual off": (dict(residuals=honest().residuals + np.eye(40)[7] * 1e-3), "residuals are not the radial"),
    "array centre of three": (dict(center=np.array([1.0, 2.0, 3.0])), "center must have shape (2,), got (3,)"),
    "text in the centre": (dict(center=(1200.0, "650")), "center_y must be a number, got str"),
    "numpy text centre": (dict(center=np.array(["1200", "650"])), "center_x must be a number, got str_"),
    "float count": (dict(nfev=3.0), "nfev must be None or a count"),
    "boolean count": (dict(iterations=True), "iterations must be None or a count"),
}

#: the same honest result in the other types a method may return (the gate's quick paths take Python floats,
#: tuples of them and float64 arrays; every other type is converted and checked as before)
HONEST_IN_OTHER_TYPES = {
    "centre as a list": dict(center=[1200.0, 650.0]),
    "centre as an array": dict(center=np.array([1200.0, 650.0])),
    "centre of numpy floats": dict(center=(np.float64(1200.0), np.float64(650.0))),
    "numpy radius": dict(radius=np.float64(299.0)),
    "numpy counts": dict(iterations=np.int64(3), nfev=np.int32(4)),
    "residuals one ulp away": dict(residuals=np.nextafter(honest().residuals, np.inf)),
    "residuals in float32": dict(residuals=honest().residuals.astype(np.float32)),
    "residuals not contiguous": dict(residuals=np.repeat(honest().residuals, 2)[::2]),
}


def test_an_honest_result_passes():
    assert results.check_result(honest(), CIRCLE) is None


@pytest.mark.parametrize("variant", list(HONEST_IN_OTHER_TYPES))
def test_an_honest_result_in_other_types_passes(variant):
    assert results.check_result(honest(**HONEST_IN_OTHER_TYPES[variant]), CIRCLE) is None


@pytest.mark.parametrize("lie", list(LIES))
def test_each_lie_is_refused_with_its_reason(lie):
    changes, reason = LIES[lie]
    problem = results.check_result(honest(**changes), CIRCLE)
    assert problem is not None and reason in problem and "\n" not in problem, problem


def test_the_family_s_declarations_win_over_a_subclass_s_own():
    """A plugin's subclass that declares the radius unchecked and no consistency is still held to CircleFit's."""
    from dataclasses import dataclass

    @dataclass(kw_only=True)
    class Lenient(results.CircleFit):
        COLUMNS = (results.Column("radius", "length", results.GEOMETRY, ""),)
        SHAPES = {}
        consistency = staticmethod(lambda result, data: None)

    res = Lenient(**{f: getattr(honest(), f) for f in ("center", "radius", "form_error", "residuals", "converged",
                                                      "message", "method")})
    res.radius = -1.0
    assert "radius = -1 must be > 0" in results.check_result(res, CIRCLE)
    res.radius, res.form_error = 299.0, 1e-9
    assert "radial span" in results.check_result(res, CIRCLE)


def test_an_ellipse_keeps_its_declared_form():
    pts = CIRCLE * np.array([1.0, 0.5])
    res = methods.fit("ellipse.halir_flusser", pts)
    assert results.check_result(res, pts) is None
    for change, reason in ((dict(semi_axes=res.semi_axes[::-1]), "a must be >= b"), (dict(angle=4.0), "[0, pi)"),
                           (dict(form_error=res.form_error / 100), "residuals span")):
        lie = methods.fit("ellipse.halir_flusser", pts)
        for k, v in change.items():
            setattr(lie, k, v)
        assert reason in results.check_result(lie, pts)


def test_the_family_contract_and_non_results():
    ellipse = results.EllipseFit(center=(0.0, 0.0), semi_axes=(2.0, 1.0), angle=0.0, conic=(0.0,) * 6,
                                 residuals=np.zeros(40), form_error=0.0, converged=True, method="circle.test")
    assert "a circle method must return a CircleFit, got a EllipseFit" in results.check_result(ellipse, CIRCLE)
    assert "not a methods.results.FitResult" in results.check_result((1.0, 2.0, 3.0), CIRCLE)


def test_a_result_that_did_not_converge_is_checked_for_types_only():
    assert results.check_result(honest(converged=False, center=(np.inf, 0.0), form_error=np.nan), CIRCLE) is None
    assert "radius must be a number" in results.check_result(honest(converged=False, radius=np.ones(2)), CIRCLE)


ARC = np.column_stack([5 + 20 * np.cos(np.radians(np.linspace(10, 100, 30))),
                       -3 + 20 * np.sin(np.radians(np.linspace(10, 100, 30)))])   # a 90° arc, radius 20 mm


@pytest.mark.parametrize("spec", method_specs("circle") + method_specs("ellipse") + method_specs("roundness"),
                         ids=lambda s: s.id)
@pytest.mark.parametrize("data", ["circle", "arc"])
def test_every_built_in_result_passes(spec, data):
    """What lets methods.fit skip the gate for built-in methods: every point-fitting built-in keeps its
    family's contract on a full circle and a short arc (the engine gates every benchmark row besides); roundness
    (ISO 12181, defined on the closed profile) refuses the arc as bad input instead of returning a result. A plugin
    method named in FITBENCH_TEST_METHODS (docs/plugins.md) is held to the same gate (it is not one of the built-ins
    methods.fit trusts: the gate checks it there too)."""
    base = CIRCLE if data == "circle" else ARC
    pts = base + np.random.default_rng(1).normal(scale=1e-3, size=base.shape)
    assert spec.builtin == (spec.id in methods._registry.BUILTIN_IDS)
    if spec.family == "roundness" and data == "arc" and spec.builtin:
        with pytest.raises(methods.InvalidInputError, match="the profile is open"):
            methods.get(spec.id).unchecked(pts)
        return
    res = methods.get(spec.id).unchecked(pts)
    problem = methods.check_result(res, pts)
    assert problem is None, problem


def test_a_plugin_named_for_the_method_tests_is_checked_by_the_gate():
    """docs/plugins.md's command for testing a plugin method runs the test above on it: an honest plugin passes
    (it failed, on the built-in assertion, whatever the method), a plugin whose result lies fails on the gate's
    reason."""
    def centroid(points, lie=False):
        c = points.mean(axis=0)
        res = results.circle_result(points, c, float(np.hypot(*(points - c).T).mean()), converged=True, message="ok")
        if lie:
            res.residuals = np.zeros(len(points))
        return res

    methods.list_methods()
    for name, lie in (("circle.test_gate_named_honest", False), ("circle.test_gate_named_liar", True)):
        methods.register(name, kind="closed form", summary="centroid", reference="gate test")(
            lambda points, lie=lie: centroid(points, lie))
    try:
        for data in ("circle", "arc"):
            test_every_built_in_result_passes(methods.get("circle.test_gate_named_honest"), data)
            with pytest.raises(AssertionError, match="residuals are not the radial distances"):
                test_every_built_in_result_passes(methods.get("circle.test_gate_named_liar"), data)
    finally:
        _REGISTRY.pop("circle.test_gate_named_honest", None)
        _REGISTRY.pop("circle.test_gate_named_liar", None)


def test_a_method_cannot_change_the_callers_array():
    seen = []

    @methods.register("circle.test_gate_mutator", kind="closed form", summary="writes", reference="gate test")
    def mutator(points):
        for attempt in (lambda: points.__setitem__((0, 0), 0.0), lambda: setattr(points.flags, "writeable", True)):
            try:
                attempt()
                seen.append("written")
            except ValueError:
                seen.append("refused")
        return results.circle_result(points, (0.0, 0.0), 1.0, converged=False, message="tried")

    try:
        for given in (CIRCLE.copy(), CIRCLE.tolist(), np.asfortranarray(CIRCLE), methods.immutable(CIRCLE)):
            before = np.array(given, copy=True)
            methods.fit("circle.test_gate_mutator", given)
            assert np.array_equal(np.asarray(given), before)
        # an ndarray (any layout) arrives immutable; a list becomes the method's own array (read-only)
        assert seen == ["refused", "refused", "refused", "written", "refused", "refused", "refused", "refused"]
    finally:
        _REGISTRY.pop("circle.test_gate_mutator", None)


def test_immutable_data_is_not_copied_again():
    frozen = methods.immutable(CIRCLE)
    assert methods.immutable(frozen) is frozen and not frozen.flags.writeable
    with pytest.raises(ValueError):
        frozen.flags.writeable = True
    from datasets import sources
    data, _ = sources.get_source("circle").load(np.random.default_rng(0), n=10)
    assert methods.immutable(data) is data     # what a data source gives the engine: no copy per timed call


@pytest.fixture(scope="module")
def recipe_site(tmp_path_factory):
    """The README's "Add a method" module, as written, installed as a plugin distribution (offline)."""
    from conftest import install_plugin
    from test_readme_plugin import recipe
    path, code, _ = recipe()
    return install_plugin(tmp_path_factory.mktemp("recipe"), "fitbench-gate-recipe", {"gate_recipe": code},
                          {"fitbench.methods": {"my_fit": "gate_recipe"}})


def test_fit_and_the_cli_refuse_a_result_that_breaks_its_contract(recipe_site, tmp_path):
    """The README's method with shrink=0 returns a converged circle of radius 0: methods.fit raises
    ResultContractError (an InvalidInputError) naming the broken rule, and the CLI's fit prints one line, exit
    non-zero, no 'converged yes'; with the default shrink both work. The engine's gate gives the same reason."""
    from conftest import run_python
    path = tmp_path / "circle.csv"
    np.savetxt(path, CIRCLE, delimiter=",", header="x,y", comments="")
    code = ("import numpy as np, methods\n"
            f"pts = np.loadtxt({str(path)!r}, delimiter=',', skiprows=1)\n"
            "print(round(methods.fit('circle.my_fit', pts).radius, 3))\n"
            "try:\n    methods.fit('circle.my_fit', pts, shrink=0.0)\n"
            "except methods.ResultContractError as exc:\n"
            "    print(isinstance(exc, methods.InvalidInputError), exc.problem)\n"
            "r = methods.get('circle.my_fit').unchecked(pts, shrink=0.0)\n"
            "print(methods.check_result(r, pts))\n")
    out = run_python("-c", code, path_first=[recipe_site])
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "299.0" and lines[1] == "True radius = 0 must be > 0" and lines[2] == "radius = 0 must be > 0"
    good = run_python("-m", "methods", "fit", "circle.my_fit", path, path_first=[recipe_site])
    assert good.returncode == 0 and "converged" in good.stdout, good.stderr
    bad = run_python("-m", "methods", "fit", "circle.my_fit", path, "--param", "shrink=0", path_first=[recipe_site])
    assert bad.returncode != 0 and "converged" not in bad.stdout, bad.stdout
    assert "Traceback" not in bad.stderr and len(bad.stderr.strip().splitlines()) == 1, bad.stderr
    assert "circle.my_fit returned a result that breaks its family's contract: radius = 0 must be > 0" in bad.stderr


def test_a_converged_claim_with_a_nan_circle_is_an_invalid_row():
    """A plugin method that builds its result with ``circle_result`` from a NaN circle and claims converged=True
    broke its promise (NaN is no answer): the row is ``invalid`` and says so. The builder downgraded it to "not
    converged" with a message about nearly straight points (a NaN circle is not one beyond float64's range: an
    overflowing one, all of whose non-finite values are infinite, is still downgraded, tests/test_circle_flags.py)."""
    from experiments.rows import fit_row

    @methods.register("circle.test_gate_nan", kind="closed form", summary="a NaN circle, converged", reference="gate test")
    def nan_circle(points, *, which="all"):
        center = (np.nan, np.nan) if which == "all" else (1200.0, np.nan) if which == "center_y" else (np.inf, np.nan)
        radius = np.nan if which == "all" else 299.0
        return results.circle_result(points, center, radius, converged=True, message="closed form")

    task = {"study": "gate", "dataset": {"label": "circle"}, "repetition": 0, "seed": 1, "stream": (0,),
            "method": "circle.test_gate_nan", "params": {}}
    try:
        for which, reason in (("all", "center_x = nan is not finite in a converged result"),
                              ("center_y", "center_y = nan is not finite in a converged result"),
                              ("inf_and_nan", "center_x = inf is not finite in a converged result")):
            res = methods.get("circle.test_gate_nan").unchecked(CIRCLE, which=which)
            assert res.converged and reason in methods.check_result(res, CIRCLE)
            row = fit_row({**task, "params": {"which": which}}, CIRCLE, {"center": (1200.0, 650.0), "radius": 299.0})
            assert row["status"] == "invalid" and reason in row["message"], row
            assert "float64's range" not in row["message"]
    finally:
        _REGISTRY.pop("circle.test_gate_nan", None)
