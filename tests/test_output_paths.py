"""The output files of a command (``--plot``, ``--report``, ``--compensation``, ``--errors-csv``): one that is an input
file (by any name: ``./x``, a symlink, a hard link) or that another output names too is refused in one line before
anything is computed or written; the outputs are written together once the command has ended, so a failure leaves
every one as it was and says which were not written; ``--json`` lists the files written."""
from __future__ import annotations

import hashlib
import json
import os
import shutil

import numpy as np
import pytest

from cli_calls import cli, one_error_line
from conftest import REPO

EXAMPLES = REPO / "docs" / "examples"


def digest(path) -> str:
    return hashlib.md5(path.read_bytes()).hexdigest()


@pytest.fixture
def axis(tmp_path):
    """The example positioning test (deviations in µm, stated in its header) as tmp_path/in.csv."""
    shutil.copy(EXAMPLES / "positioning.csv", tmp_path / "in.csv")
    return tmp_path / "in.csv"


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    from datasets.multilateration import write_example
    return write_example(tmp_path_factory.mktemp("ml"))


def refused_untouched(called, files: dict, folder, *words) -> None:
    """``called`` refused in one line holding ``words``; every file of ``files`` ({path: digest before}) is
    unchanged and no other file appeared in ``folder``."""
    one_error_line(called, *words)
    assert called.stdout == ""
    for path, before in files.items():
        assert digest(path) == before, f"{path} was overwritten"
    assert sorted(p.name for p in folder.iterdir()) == sorted(p.name for p in files if p.parent == folder)


@pytest.mark.parametrize("name", ["in.csv", "./in.csv", "link.csv", "hard.csv"])
def test_a_compensation_table_onto_the_measurement_is_refused(axis, name, monkeypatch):
    # R7: `--compensation csv in.csv` with in.csv the laser test wrote the table over it, exit 0
    folder = axis.parent
    monkeypatch.chdir(folder)
    if name == "link.csv":
        (folder / name).symlink_to(axis)
    elif name == "hard.csv":
        os.link(axis, folder / name)
    files = {axis: digest(axis)} | ({folder / name: digest(axis)} if name in ("link.csv", "hard.csv") else {})
    got = cli("positioning", "in.csv", "--axis", "X1", "--compensation", "csv", name)
    refused_untouched(got, files, folder, f"--compensation csv {name}", "input file", "another file name")


def test_multilaterate_errors_csv_onto_a_data_file_is_refused(campaign):
    meas, stations = campaign
    files = {meas: digest(meas), stations: digest(stations)}
    for target in (meas, stations):
        got = cli("multilaterate", meas, "--stations", stations, "--identify", "--errors-csv", target)
        refused_untouched(got, files, meas.parent, f"--errors-csv {target}", "input file")


@pytest.mark.parametrize("command", ["fit", "roundness", "circular-test", "magnify"])
def test_a_plot_onto_an_input_file_is_refused(tmp_path, command):
    # a points file whose name has an image suffix is read all the same: the plot went over it
    data = tmp_path / "data.svg"
    files = {data: None}
    if command == "magnify":   # a straight path and a trajectory 2 µm about it
        x = np.linspace(0.0, 100.0, 201)
        np.savetxt(data, np.c_[x, 0 * x], delimiter=",", header="x,y", comments="")
        np.savetxt(tmp_path / "meas.csv", np.c_[x, 0.002 * np.sin(x / 10)], delimiter=",", header="x,y", comments="")
        files[tmp_path / "meas.csv"] = None
    else:
        shutil.copy(EXAMPLES / {"fit": "trace.csv", "circular-test": "ballbar.csv"}.get(command, "roundness.csv"), data)
    args = {"fit": ["fit", "circle.kasa", data], "roundness": ["roundness", data],
            "circular-test": ["circular-test", data, "--nominal-radius", "150"],
            "magnify": ["magnify", data, tmp_path / "meas.csv", "--eta", "100"]}[command]
    got = cli(*args, "--plot", data)
    refused_untouched(got, {f: digest(f) for f in files}, tmp_path, f"--plot {data}", "input file")


def test_two_outputs_to_one_file_are_refused(axis):
    # R7: two tables to one path kept only the second while both were reported written
    folder = axis.parent
    got = cli("positioning", axis, "--axis", "X1", "--compensation", "csv", folder / "same.txt",
              "--compensation", "siemens-eec", folder / "same.txt")
    refused_untouched(got, {axis: digest(axis)}, folder, "name the same file", "its own file name")
    (folder / "link.pdf").symlink_to(folder / "r.pdf")
    got = cli("positioning", axis, "--plot", folder / "r.pdf", "--report", folder / "link.pdf")
    one_error_line(got, "--plot", "--report", "name the same file (by two names)")
    assert not (folder / "r.pdf").exists()


def test_an_output_in_a_missing_folder_is_refused_before_any_is_written(axis):
    # R10: the second table's missing folder ended the command after the first was written, without a word
    folder = axis.parent
    (folder / "ok1.csv").write_text("an older table\n")
    got = cli("positioning", axis, "--axis", "X1", "--compensation", "csv", folder / "ok1.csv",
              "--compensation", "siemens-eec", folder / "nonexist" / "x.mpf")
    one_error_line(got, "nonexist", "does not exist")
    assert (folder / "ok1.csv").read_text() == "an older table\n"


def test_a_failed_write_leaves_every_output_as_it_was_and_says_so(axis, monkeypatch):
    import fitbench.cli.options as options
    import fitbench.cli.positioning as positioning
    from methods import InvalidInputError
    real = options.write_text_atomic

    def disk_full_for_mpf(path, text):
        if str(path).endswith(".mpf"):
            raise InvalidInputError(f"cannot write {path}: No space left on device")
        real(path, text)

    monkeypatch.setattr(positioning, "write_text_atomic", disk_full_for_mpf)
    folder = axis.parent
    (folder / "ok1.csv").write_text("an older table\n")
    got = cli("positioning", axis, "--axis", "X1", "--plot", folder / "p.png", "--compensation", "csv",
              folder / "ok1.csv", "--compensation", "siemens-eec", folder / "x.mpf")
    one_error_line(got, "No space left", f"not written: {folder / 'ok1.csv'}")
    assert (folder / "ok1.csv").read_text() == "an older table\n"
    assert sorted(p.name for p in folder.iterdir()) == ["in.csv", "ok1.csv"]     # no temporary left


def test_a_failed_move_into_place_names_what_was_written(tmp_path):
    from fitbench.cli import guards
    with pytest.raises(guards.InvalidInputError) as err:
        with guards.staged_outputs():
            for name in ("a.csv", "b.csv"):
                guards.check_outputs([], [("--out", tmp_path / name, "table")])
                with guards.output_path(tmp_path / name) as tmp:
                    tmp.write_text(name)
            (tmp_path / "b.csv").mkdir()        # b.csv became a folder since it was checked
    assert f"written: {tmp_path / 'a.csv'}; not written: {tmp_path / 'b.csv'}" in str(err.value)
    assert (tmp_path / "a.csv").read_text() == "a.csv"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.csv"]


def test_json_lists_the_files_written(axis, campaign):
    # R10: with --json the tables were written and the JSON said nothing of them
    folder = axis.parent
    got = cli("positioning", EXAMPLES / "positioning_periodic.csv", "--axis", "X1", "--compensation-from", "mean",
              "--compensation", "siemens-eec", folder / "pj.mpf", "--compensation", "csv", folder / "pj.csv",
              "--plot", folder / "p.png", "--json")
    assert got.returncode == 0, got.stderr
    d = json.loads(got.stdout)
    written = {f["path"]: f for f in d["files_written"]}
    assert set(written) == {str(folder / n) for n in ("pj.mpf", "pj.csv", "p.png")}
    assert all((folder / n).is_file() for n in ("pj.mpf", "pj.csv", "p.png"))
    assert written[str(folder / "pj.mpf")]["option"] == "--compensation siemens-eec"
    comp = d["compensation"]
    assert [t["format"] for t in comp["tables"]] == ["siemens-eec", "csv"] and comp["source"] == "mean"
    assert comp["points"] <= 200 and comp["chosen"].startswith(f"every {comp['interval_mm']:g} mm")
    meas, stations = campaign
    got = cli("multilaterate", meas, "--stations", stations, "--identify", "--errors-csv", folder / "e.csv", "--json")
    d = json.loads(got.stdout)
    assert [f["path"] for f in d["files_written"]] == [str(folder / "e.csv")] and (folder / "e.csv").is_file()


def test_history_json_lists_the_files_written(tmp_path):
    """``history --json`` lists its --plot in ``files_written``, as every other command's JSON lists its files (it
    had no such field); without --plot the list is empty. The trends stay keyed by test beside it."""
    from profile_lines import profile_file
    folder = tmp_path / "machine"
    folder.mkdir()
    done = cli("roundness", profile_file(tmp_path / "shaft.csv", n=720), "--date", "2026-11-02", "--json")
    assert done.returncode == 0, done.stderr
    (folder / "r.json").write_text(done.stdout)
    got = cli("history", folder, "--json", "--plot", tmp_path / "trend.png")
    assert got.returncode == 0, got.stderr
    d = json.loads(got.stdout)
    assert d["files_written"] == [{"path": str(tmp_path / "trend.png"), "option": "--plot", "what": "plot"}]
    assert (tmp_path / "trend.png").is_file() and [t["file"] for t in d["roundness"]["tests"]] == ["r.json"]
    got = cli("history", folder, "--json")
    assert got.returncode == 0 and json.loads(got.stdout)["files_written"] == [], got.stderr


def test_every_output_option_is_checked():
    """Every option of a subcommand that names a file to write is one the tests above refuse onto an input (a new
    output option must be passed to fitbench.cli.guards.check_outputs and added here)."""
    from fitbench.cli import build_parser
    parser = build_parser()
    found = set()
    for name, sub in parser.subcommands.items():
        for action in sub._actions:
            metavar = " ".join(action.metavar) if isinstance(action.metavar, tuple) else str(action.metavar or "")
            if action.option_strings and any(w in metavar for w in ("FILE", "PNG", ".pdf")):
                found.add((name, action.option_strings[0]))
    inputs = {("multilaterate", "--stations")}
    # history's --plot: its input is a folder (a plot onto it is refused as a folder)
    covered = {("fit", "--plot"), ("roundness", "--plot"), ("roundness", "--report"), ("circular-test", "--plot"),
               ("circular-test", "--report"), ("magnify", "--plot"), ("positioning", "--plot"),
               ("positioning", "--report"), ("positioning", "--compensation"), ("multilaterate", "--errors-csv"),
               ("history", "--plot")}
    assert found - inputs == covered


@pytest.mark.parametrize("streams", ["stdout", "stdout and stderr"])
def test_a_reader_closing_the_pipe_early_still_gets_the_files(axis, streams):
    """`fitbench positioning in.csv --compensation csv t.csv ... | head -1` (also `2>&1 | head -1`): the reader has gone,
    the command still ends and writes every output (the same bytes as a run printing everything), exit 0 and quiet as
    for a closed pipe elsewhere (`experiments.run --list | head -1`). The print that met the closed pipe discarded
    the staged tables and the command said nothing, exit 0."""
    import subprocess
    import sys
    from conftest import subprocess_env
    folder = axis.parent
    tables = ["--compensation", "csv", "t.csv", "--compensation", "siemens-eec", "t.mpf"]
    (folder / "ref").mkdir()
    got = cli("positioning", axis, "--axis", "X1", *[str(folder / "ref" / a) if "." in a else a for a in tables])
    assert got.returncode == 0, got.stderr
    read, write = os.pipe()
    os.close(read)   # the reader has gone before the command prints
    try:
        done = subprocess.run([sys.executable, "-m", "fitbench", "positioning", "in.csv", "--axis", "X1", *tables],
                              cwd=folder, env=subprocess_env(), stdout=write,
                              stderr=write if streams != "stdout" else subprocess.PIPE, timeout=120)
    finally:
        os.close(write)
    assert done.returncode == 0 and not done.stderr, done.stderr
    for name in ("t.csv", "t.mpf"):
        assert (folder / name).read_bytes() == (folder / "ref" / name).read_bytes(), name
    assert sorted(p.name for p in folder.iterdir()) == ["in.csv", "ref", "t.csv", "t.mpf"]   # no temporary left


def _staged_table_appears(proc, folder, timeout=120.0) -> bool:
    """Wait until ``proc`` has staged t.csv (a hidden temporary beside it); False if it ended first."""
    import time
    end = time.monotonic() + timeout
    while proc.poll() is None and time.monotonic() < end:
        if any(p.name.startswith(".t.csv.") for p in folder.iterdir()):
            return True
        time.sleep(0.002)
    return False


@pytest.mark.parametrize("name", ["SIGTERM", "SIGHUP"])
def test_sigterm_and_sighup_remove_the_staged_outputs(axis, name):
    """A job scheduler's kill (SIGTERM) or a closed terminal (SIGHUP) once the tables are staged, while the plot is
    drawn: one line, exit 128 + the signal, every target as it was and no temporary left, as Ctrl-C. The default
    action ended the process at once and left the complete tables under hidden names for good."""
    import signal
    import subprocess
    import sys
    from conftest import subprocess_env
    num = getattr(signal, name)
    folder = axis.parent
    for old in ("t.csv", "t.mpf"):
        (folder / old).write_text("OLD\n")
    proc = subprocess.Popen([sys.executable, "-m", "fitbench", "positioning", "in.csv", "--axis", "X1", "--compensation",
                             "csv", "t.csv", "--compensation", "siemens-eec", "t.mpf", "--plot", "p.png"],
                            cwd=folder, env=subprocess_env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, preexec_fn=lambda: signal.signal(num, signal.SIG_DFL))   # as from a terminal
    try:
        assert _staged_table_appears(proc, folder), "the command ended before its tables were staged"
        proc.send_signal(num)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 128 + num and err.strip() == f"fitbench: terminated ({name})", (proc.returncode, err)
    assert sorted(p.name for p in folder.iterdir()) == ["in.csv", "t.csv", "t.mpf"]
    assert (folder / "t.csv").read_text() == (folder / "t.mpf").read_text() == "OLD\n"


def test_a_signal_while_the_outputs_move_into_place_waits_for_all(axis):
    """SIGTERM as the first staged output replaces its target: the others follow (all or none), then the command
    stops with its line and exit 143; before, the process ended between two replacements, temporaries left."""
    import subprocess
    import sys
    from conftest import subprocess_env
    script = ("import os, signal, sys\n"
              "signal.signal(signal.SIGTERM, signal.SIG_DFL)\n"
              "real = os.replace\n"
              "def replace(a, b):\n"
              "    os.replace = real\n"
              "    os.kill(os.getpid(), signal.SIGTERM)\n"
              "    real(a, b)\n"
              "os.replace = replace\n"
              "from fitbench.cli import main\n"
              "sys.exit(main(sys.argv[1:]))\n")
    folder = axis.parent
    for old in ("t.csv", "t.mpf"):
        (folder / old).write_text("OLD\n")
    done = subprocess.run([sys.executable, "-c", script, "positioning", "in.csv", "--axis", "X1", "--compensation",
                           "csv", "t.csv", "--compensation", "siemens-eec", "t.mpf"], cwd=folder, env=subprocess_env(),
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, timeout=120)
    assert done.returncode == 143 and done.stderr.strip() == "fitbench: terminated (SIGTERM)", done
    assert sorted(p.name for p in folder.iterdir()) == ["in.csv", "t.csv", "t.mpf"]
    assert (folder / "t.csv").read_text().startswith("#") and (folder / "t.mpf").read_text().startswith("%")


def test_an_exception_compiled_code_made_of_the_signal_still_stops_the_command():
    """matplotlib's renderer turns an exception raised in it (the signal's) into ValueError('Invalid bounding box'):
    it is reported as the signal (one line, 143), not as a traceback with exit 1."""
    import signal
    from fitbench.cli import guards
    with pytest.raises(guards.Terminated) as stopped:
        with guards.stopping_signals():
            try:
                guards._stop(signal.SIGTERM, None)
            except guards.Terminated:
                raise ValueError("Invalid bounding box") from None
    assert stopped.value.signum == signal.SIGTERM


def test_a_plot_is_staged_once(axis, monkeypatch):
    """The plot goes to one temporary beside p.png (the staged one), not to a second atomic write nested in it
    ('..p.png.X.tmp.png.Y.tmp.png', one more file a kill could leave)."""
    from methods import files
    real, made = files._temporary_beside, []

    def recording(path, make_parents):
        made.append(os.path.basename(path))
        return real(path, make_parents)

    monkeypatch.setattr(files, "_temporary_beside", recording)
    folder = axis.parent
    got = cli("positioning", axis, "--axis", "X1", "--compensation", "csv", folder / "t.csv", "--plot", folder / "p.png")
    assert got.returncode == 0, got.stderr
    assert sorted(made) == ["p.png", "t.csv"]
    assert sorted(p.name for p in folder.iterdir()) == ["in.csv", "p.png", "t.csv"]


def test_written_to_lines_follow_the_files(axis, monkeypatch):
    """The 'compensation table ... written to PATH' lines are printed once the tables are in place, and only for the
    ones that are: a table the move into place failed on is not said written (stdout said it, then stderr said
    'not written')."""
    real = os.replace

    def no_mpf(src, dst):
        if str(dst).endswith(".mpf"):
            raise PermissionError(13, "Permission denied")
        real(src, dst)

    folder = axis.parent
    monkeypatch.setattr(os, "replace", no_mpf)
    got = cli("positioning", axis, "--axis", "X1", "--compensation", "csv", folder / "t.csv",
              "--compensation", "siemens-eec", folder / "t.mpf")
    one_error_line(got, f"written: {folder / 't.csv'}; not written: {folder / 't.mpf'}")
    said = [line for line in got.stdout.splitlines() if "written to" in line]
    assert len(said) == 1 and said[0].endswith(f"written to {folder / 't.csv'}"), said
    monkeypatch.setattr(os, "replace", real)
    got = cli("positioning", axis, "--axis", "X1", "--compensation", "csv", folder / "t.csv",
              "--compensation", "siemens-eec", folder / "t.mpf")
    assert got.returncode == 0 and got.stdout.rstrip().endswith(f"written to {folder / 't.mpf'}"), got
    assert len([line for line in got.stdout.splitlines() if "written to" in line]) == 2
