"""A method that raises SystemExit (sys.exit() in a plugin) ends `fitbench fit` with one line naming the method and
a non-zero status, never with nothing printed and exit 0 (a script reading --json got an empty output and success)."""
import numpy as np
import pytest

from fitbench.cli.commands import EXIT_METHOD_FAILED, main
from methods import register


def _exit_zero(points):
    raise SystemExit(0)


def _exit_none(points):
    import sys
    sys.exit()


@pytest.fixture
def exiting_methods():
    """The methods of a plugin, registered from this module (not methods.*) for one test only."""
    from methods import _registry
    ids = {"circle.test_exit_zero": _exit_zero, "circle.test_exit_none": _exit_none}
    for mid, func in ids.items():
        register(mid, kind="closed form", summary="exits (test)", reference="a test")(func)
    yield
    for mid in ids:
        _registry._REGISTRY.pop(mid, None)


@pytest.fixture
def circle_file(tmp_path):
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    path = tmp_path / "circle.csv"
    np.savetxt(path, np.c_[10 + 5 * np.cos(t), -3 + 5 * np.sin(t)], delimiter=",", header="x,y", comments="")
    return path


@pytest.mark.parametrize("method, raised", [("circle.test_exit_zero", "SystemExit(0)"),
                                            ("circle.test_exit_none", "SystemExit()")])
@pytest.mark.parametrize("json", [False, True])
def test_a_method_exiting_is_an_error_naming_it(circle_file, capsys, exiting_methods, method, raised, json):
    code = main(["fit", method, str(circle_file), *(["--json"] if json else [])])
    out, err = capsys.readouterr()
    assert code == EXIT_METHOD_FAILED and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and f"{method} failed: it raised {raised}" in lines[0], err
    assert "Traceback" not in err
