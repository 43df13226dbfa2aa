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


def test_history_keeps_machines_and_axes_apart(tmp_path, capsys):
    """history pooled every positioning result of a folder into one trend (machine M1's X axis, its Y axis and
    machine M2's X axis read as one axis drifting), and the positioning JSON did not record the axis. Each trend is
    now one (test, machine, axis); the JSON records --axis in details.conditions."""
    from datasets.positioning import axis_test, to_frame
    folder = tmp_path / "results"
    folder.mkdir()
    runs = [("M1", "X", "2026-01-10", 0.0), ("M1", "Y", "2026-01-11", 0.01), ("M2", "X", "2026-01-12", 0.02),
            ("M1", "X", "2026-03-10", 0.004), (None, None, "2026-02-01", 0.0)]
    for k, (machine, axis, date, slope) in enumerate(runs):
        data, _ = axis_test(rng=np.random.default_rng(k), pitch=(0.0, slope))
        src = tmp_path / f"axis{k}.csv"
        to_frame(data, actual=False).to_csv(src, index=False)
        args = ["positioning", str(src), "--date", date, "--json"]
        args += ["--machine", machine] if machine else []
        args += ["--axis", axis] if axis else []
        assert main(args) == 0
        d = json.loads(capsys.readouterr().out)
        assert d["details"]["conditions"]["axis"] == (axis or "")
        (folder / f"{k}.json").write_text(json.dumps(d))
    assert main(["history", str(folder), "--json", "--plot", str(tmp_path / "trend.png")]) == 0
    trend = json.loads(capsys.readouterr().out)["positioning"]
    got = {(t["machine"], t["axis"]): [x["file"] for x in t["tests"]] for t in trend["trends"]}
    assert got == {("", ""): ["4.json"], ("M1", "X"): ["0.json", "3.json"], ("M1", "Y"): ["1.json"],
                   ("M2", "X"): ["2.json"]}
    assert [t["file"] for t in trend["tests"]] == ["0.json", "1.json", "2.json", "4.json", "3.json"]
    assert all({"machine", "axis"} <= set(t) for t in trend["tests"])
    assert main(["history", str(folder)]) == 0
    heads = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("positioning")]
    assert heads == ["positioning, machine not given, axis not recorded: 1 test(s)",
                     "positioning, machine M1, axis X: 2 test(s)", "positioning, machine M1, axis Y: 1 test(s)",
                     "positioning, machine M2, axis X: 1 test(s)"]
    assert (tmp_path / "trend.png").read_bytes().startswith(b"\x89PNG")


def test_history_plot_has_a_panel_per_trend(tmp_path):
    import datetime as dt
    from fitbench.cli import history
    rows = [(dt.datetime(2026, 1, d), f"{d}.json", {"A": 1.0, "E": 1.0, "R": 1.0, "B": 1.0, "M": 1.0}) for d in (1, 2)]
    trends = {("positioning", "M1", "X"): rows, ("positioning", "M1", "Y"): rows[:1]}
    titles = []

    def save(fig, path):
        titles.extend(ax.get_title() for ax in fig.axes if ax.get_title())
    history.plot(trends, None, save)
    assert titles == ["positioning, machine M1, axis X: trend over 2 test(s)",
                      "positioning, machine M1, axis Y: trend over 1 test(s)"]


def test_roundness_json_names_its_units_as_the_other_commands_do(circle_file, capsys):
    """roundness --json said units {lengths, angles} with input_unit outside them, where fit, circular-test and
    positioning say units {length, angle, input_unit}: a script reading units.length failed on it."""
    assert main(["roundness", circle_file, "--json"]) == 0
    units = json.loads(capsys.readouterr().out)["units"]
    assert units["length"] == "mm" and units["angle"] == "rad" and units["input_unit"] == "mm"
    assert main(["fit", "circle.kasa", circle_file, "--json"]) == 0
    assert {"length", "angle", "input_unit"} <= set(json.loads(capsys.readouterr().out)["units"])
