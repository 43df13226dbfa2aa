"""Light import (issue 20): ``import methods`` and the CLI's ``list`` / ``fit`` on a small file load only
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
