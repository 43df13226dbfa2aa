"""An ellipse truth of a file data set is held to the convention the ellipse family's results follow (``EllipseFit``:
a >= b, the angle the direction of a in rad, its error taken modulo pi), review16 V12: ``semi_axes = [40.0, 50.0]``
was accepted and compared crosswise (semi_axis_a_error 10 mm of an exact fit), ``angle = 30.0`` (degrees, as the
generators' ``angle_deg``) gave an angle error of -0.60 rad. Both are one line when the study is loaded."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from experiments import config as configs
from experiments.schema import truth_problem
from experiments.study import ConfigError
from methods import results

STUDY = '''
name = "ell"
title = "t"
seed = 1
[[datasets]]
file = "ring.csv"
truth = {truth}
[[methods]]
id = "ellipse.halir_flusser"
'''


def _write(tmp_path, truth):
    t = np.linspace(0.0, 2 * np.pi, 24, endpoint=False)
    np.savetxt(tmp_path / "ring.csv", np.c_[50 * np.cos(t), 40 * np.sin(t)], delimiter=",", header="x,y", comments="")
    path = tmp_path / "ell.toml"
    path.write_text(STUDY.format(truth=truth), encoding="utf-8")
    return path


@pytest.mark.parametrize("truth, said", [
    ('{ family = "ellipse", semi_axes = [40.0, 50.0], angle = 0.5 }',
     "datasets[0].truth.semi_axes: a >= b (the semi-major axis first, at angle; the fits give a >= b), got [40, 50]: "
     f"write semi_axes = [50, 40], angle = {0.5 + math.pi / 2:.6g} (the angle of 50 in rad)"),
    ('{ family = "ellipse", semi_axes = [50.0, 40.0], angle = 30.0 }',
     "datasets[0].truth.angle: 30 is beyond ±2π: the angle is in rad (the direction of semi-axis a; 30° is 0.523599 "
     "rad)"),
])
def test_an_ellipse_truth_against_the_convention_is_refused_in_one_line(tmp_path, truth, said):
    with pytest.raises(ConfigError) as caught:
        configs.load(str(_write(tmp_path, truth)))
    assert said in str(caught.value) and "\n" not in str(caught.value), str(caught.value)


@pytest.mark.parametrize("angle", [0.0, -0.5, 3.5, -2 * math.pi])
def test_an_angle_in_any_radian_convention_loads(tmp_path, angle):
    configs.load(str(_write(tmp_path, f'{{ family = "ellipse", semi_axes = [50.0, 40.0], angle = {angle!r} }}')))


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
