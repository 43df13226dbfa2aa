"""What the ``fitbench`` command does with a user's inputs beyond the happy path: ``history`` over results of any
size and over files that are not results, ``--date`` checked where it is given, error lines naming the option or
the file the user gave, plugin methods that raise or print, and files in encodings the readers cannot read."""
from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from datasets.positioning import axis_test, to_frame
from profile_lines import circular_runs_file, profile_file


# ------------------------------------------------------------------------------------------ history
def test_history_reads_results_longer_than_a_reader_line_and_names_what_it_skips(tmp_path):
    """A roundness result (3600 points) and a 401-target positioning result are each one JSON line of more
    than 64 K characters: history trends them; a file that is not a result is named on stderr and skipped."""
    folder = tmp_path / "machine"
    folder.mkdir()
    out = cli("roundness", profile_file(tmp_path / "shaft.csv"), "--json", "--date", "2026-11-25")
    assert out.returncode == 0, out.stderr
    (folder / "r.json").write_text(out.stdout)
    data, _ = axis_test(travel=(0.0, 2000.0), targets=401, rng=np.random.default_rng(5))
    pos = tmp_path / "laser.csv"
    to_frame(data, actual=False).to_csv(pos, index=False)
    out = cli("positioning", pos, "--json", "--date", "2026-11-20")
    assert out.returncode == 0, out.stderr
    (folder / "p.json").write_text(out.stdout)
    assert min(len((folder / n).read_text()) for n in ("r.json", "p.json")) > 1 << 16
    (folder / "notes.json").write_text('{"operator": "A. N. Other"}')
    (folder / "broken.json").write_text('{"G_b": ')
    got = cli("history", folder, "--json")
    assert got.returncode == 0, got.stderr
    trend = json.loads(got.stdout)
    assert [t["date"][:10] for t in trend["roundness"]["tests"]] == ["2026-11-25"]
    assert [t["date"][:10] for t in trend["positioning"]["tests"]] == ["2026-11-20"]
    rond = json.loads((folder / "r.json").read_text())
    assert trend["roundness"]["tests"][0]["RONt LSCI"] == pytest.approx(rond["references"]["lsci"]["RONt"] * 1e3)
    assert trend["positioning"]["tests"][0]["A"] == pytest.approx(json.loads((folder / "p.json").read_text())["A"] * 1e3)
    lines = got.stderr.strip().splitlines()
    assert len(lines) == 2 and "Traceback" not in got.stderr, got.stderr
    assert any("notes.json" in ln and "skipped" in ln for ln in lines), got.stderr
    assert any("broken.json" in ln and "not valid JSON" in ln for ln in lines), got.stderr


@pytest.mark.parametrize("date", ["2026-13-45", "2026-02-30", "25.11.2026", "yesterday"])
def test_date_is_checked_where_it_is_given(tmp_path, date):
    """Every subcommand taking --date refuses one that is not a YYYY-MM-DD calendar date in one line, before
    writing a result that history could not date."""
    runs = circular_runs_file(tmp_path / "runs.csv")
    shaft = profile_file(tmp_path / "shaft.csv", n=360)
    data, _ = axis_test(rng=np.random.default_rng(2))
    pos = tmp_path / "pos.csv"
    to_frame(data, actual=False).to_csv(pos, index=False)
    for cmd in (("circular-test", runs, "--nominal-radius", 100), ("roundness", shaft), ("positioning", pos)):
        out = cli(*cmd, "--date", date, "--json")
        one_error_line(out, "--date", repr(date), "YYYY-MM-DD")
        assert out.stdout == ""
    good = cli("roundness", shaft, "--date", "2026-1-5", "--json")
    assert good.returncode == 0, good.stderr
    assert json.loads(good.stdout)["details"]["conditions"]["date"] == "2026-01-05"


def test_history_skips_a_result_with_a_bad_date_and_keeps_the_others(tmp_path):
    """A result written before --date was checked may hold any text as its date: that file is named in one
    warning and skipped; the folder's other results are trended."""
    folder = tmp_path / "machine"
    folder.mkdir()
    out = cli("circular-test", circular_runs_file(tmp_path / "runs.csv"), "--nominal-radius", 100,
              "--nominal-center", 0, 0, "--date", "2026-05-03", "--json")
    assert out.returncode == 0, out.stderr
    (folder / "good.json").write_text(out.stdout)
    old = json.loads(out.stdout)
    old["details"]["conditions"]["date"] = "2026-13-45"
    (folder / "old.json").write_text(json.dumps(old))
    got = cli("history", folder, "--json")
    assert got.returncode == 0, got.stderr
    assert [t["file"] for t in json.loads(got.stdout)["circular-test"]["tests"]] == ["good.json"]
    assert len(got.stderr.strip().splitlines()) == 1 and "old.json" in got.stderr and "2026-13-45" in got.stderr
    # details that are not an object (a hand-edited file): no date there, the file's time dates it
    old["details"] = "edited by hand"
    (folder / "old.json").write_text(json.dumps(old))
    got = cli("history", folder, "--json")
    assert got.returncode == 0 and got.stderr == "", got.stderr
    assert sorted(t["file"] for t in json.loads(got.stdout)["circular-test"]["tests"]) == ["good.json", "old.json"]


# ------------------------------------------------------------------------------------------ output options
def test_report_and_plot_errors_name_the_option_given(tmp_path):
    """A bad --report file (unknown format, missing folder, a folder) is refused naming --report, a bad --plot
    naming --plot, on every subcommand that takes them."""
    runs = circular_runs_file(tmp_path / "runs.csv")
    shaft = profile_file(tmp_path / "shaft.csv", n=360)
    data, _ = axis_test(rng=np.random.default_rng(2))
    pos = tmp_path / "pos.csv"
    to_frame(data, actual=False).to_csv(pos, index=False)
    bad = {"rep.txt": "unknown image format", str(tmp_path / "missing" / "rep.pdf"): "does not exist",
           str(tmp_path): "is a folder"}
    for cmd in (("circular-test", runs, "--nominal-radius", 100), ("roundness", shaft), ("positioning", pos)):
        for option in ("--report", "--plot"):
            for path, why in bad.items():
                out = cli(*cmd, option, path)
                one_error_line(out, f"{option} {path}:", why)
                assert ("--plot" if option == "--report" else "--report") not in out.stderr
                if why == "is a folder":
                    assert ("report.pdf" if option == "--report" else "plot.png") in out.stderr


# ------------------------------------------------------------------------------------------ plugin methods
def _raises(points):
    raise RuntimeError("solver exploded\n  at step 3")


def _writes(points):
    points -= points.mean(axis=0)          # a plugin that centres its input in place
    raise AssertionError("not reached: the input is read-only")


def _chatty(points):
    import methods
    print("iteration 1: cost 0.5")
    print("iteration 2: cost 0.1")
    return methods.get("circle.kasa").func(points)


@pytest.fixture
def plugin_methods():
    """Methods of a plugin (registered from this module, not methods.*) for one test only."""
    from plugin_methods import registered
    with registered({"circle.cli_raises": _raises, "circle.cli_writes": _writes, "circle.cli_chatty": _chatty},
                    kind="closed form", summary="CLI test plugin", reference="fitbench test"):
        yield


def test_a_plugin_method_that_raises_is_one_line_naming_it(tmp_path, plugin_methods):
    shaft = profile_file(tmp_path / "shaft.csv", n=360)
    for mid, words in (("circle.cli_raises", ("RuntimeError: solver exploded at step 3",)),
                       ("circle.cli_writes", ("ValueError", "read-only", "points.copy()"))):
        for extra in ((), ("--json",)):
            out = cli("fit", mid, shaft, *extra)
            assert out.returncode not in (0, 1), (out.returncode, out.stderr)   # 1: a fit that did not converge
            assert out.stdout == "" and "Traceback" not in out.stderr
            assert len(out.stderr.strip().splitlines()) == 1, out.stderr
            assert f"{mid} failed" in out.stderr and "test_cli_inputs" in out.stderr, out.stderr
            for w in words:
                assert w in out.stderr, out.stderr


def test_a_plugin_method_that_prints_leaves_stdout_to_the_json(tmp_path, plugin_methods):
    import methods
    shaft = profile_file(tmp_path / "shaft.csv", n=360)
    out = cli("fit", "circle.cli_chatty", shaft, "--json")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)                               # the whole of stdout is the one JSON object
    ref = methods.fit("circle.kasa", np.loadtxt(shaft, delimiter=",", skiprows=1))
    assert d["method"] == "circle.cli_chatty" and d["radius"] == pytest.approx(ref.radius, rel=1e-12)
    assert "iteration 1: cost 0.5" in out.stderr and "iteration 2: cost 0.1" in out.stderr


# ------------------------------------------------------------------------------------------ program name
def test_errors_and_warnings_name_the_program_the_user_ran(tmp_path):
    """'python -m methods run' answered 'fitbench: error: ... invalid choice'; the lines now start with the
    program used, and the experiment subcommands are pointed to the command that has them."""
    from conftest import run_python
    from fitbench.cli import DELEGATED
    from fitbench.cli.commands import EXPERIMENT_SUBCOMMANDS, main as commands_main
    assert set(EXPERIMENT_SUBCOMMANDS) == set(DELEGATED)
    out = run_python("-m", "methods", "run", "published")
    assert out.returncode == 2 and "Traceback" not in out.stderr, out.stderr
    assert out.stderr.startswith("python -m methods: error: 'run' is a subcommand of fitbench"), out.stderr
    assert "'fitbench run ...'" in out.stderr and len(out.stderr.strip().splitlines()) == 1
    latin = tmp_path / "latin.csv"
    latin.write_bytes("x [µm],y [µm]\n".encode("cp1252") + b"".join(b"%.4f,%.4f\n" % (np.cos(a) * 1e3, np.sin(a) * 1e3)
                                                                    for a in np.linspace(0, 6, 20)))
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        assert commands_main(["fit", "circle.kasa", str(latin)], prog="python -m methods") == 0
        assert commands_main(["fit", "circle.kasa", str(tmp_path / "absent.csv")], prog="python -m methods") == 2
    lines = err.getvalue().strip().splitlines()
    assert lines[0].startswith("python -m methods: warning: ") and "Windows-1252" in lines[0], lines
    assert lines[-1].startswith("python -m methods: error: ") and "absent.csv: no such file" in lines[-1], lines
    assert cli("fit", "circle.kasa", tmp_path / "absent.csv").stderr.startswith("fitbench: error: ")


def test_output_of_compiled_code_in_a_method_leaves_stdout_to_the_json(tmp_path):
    """A method whose compiled solver writes its log to descriptor 1 (printf, still in the C buffers when the
    method returns, and a raw write) keeps ``--json`` one JSON object on stdout: the log goes to stderr."""
    from conftest import run_python
    shaft = profile_file(tmp_path / "shaft.csv", n=360)
    script = tmp_path / "chatty_c.py"
    script.write_text(
        "import ctypes, os, sys\n"
        "import methods\n"
        "from fitbench.cli import main\n"
        "@methods.register('circle.c_chatty', kind='closed form', summary='C log (test)', reference='fitbench test')\n"
        "def c_chatty(points):\n"
        "    ctypes.CDLL(None).printf(b'solver log from printf\\n')\n"
        "    os.write(1, b'solver log from write\\n')\n"
        "    return methods.get('circle.kasa').func(points)\n"
        "sys.exit(main(sys.argv[1:]))\n")
    out = run_python(script, "fit", "circle.c_chatty", shaft, "--json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["method"] == "circle.c_chatty"
    assert "solver log from printf" in out.stderr and "solver log from write" in out.stderr, out.stderr
