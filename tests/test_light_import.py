"""Light import: ``import methods`` and the CLI's ``list`` / ``fit`` on a small file load only
what registration needs; solvers, pandas, shapely, nlopt, clarabel, cvxpy and matplotlib load when first
used. A property of the import graph (checked in sys.modules of a fresh interpreter), not a timing."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("cvxpy", "pandas", "matplotlib", "scipy.optimize", "scipy.linalg", "scipy.sparse", "shapely", "nlopt",
         "clarabel")

PROBE = """
import json, sys, runpy
sys.argv = {argv!r}
try:
    {body}
except SystemExit:
    pass
heavy = {heavy!r}
print(json.dumps(sorted(m for m in heavy if m in sys.modules)))
"""


def loaded_after(body: str, argv=("x",)) -> list[str]:
    code = PROBE.format(argv=list(argv), body=body, heavy=HEAVY)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_import_methods_loads_no_solver_and_no_pandas():
    assert loaded_after("import methods") == []


def test_cli_list_loads_no_solver_and_no_pandas():
    assert loaded_after("runpy.run_module('methods', run_name='__main__')", argv=("methods", "list")) == []


def test_cli_fit_of_a_small_file_loads_only_what_the_method_needs(tmp_path):
    t = np.linspace(0, 2 * np.pi, 50, endpoint=False)
    path = tmp_path / "small.csv"
    np.savetxt(path, np.column_stack([100 + 5 * np.cos(t), 3 + 5 * np.sin(t)]), delimiter=",", header="x,y",
               comments="")
    assert loaded_after("runpy.run_module('methods', run_name='__main__')",
                        argv=("methods", "fit", "circle.kasa", str(path))) == []


@pytest.mark.parametrize("method, needs", [("circle.chebyshev_lp", "scipy.optimize"),
                                           ("circle.minimum_zone", "clarabel")])
def test_a_solver_loads_when_first_used(method, needs):
    """The lazy imports do load the solver when the method runs (and the fit works)."""
    body = ("import methods, numpy as np\n    t = np.linspace(0, 6, 20)\n"
            f"    r = methods.fit({method!r}, np.column_stack([np.cos(t), np.sin(t)]))\n"
            "    assert abs(r.radius - 1) < 1e-9, r")
    assert needs in loaded_after(body)


SMALL_FILES = {
    "comma_header.csv": "x,y\n1.5,2.25\n-3e-3,4\n5,6.125\n",
    "semicolon_decimal_comma.csv": "# a comment\nx;y\n1,5;2,25\n-0,003;4\n5;6,125\n",
    "whitespace_no_header.txt": "1.5  2.25\n\n-3e-3\t4\n5 6.125\n",
    "three_columns.csv": "t,x,y\n0,1.5,2.25\n1,-3e-3,4\n2,5,6.125\n",
    "percent_comments.txt": "% instrument export\nx y\n% run 1\n1.5 2.25\n-3e-3 4\n5 6.125\n",
}


@pytest.mark.parametrize("name", sorted(SMALL_FILES))
def test_small_file_reader_agrees_with_the_pandas_reader(tmp_path, monkeypatch, name):
    """The pandas-free reader of small files gives the same points as the pandas reader it bypasses."""
    from datasets import io as dio
    path = tmp_path / name
    path.write_text(SMALL_FILES[name], encoding="utf-8")

    class NoPandas:
        def __getattr__(self, attr):
            raise AssertionError("the small-file reader used pandas")
    with monkeypatch.context() as m:
        m.setattr(dio.columns, "pd", NoPandas())
        fast = dio.read_points(path)
    monkeypatch.setattr(dio.columns, "SMALL_FILE_BYTES", -1)  # force the pandas path
    slow = dio.read_points(path)
    np.testing.assert_array_equal(fast, slow)
    np.testing.assert_array_equal(fast, [[1.5, 2.25], [-3e-3, 4.0], [5.0, 6.125]])


@pytest.mark.parametrize("text", ["x,y\n1,2\n3,nan\n4,5\n", "x,y\n1,2\n3\n4,5\n", "x,y\n1,2\n3,abc\n4,5\n",
                                  "x,y\n1,2 # note\n3,4\n5,7\n"])
def test_small_file_reader_leaves_unusual_files_to_the_pandas_reader(tmp_path, monkeypatch, text):
    """Bad or unusual small files get the same outcome (points or the same one-line error) either way."""
    from datasets import io as dio
    path = tmp_path / "odd.csv"
    path.write_text(text, encoding="utf-8")

    def outcome():
        try:
            return dio.read_points(path).tolist()
        except dio.DataFileError as exc:
            return str(exc)
    fast = outcome()
    monkeypatch.setattr(dio.columns, "SMALL_FILE_BYTES", -1)
    assert fast == outcome()
