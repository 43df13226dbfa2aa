"""Results that are right but easy to misread carry a note, and ``fitbench fit`` prints it above the figures.

* The minimum circumscribed circle of a partial arc (points that do not surround a centre) is the smallest circle
  holding the arc (for a 90 deg arc: the chord as its diameter), certified, but not the arc's circle: a 4 um arc
  of R 50 mm read 'form error 20.7 mm, converged yes' with no word, where max_inscribed flags the partial arc.
* The angle of an ellipse whose a - b is far below the residual RMS is undetermined: it was printed to 10 digits."""
from __future__ import annotations

import json

import numpy as np
import pytest

import methods
from cli_calls import cli
from datasets.synthetic import circle_points, ellipse_points


def arc_points(span_deg=90.0, n=181):
    t = np.radians(np.linspace(0.0, span_deg, n))
    r = 50.0 + 0.002 * np.cos(5 * t)
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def test_mcc_of_a_partial_arc_is_certified_and_noted():
    res = methods.fit("circle.min_circumscribed", arc_points())
    assert res.converged and res.extra["certified"] == "global"   # the MCC of the arc, as the mathematics says
    assert res.radius == pytest.approx(0.5 * np.hypot(50.002, 50.0), rel=1e-4)   # the chord as its diameter
    assert res.extra["angular_gap_deg"] == pytest.approx(270.0, abs=0.1)
    [note] = res.extra["notes"]
    assert "partial arc" in note and "not its circle" in note and "circle.minimum_zone" in note


@pytest.mark.parametrize("span_deg", [200.0, 360.0])
def test_mcc_of_points_around_a_centre_has_no_note(span_deg):
    res = methods.fit("circle.min_circumscribed", circle_points((3.0, -2.0), 50.0, 200, arc=(0.0, np.radians(span_deg)),
                                                                endpoint=span_deg < 360))
    assert res.converged and "notes" not in res.extra and res.radius == pytest.approx(50.0, rel=1e-12)


def test_fit_prints_the_partial_arc_note_before_the_figures(tmp_path):
    p = tmp_path / "arc.csv"
    np.savetxt(p, arc_points(), delimiter=",", header="x,y", comments="", fmt="%.9f")
    code, out, err = cli("fit", "circle.min_circumscribed", p)
    assert code == 0 and "Traceback" not in err, err
    note = next(i for i, line in enumerate(out.splitlines()) if line.startswith("note: ") and "partial arc" in line)
    assert note < next(i for i, line in enumerate(out.splitlines()) if line.startswith("form error"))
    code, out, _ = cli("fit", "circle.min_circumscribed", p, "--json", "--no-residuals")
    assert code == 0 and any("not its circle" in n for n in json.loads(out)["notes"])


@pytest.mark.parametrize("method_id", ["ellipse.halir_flusser", "ellipse.orthogonal"])
def test_ellipse_angle_of_a_near_circle_is_noted_as_undetermined(method_id):
    rng = np.random.default_rng(7)
    near = ellipse_points((120.0, 80.0), (50.0001, 50.0), 0.9, 240, noise=0.0005, rng=rng)   # a - b 0.1 um, 0.5 um noise
    res = methods.fit(method_id, near)
    assert res.converged and any(n.startswith("the angle is") and "determined" in n for n in res.extra["notes"]), res.extra
    clear = ellipse_points((120.0, 80.0), (50.0221, 50.0), 0.9, 3358, noise=0.001, rng=rng)  # the paper's a - b
    assert "notes" not in methods.fit(method_id, clear).extra


def test_fit_prints_the_angle_note(tmp_path):
    rng = np.random.default_rng(8)
    p = tmp_path / "trace.csv"
    np.savetxt(p, ellipse_points((120.0, 80.0), (50.0001, 50.0), 0.9, 240, noise=0.0005, rng=rng), delimiter=",",
               header="x,y", comments="", fmt="%.9f")
    code, out, err = cli("fit", "ellipse.halir_flusser", p)
    assert code == 0 and "note: the angle is" in out and "determined" in out, (out, err)
