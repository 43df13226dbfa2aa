"""A method's exception is the method's failure, named by its own type: one raising a ``BaseException`` subclass of
its own, or an exception whose ``str()`` raises, ends ``fitbench fit`` with one line and exit status 3 (it was a
traceback), and makes an ``error`` row whose message names the exception the method raised (the message blamed the
``RuntimeError`` its ``__str__`` raised, or the row crashed the worker). A method that raises SystemExit (sys.exit()
in a plugin) is one too: `fitbench fit` printed nothing and exited 0 (a script reading --json got an empty output and
success)."""
import numpy as np
import pandas as pd
import pytest

import methods
from conftest import install_plugin, run_python
from fitbench.cli.commands import EXIT_METHOD_FAILED, main
from plugin_methods import plugin_here, registered
from study_kinds import circle_study

RAISERS = '''
from methods import InvalidInputError, register


class Weird(BaseException):
    pass


class BadStr(ValueError):
    def __str__(self):
        raise RuntimeError("no str for you")


class WeirdBadStr(BaseException):
    def __str__(self):
        raise RuntimeError("no str either")


class BadRefusal(InvalidInputError):
    def __str__(self):
        raise RuntimeError("no refusal text")


class Unrepresentable:
    def __repr__(self):
        raise RuntimeError("no repr")


@register("circle.raise_weird", kind="closed form", summary="raises a BaseException subclass", reference="a test")
def raise_weird(points):
    raise Weird("weird")


@register("circle.raise_bad_str", kind="closed form", summary="raises an exception whose str raises",
          reference="a test")
def raise_bad_str(points):
    raise BadStr()


@register("circle.raise_weird_bad_str", kind="closed form", summary="a BaseException whose str raises",
          reference="a test")
def raise_weird_bad_str(points):
    raise WeirdBadStr(Unrepresentable())


@register("circle.raise_bad_refusal", kind="closed form", summary="an InvalidInputError whose str raises",
          reference="a test")
def raise_bad_refusal(points):
    raise BadRefusal()
'''


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("raisers"), "fitbench-raisers", {"fitbench_raisers": RAISERS},
                          {"fitbench.methods": {"raisers": "fitbench_raisers"}})


@pytest.fixture
def raisers():
    """The plugin's methods registered in this process for one test."""
    with plugin_here(RAISERS, "fitbench_raisers_test") as namespace:
        yield namespace


def _exit_zero(points):
    raise SystemExit(0)


def _exit_none(points):
    import sys
    sys.exit()


@pytest.fixture
def exiting_methods():
    """Methods that exit, registered from this module (not methods.*) for one test only."""
    with registered({"circle.test_exit_zero": _exit_zero, "circle.test_exit_none": _exit_none},
                    kind="closed form", summary="exits (test)", reference="a test"):
        yield


@pytest.fixture
def circle_file(tmp_path):
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    path = tmp_path / "circle.csv"
    np.savetxt(path, np.c_[10 + 5 * np.cos(t), -3 + 5 * np.sin(t)], delimiter=",", header="x,y", comments="")
    return path


@pytest.mark.parametrize("method, said", [
    ("circle.raise_weird", "circle.raise_weird failed: it raised Weird('weird')"),
    ("circle.raise_bad_str", "circle.raise_bad_str failed: BadStr (its message cannot be printed: RuntimeError: "
                             "no str for you)"),
    ("circle.raise_weird_bad_str", "circle.raise_weird_bad_str failed: it raised WeirdBadStr(<Unrepresentable "
                                   "object>)"),
    ("circle.raise_bad_refusal", "circle.raise_bad_refusal failed: BadRefusal (its message cannot be printed: "
                                 "RuntimeError: no refusal text)"),
    ("circle.test_exit_zero", "circle.test_exit_zero failed: it raised SystemExit(0)"),
    ("circle.test_exit_none", "circle.test_exit_none failed: it raised SystemExit()")])
@pytest.mark.parametrize("json", [False, True])
def test_fit_names_the_exception_the_method_raised_in_one_line(raisers, exiting_methods, circle_file, capsys, method,
                                                               said, json):
    code = main(["fit", method, str(circle_file), *(["--json"] if json else [])])
    out, err = capsys.readouterr()
    assert code == EXIT_METHOD_FAILED and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"fitbench: error: {said} (an error inside the method"), err
    assert "Traceback" not in err


def test_exception_text_never_raises_and_blames_the_raiser(raisers):
    assert methods.exception_text(raisers["BadStr"]()) == \
        "BadStr (its message cannot be printed: RuntimeError: no str for you)"
    assert methods.exception_text(raisers["Weird"]("weird")) == "Weird: weird"
    assert methods.exception_text(ValueError()) == "ValueError"
    assert methods.exception_call(raisers["WeirdBadStr"](1, "a")) == "WeirdBadStr(1, 'a')"


def _task(method):
    spec = {"label": "ring", "source": "circle", "params": {"radius": 5.0, "noise": 0.01, "n": 30}}
    return {"study": "raisers", "kind": "grid", "dataset": spec, "repetition": 0, "stream": [0, 0, 0], "seed": 3,
            "params": {}, "method": method, "timing": None, "index": 0}


@pytest.mark.parametrize("method, message", [
    ("circle.raise_bad_str", "BadStr (its message cannot be printed: RuntimeError: no str for you)"),
    ("circle.raise_bad_refusal", "BadRefusal (its message cannot be printed: RuntimeError: no refusal text)")])
def test_a_row_names_the_exception_whose_str_raises(raisers, method, message):
    from experiments import rows
    row = rows.run_task(_task(method))
    assert row["status"] == "error"
    assert row["message"] == message, row


@pytest.mark.slow
def test_a_study_s_rows_name_the_exceptions_the_methods_raised(site, tmp_path):
    ids = ["circle.kasa", "circle.raise_weird", "circle.raise_bad_str", "circle.raise_weird_bad_str",
           "circle.raise_bad_refusal"]
    study = circle_study(tmp_path, "raisers", "Methods raising odd exceptions", ids, repetitions=1)
    out = tmp_path / "out"
    proc = run_python("-m", "experiments.run", study, "--out", out, "--jobs", "1", "--no-report", path_first=[site])
    assert proc.returncode == 0, proc.stderr
    df = pd.read_csv(out / "raisers" / "results.csv").set_index("method")
    assert df.loc["circle.kasa", "status"] == "ok"
    assert df.loc["circle.raise_weird", ["status", "message"]].tolist() == ["error", "Weird: weird"]
    assert df.loc["circle.raise_bad_str", ["status", "message"]].tolist() == [
        "error", "BadStr (its message cannot be printed: RuntimeError: no str for you)"]
    assert df.loc["circle.raise_weird_bad_str", ["status", "message"]].tolist() == [
        "error", "WeirdBadStr (its message cannot be printed: RuntimeError: no str either)"]
    assert df.loc["circle.raise_bad_refusal", ["status", "message"]].tolist() == [
        "error", "BadRefusal (its message cannot be printed: RuntimeError: no refusal text)"]
