"""``fitbench history`` never trends results evaluated with different settings as one series: the same positioning
data evaluated to ISO 230-2:2014 (k = 2) and 1988 (k = 3) read as A and R growing, a test corrected to 20 °C beside
uncorrected ones as A jumping, the same profile filtered at 50 and 15 UPR as RONt shrinking, and nothing said that
a setting had changed. They are now separate trends named by the setting that differs, with one warning line per
machine's axis (or test) saying which settings differ."""
from __future__ import annotations

import json

import numpy as np

from cli_calls import cli
from datasets.positioning import axis_test, to_frame
from profile_lines import profile_file


def _save(folder, name, *args):
    out = cli(*args, "--json")
    assert out.returncode == 0, out.stderr
    (folder / name).write_text(out.stdout)
    return json.loads(out.stdout)


def test_settings_that_change_the_figures_are_separate_trends(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(4))
    axis = tmp_path / "axis.csv"
    to_frame(data, actual=False).rename(columns={"deviation": "deviation [mm]"}).to_csv(axis, index=False)
    prof = profile_file(tmp_path / "shaft.csv", n=720)
    folder = tmp_path / "results"
    folder.mkdir()
    pos = ("positioning", axis, "--machine", "M1", "--axis", "X")
    got = {"a": _save(folder, "a.json", *pos, "--date", "2026-10-01"),
           "b": _save(folder, "b.json", *pos, "--date", "2026-11-01"),
           "d": _save(folder, "d.json", *pos, "--date", "2026-11-15", "--standard", "iso230-2:1988"),
           "f": _save(folder, "f.json", *pos, "--date", "2026-11-20", "--material-temperature", 26,
                      "--expansion-coefficient", 11.5),
           "c": _save(folder, "c.json", "roundness", prof, "--date", "2026-11-02", "--cutoff", 50),
           "e": _save(folder, "e.json", "roundness", prof, "--date", "2026-11-03", "--cutoff", 15)}
    # the settings do change the figures of the same data (what a pooled trend showed as a change of the machine)
    assert got["d"]["R"] > 1.2 * got["a"]["R"] and got["f"]["A"] != got["a"]["A"]
    assert got["e"]["references"]["lsci"]["RONt"] != got["c"]["references"]["lsci"]["RONt"]

    out = cli("history", folder, "--json")
    assert out.returncode == 0, out.stderr
    trends = json.loads(out.stdout)
    pos_trends = {tuple(t["settings"].values()): t for t in trends["positioning"]["trends"]}
    assert {k: [x["file"] for x in t["tests"]] for k, t in pos_trends.items()} == {
        ("iso230-2:2014 (k = 2)", "as measured"): ["a.json", "b.json"],
        ("iso230-2:1988 (k = 3)", "as measured"): ["d.json"],
        ("iso230-2:2014 (k = 2)", "corrected to 20 °C"): ["f.json"]}
    # each trend holds its own results' figures (µm)
    for t in pos_trends.values():
        for x in t["tests"]:
            assert x["R"] == got[x["file"][0]]["R"] * 1e3 and x["A"] == got[x["file"][0]]["A"] * 1e3
    rnd = {t["settings"]["filter"]: [x["file"] for x in t["tests"]] for t in trends["roundness"]["trends"]}
    assert rnd == {"50 UPR": ["c.json"], "15 UPR": ["e.json"]}
    # one warning per machine's axis (or test) that mixes settings, naming the settings and their values
    warned = out.stderr.strip().splitlines()
    assert len(warned) == 2, out.stderr
    assert all(w in warned[0] for w in ("positioning, machine M1, axis X", "different settings",
                                        "standard iso230-2:2014 (k = 2) / iso230-2:1988 (k = 3)",
                                        "deviations as measured / corrected to 20 °C", "separate trends"))
    assert "roundness" in warned[1] and "filter 50 UPR / 15 UPR" in warned[1]

    text = cli("history", folder).stdout
    heads = [ln for ln in text.splitlines() if ln.startswith(("positioning", "roundness"))]
    assert heads == [
        "positioning, machine M1, axis X, standard iso230-2:2014 (k = 2), deviations as measured: 2 test(s)",
        "positioning, machine M1, axis X, standard iso230-2:1988 (k = 3), deviations as measured: 1 test(s)",
        "positioning, machine M1, axis X, standard iso230-2:2014 (k = 2), deviations corrected to 20 °C: 1 test(s)",
        "roundness, machine not given, filter 50 UPR: 1 test(s)",
        "roundness, machine not given, filter 15 UPR: 1 test(s)"]
    # the plot's panels carry the same names
    from fitbench.cli import history
    titles = []
    history.plot(history.collect(folder), None, lambda fig, path: titles.extend(a.get_title() for a in fig.axes))
    assert [t.split(": trend over")[0] for t in titles] == [h.rsplit(": ", 1)[0] for h in heads]


def test_one_setting_throughout_is_one_trend_without_a_warning(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(5))
    axis = tmp_path / "axis.csv"
    to_frame(data, actual=False).rename(columns={"deviation": "deviation [mm]"}).to_csv(axis, index=False)
    folder = tmp_path / "results"
    folder.mkdir()
    for k, date in enumerate(("2026-01-01", "2026-02-01")):
        _save(folder, f"{k}.json", "positioning", axis, "--machine", "M1", "--axis", "X", "--date", date,
              "--standard", "iso230-2:1988")
    out = cli("history", folder)
    assert out.returncode == 0 and out.stderr == "", out.stderr
    assert out.stdout.splitlines()[0] == "positioning, machine M1, axis X: 2 test(s)"


def test_circular_tests_at_another_radius_or_feed_are_another_trend(tmp_path):
    """ISO 230-4 compares circular tests made at the same radius and feed: G at 150 mm or at another feed is
    another trend of the same machine's plane, and the warning names radius and feed."""
    folder = tmp_path / "results"
    folder.mkdir()
    for k, (radius, feed, g) in enumerate(((100, 1000, 0.010), (100, 1000, 0.011), (150, 1000, 0.014),
                                           (100, 2000, 0.016))):
        result = {"G_b": g, "G_cw": g, "G_ccw": g, "diagnostics": "not estimated: give --nominal-center X Y",
                  "details": {"conditions": {"machine": "M1", "plane": "XY", "date": f"2026-0{k + 1}-01",
                                             "nominal_radius_mm": radius, "feed_mm_min": feed}}}
        (folder / f"{k}.json").write_text(json.dumps(result))
    out = cli("history", folder, "--json")
    assert out.returncode == 0
    trends = json.loads(out.stdout)["circular-test"]["trends"]
    assert {tuple(t["settings"].values()): [x["file"] for x in t["tests"]] for t in trends} == {
        ("100 mm", "1000 mm/min"): ["0.json", "1.json"], ("150 mm", "1000 mm/min"): ["2.json"],
        ("100 mm", "2000 mm/min"): ["3.json"]}
    assert out.stderr.count("\n") == 1 and "radius 100 mm / 150 mm; feed 1000 mm/min / 2000 mm/min" in out.stderr
