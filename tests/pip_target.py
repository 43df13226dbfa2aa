"""A plugin distribution built from a source folder and installed offline by pip (``pip install --target``), for the
tests that need what only pip makes of it: an editable install's path hook, a package, declared dependencies
(``conftest.install_plugin`` writes a flat module's install in milliseconds; it serves everywhere else)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

#: the ``[build-system]`` table of a setuptools distribution (PEP 517/518)
BUILD_SYSTEM = '[build-system]\nrequires = ["setuptools>=61"]\nbuild-backend = "setuptools.build_meta"\n'


def write_pyproject(src: Path, name: str, rest: str) -> None:
    """``src/pyproject.toml`` of the setuptools distribution ``name`` version 0.1; ``rest``: the lines after its
    ``[project]`` name and version (entry points, ``[tool.setuptools]``)."""
    (src / "pyproject.toml").write_text(BUILD_SYSTEM + f'[project]\nname = "{name}"\nversion = "0.1"\n' + rest)


def pip_install(src: Path, site: Path, *, editable: bool = False) -> Path:
    """``pip install --target SITE SRC`` (``-e SRC`` if ``editable``) without dependencies, build isolation or an
    index; ``site`` (put it first on the path)."""
    out = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-build-isolation", "--no-index",
                          "--quiet", "--target", str(site), *(["-e"] if editable else []), str(src)],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return site
