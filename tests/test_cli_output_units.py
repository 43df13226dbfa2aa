"""What the operator reads from ``fitbench fit`` and ``fitbench history``: a plain converged line (the solver's
test, in its unit frame, with --verbose and in the JSON), and trends kept apart per machine and axis."""
import json

import numpy as np
import pytest

from fitbench.cli import main


@pytest.fixture
def circle_file(tmp_path):
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    r = 12.5 + 0.002 * np.cos(5 * t)
    path = tmp_path / "part.csv"
    np.savetxt(path, np.column_stack([30 + r * np.cos(t), -5 + r * np.sin(t)]), delimiter=",", header="x,y",
               comments="", fmt="%.9f")
    return str(path)


def test_fit_prints_a_plain_converged_line(circle_file, capsys):
    """The converged line read 'yes ((Delta^T Delta)^(1/2) <= xtol=1e-12; stationary: ... (unit frame))'."""
    assert main(["fit", "circle.gauss_newton", circle_file]) == 0
    out = capsys.readouterr().out
    assert "converged    yes\n" in out and "unit frame" not in out and "solver" not in out
    assert main(["fit", "circle.gauss_newton", circle_file, "--verbose"]) == 0
    out = capsys.readouterr().out
    assert "converged    yes\n" in out
    solver = [ln for ln in out.splitlines() if ln.startswith("solver ")]
    assert len(solver) == 1 and "unit frame" in solver[0]
    assert main(["fit", "circle.gauss_newton", circle_file, "--json"]) == 0
    assert "unit frame" in json.loads(capsys.readouterr().out)["message"]


def test_fit_that_did_not_converge_still_says_why(circle_file, capsys):
    assert main(["fit", "circle.gauss_newton", circle_file, "--param", "max_iter=1", "--param", "xtol=1e-300",
                 "--param", "start=29,-4,12"]) == 1
    line = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("converged")][0]
    assert line.startswith("converged    NO (") and len(line) > len("converged    NO ()") + 10
