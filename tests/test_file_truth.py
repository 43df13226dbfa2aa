"""A file data set's ``truth`` table is checked when the study's config is loaded, against what the result classes
compare (``experiments.schema.TRUTH_KEYS``): a shape no fit can be compared with (``center = [120.0]``: every row
was ``error`` with ``IndexError: list index out of range``, blamed on the method and retried every run) or an
unknown key (``centre``: silently no centre error) is one line naming ``datasets[0].truth.KEY``, exit 2.

An ellipse truth is held to the convention the ellipse family's results follow (``EllipseFit``: a >= b, the angle
the direction of a in rad, its error taken modulo pi): ``semi_axes = [40.0, 50.0]`` was accepted and compared
crosswise (semi_axis_a_error 10 mm of an exact fit), ``angle = 30.0`` (degrees, as the generators' ``angle_deg``)
gave an angle error of -0.60 rad. Both are one line when the study is loaded."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from cli_calls import call, one_error_line
from experiments import config as configs
from experiments import run
from experiments.schema import FAMILY_TRUTH, TRUTH_KEYS, truth_problem
from experiments.study import ConfigError
from methods import results

STUDY = '''
name = "truthy"
title = "t"
seed = 1
[[datasets]]
file = "ring.csv"
truth = {truth}
[[methods]]
id = "{method}"
{extra}
'''


def _write(tmp_path, truth, method="circle.kasa", extra=""):
    t = np.linspace(0.0, 2 * np.pi, 24, endpoint=False)
    np.savetxt(tmp_path / "ring.csv", np.c_[120 + 50 * np.cos(t), 80 + 30 * np.sin(t)], delimiter=",",
               header="x,y", comments="")
    path = tmp_path / "truthy.toml"
    path.write_text(STUDY.format(truth=truth, method=method, extra=extra), encoding="utf-8")
    return path


@pytest.mark.parametrize("truth, said", [
    ('{ center = [120.0], radius = "50" }', "datasets[0].truth.center: must be 2 finite numbers [x, y]"),
    ('{ center = [120.0, 80.0], radius = "50" }', "datasets[0].truth.radius: must be a number > 0"),
    ('{ center = [120.0, true] }', "datasets[0].truth.center: must be 2 finite numbers"),
    ('{ centre = [120.0, 80.0], radius = 50.0 }', "datasets[0].truth.centre: unknown key (a file's truth has: center, "
                                                   "radius, semi_axes, angle, family; no fit compares 'centre'); "
                                                   "did you mean 'center'?"),
    ('{ family = "circle", center = [120.0, 80.0], semi_axes = [50.0, 30.0], angle = 0.0 }',
     "datasets[0].truth.semi_axes: unknown key (the truth of a circle has: center, radius, family"),
    ('{ family = "ellipse", center = [120.0, 80.0], semi_axes = [50.0, 30.0] }',
     "datasets[0].truth.semi_axes: needs angle too"),
    # an ellipse truth against the convention of the family's results
    ('{ family = "ellipse", semi_axes = [40.0, 50.0], angle = 0.5 }',
     "datasets[0].truth.semi_axes: a >= b (the semi-major axis first, at angle; the fits give a >= b), got [40, 50]: "
     f"write semi_axes = [50, 40], angle = {0.5 + math.pi / 2:.6g} (the angle of 50 in rad)"),
    ('{ family = "ellipse", semi_axes = [50.0, 40.0], angle = 30.0 }',
     "datasets[0].truth.angle: 30 is beyond ±2π: the angle is in rad (the direction of semi-axis a; 30° is 0.523599 "
     "rad)"),
])
def test_a_truth_no_fit_can_be_compared_with_is_refused_in_one_line(tmp_path, truth, said):
    method = "ellipse.fitzgibbon" if "ellipse" in truth else "circle.kasa"
    with pytest.raises(ConfigError) as caught:
        configs.load(str(_write(tmp_path, truth, method)))
    assert said in str(caught.value) and "\n" not in str(caught.value), str(caught.value)


def test_the_run_refuses_it_before_any_row(tmp_path):
    path = _write(tmp_path, '{ center = [120.0], radius = "50" }')
    one_error_line(call(run.main, path, "--out", tmp_path / "out", "--no-report"),
                   "truthy.toml: datasets[0].truth.center: must be")
    assert not (tmp_path / "out" / "truthy" / "results.csv").exists()


def test_sound_truths_load(tmp_path):
    configs.load(str(_write(tmp_path, "{ center = [120, 80.0], radius = 50 }")))
    configs.load(str(_write(tmp_path, '{ family = "ellipse", center = [120.0, 80.0], semi_axes = [50.0, 30.0], '
                                      'angle = 0.0 }', "ellipse.fitzgibbon")))
    # another family's truth is read by that family's own class, whatever its keys
    configs.load(str(_write(tmp_path, '{ family = "square", center = [120.0, 80.0], side = 2.0 }',
                            extra="any_family = true")))


# ------------------------------------------------------------------- an ellipse truth's convention
@pytest.mark.parametrize("angle", [0.0, -0.5, 3.5, -2 * math.pi])
def test_an_angle_in_any_radian_convention_loads(tmp_path, angle):
    configs.load(str(_write(tmp_path, f'{{ family = "ellipse", semi_axes = [50.0, 40.0], angle = {angle!r} }}',
                            "ellipse.halir_flusser")))


def test_the_rewritten_truth_gives_the_errors_of_the_same_ellipse():
    """The rewrite the refusal suggests describes the same ellipse: an exact fit's errors against it are 0, where the
    truth as given made a 10 mm semi-axis error of each."""
    cls = results.contract("ellipse")
    fitted = SimpleNamespace(center=np.array([0.0, 0.0]), semi_axes=np.array([50.0, 40.0]),
                             angle=(0.5 + math.pi / 2) % math.pi)
    given = {"center": [0.0, 0.0], "semi_axes": [40.0, 50.0], "angle": 0.5}
    assert cls.truth_errors(fitted, given)["semi_axis_a_error"] == pytest.approx(10.0)
    key, said = truth_problem({"family": "ellipse", **given})
    rewritten = {"center": [0.0, 0.0], "semi_axes": [50.0, 40.0],
                 "angle": float(said.split("angle = ")[1].split(" ")[0])}
    errors = cls.truth_errors(fitted, rewritten)
    assert max(abs(v) for v in errors.values()) < 1e-5, errors


class _Recording(dict):
    """A truth that records the keys a ``truth_errors`` asks for."""

    def __init__(self, *args):
        super().__init__(*args)
        self.asked = set()

    def __contains__(self, key):
        self.asked.add(key)
        return super().__contains__(key)

    def __getitem__(self, key):
        self.asked.add(key)
        return super().__getitem__(key)

    def get(self, key, default=None):
        self.asked.add(key)
        return super().get(key, default)


@pytest.mark.parametrize("family", sorted(FAMILY_TRUTH))
def test_the_keys_checked_are_those_the_family_compares(family):
    cls = results.contract(family)
    fitted = SimpleNamespace(center=np.array([1.0, 2.0]), radius=3.0, semi_axes=np.array([3.0, 2.0]), angle=0.5)
    truth = _Recording({"center": [1.5, 2.5], "radius": 2.0, "semi_axes": [2.0, 1.0], "angle": 0.25,
                        "family": family})
    errors = cls.truth_errors(fitted, truth)
    assert errors and all(np.isfinite(v) for v in errors.values())
    assert truth.asked == set(FAMILY_TRUTH[family]) and truth.asked <= set(TRUTH_KEYS)
