"""A fresh non-editable install: build the wheel from a copy of the sources, install it with --no-deps into
a temporary folder, and run the ``fitbench`` console script from another directory: ``--version`` works,
``fitbench run published --quick --out X`` writes into X, and nothing is written into the installed package. (The
quick grid: the same published data sets, read from the installed package, as the full study, whose timing rounds
and 1000-sample rounding Monte Carlo, ~7 s of CPU more, check nothing about the installation.)"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO


def _tree(root: Path) -> set:
    return {str(p.relative_to(root)) for p in root.rglob("*") if "__pycache__" not in p.parts}


@pytest.mark.system  # builds a wheel and installs it: its own CI step
def test_wheel_install_runs_from_another_directory(tmp_path):
    if shutil.which("git") is None:
        pytest.skip("git is needed to list the sources")  # pragma: no cover
    files = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard"], cwd=REPO,
                           capture_output=True, text=True, check=True).stdout.split()
    src = tmp_path / "src"
    for f in files:
        if f.startswith(("results/", "paper/")) or not (REPO / f).is_file():
            continue
        (src / f).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(REPO / f, src / f)
    wheels = tmp_path / "wheels"
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "--no-build-isolation",
                            "-w", str(wheels), "-q"], capture_output=True, text=True)
    assert build.returncode == 0, build.stderr[-2000:]
    wheel = next(wheels.glob("fitbench-*.whl"))
    target = tmp_path / "site"
    inst = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-compile", "--target", str(target),
                           str(wheel), "-q"], capture_output=True, text=True)
    assert inst.returncode == 0, inst.stderr[-2000:]
    script = target / "bin" / "fitbench"
    assert script.is_file()
    before = _tree(target)
    elsewhere = tmp_path / "work"
    elsewhere.mkdir()
    env = {**os.environ, "PYTHONPATH": str(target), "PYTHONDONTWRITEBYTECODE": "1"}
    version = subprocess.run([str(script), "--version"], capture_output=True, text=True, cwd=elsewhere, env=env)
    from fitbench import __version__
    assert version.returncode == 0 and version.stdout.strip() == f"fitbench {__version__}", version
    # the installed modules are the wheel's, not the repository's
    where = subprocess.run([sys.executable, "-c", "import methods, fitbench; print(methods.__file__, fitbench.__file__)"],
                           capture_output=True, text=True, cwd=elsewhere, env=env).stdout
    assert str(target) in where and str(REPO) not in where
    # the first listing caches the manifest of the built-in methods in the user's cache folder, never in the install
    env["FITBENCH_CACHE_DIR"] = str(tmp_path / "cache")
    listing = subprocess.run([str(script), "list"], capture_output=True, text=True, cwd=elsewhere, env=env)
    assert listing.returncode == 0 and "circle.kasa" in listing.stdout, listing
    current = subprocess.run([sys.executable, "-c", "from methods import _manifest; print(_manifest.read() is not None)"],
                             capture_output=True, text=True, cwd=elsewhere, env=env)
    assert current.stdout.strip() == "True", current
    run = subprocess.run([str(script), "run", "published", "--quick", "--out", "X", "--jobs", "1"], capture_output=True,
                         text=True, cwd=elsewhere, env=env)
    assert run.returncode == 0, run.stderr[-2000:]
    assert (elsewhere / "X" / "published" / "results.csv").is_file()
    assert _tree(target) == before, sorted(_tree(target) - before)[:10]
