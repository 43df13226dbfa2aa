"""The command line: human and JSON output, one-line errors with exit status 2.

The program itself (``python -m methods`` in a new process: its exit status, its stdout, its stderr) is run by
:func:`run` where that is what a test checks (the listing, an error's exit status and single line, the JSON output);
the other cases of the same commands call its entry point in this process (:func:`run_here`), which saves a Python
start-up and fitbench's imports each (~0.5 s of CPU)."""
import contextlib
import io
import json
from types import SimpleNamespace

import pytest

from conftest import REPO, run_python
from fitbench.cli.commands import main


def run(*args, cwd=REPO):
    return run_python("-m", "methods", *args, cwd=cwd)


def run_here(*args):
    """``python -m methods ARGS`` as :func:`run` gives it (exit status, stdout, stderr), by its entry point
    (``methods/__main__.py``: ``sys.exit(main(prog="python -m methods"))``) in this process; an exception escaping it
    fails the test as a traceback would."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in args], prog="python -m methods")
        except SystemExit as exc:  # argparse's own exit
            code = exc.code
    return SimpleNamespace(returncode=code, stdout=out.getvalue(), stderr=err.getvalue())


def test_list_one_line_per_method():
    out = run("list")
    assert out.returncode == 0
    lines = out.stdout.strip().splitlines()
    assert len(lines) >= 8
    assert any(l.startswith("circle.gauss_newton") and "iterative" in l and "least squares" in l for l in lines)


def test_list_of_a_family_that_does_not_exist_says_so():
    out = run("list", "--family", "nosuch")
    assert out.returncode == 2 and out.stdout == ""
    assert out.stderr.strip().splitlines() == [out.stderr.strip()] and "no family 'nosuch'" in out.stderr
    assert "circle, ellipse" in out.stderr and "Traceback" not in out.stderr
    assert run_here("list", "--family", "ellipse").stdout.startswith("ellipse.")


def test_fit_published_set_json():
    out = run("fit", "circle.gauss_newton", "roundness_set2", "--json")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    for key in ("method", "center", "radius", "form_error", "converged", "iterations", "nfev", "runtime_s"):
        assert key in d
    assert d["method"] == "circle.gauss_newton" and round(d["form_error"], 4) == 1.7487
    assert len(d["residuals"]) == 20


def test_fit_file_with_params_human_table(tmp_path):
    f = tmp_path / "arc.csv"
    f.write_text("x;y\n1;0\n0;1\n-1;0\n0;-1\n0,7071067811865476;0,7071067811865476\n")
    out = run_here("fit", "circle.nelder_mead", str(f), "--param", "backend=nlopt", "--param", "start=0,0,2",
              "--param", "step=0.1,0.1,0.1")
    assert out.returncode == 0, out.stderr
    assert "radius" in out.stdout and "backend='nlopt'" in out.stdout and "start=[0, 0, 2]" in out.stdout


@pytest.mark.parametrize("args, match", [
    (("fit", "circle.gauss_newtn", "roundness_set2"), "did you mean circle.gauss_newton"),
    (("fit", "circle.kasa", "no_such_file.csv"), "no such file"),
    (("fit", "circle.kasa", "roundness_set2", "--param", "nope=1"), "no parameter 'nope'"),
    (("fit", "circle.gauss_newton", "roundness_set2", "--param", "max_iter=lots"), "not an integer"),
    (("fit", "circle.kasa", "roundness_set2", "--param", "novalue"), "KEY=VALUE"),
    (("frobnicate",), "invalid choice"),
])
def test_bad_input_one_line_exit_2(args, match):
    out = run_here(*args)
    assert out.returncode == 2
    assert out.stdout == ""
    err = out.stderr.strip().splitlines()
    assert len(err) == 1 and match in err[0] and "Traceback" not in out.stderr


@pytest.mark.parametrize("content, match", [
    ("x,y\n0,0\n1,1\n", "at least 3 points"),
    ("x,y\n0,0\n1,1\n2,2\n", "straight line"),
    ("x,y\n1,1\n1,1\n1,1\n", "identical"),
    ("x,y\n0,0\n1,inf\n2,0\n", "not a finite number"),
    ("x,y\n0,0\n1,1;\n", "not a number"),
])
def test_bad_data_files(tmp_path, content, match):
    f = tmp_path / "bad.csv"
    f.write_text(content)
    out = run_here("fit", "circle.gauss_newton", str(f))
    assert out.returncode == 2 and match in out.stderr and "Traceback" not in out.stderr
