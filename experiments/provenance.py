"""Provenance of a run: commit, dirty flag, package versions, BLAS, machine, date, config hash."""
from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path

from methods.files import write_atomic  # noqa: F401  (the one atomic writer; experiments import it from here)

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("numpy", "scipy", "cvxpy", "clarabel", "nlopt", "pandas", "matplotlib")


def _git(*args) -> str | None:
    try:
        out = subprocess.run(["git", *args], cwd=REPO, capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def config_hash(config: dict) -> str:
    return hashlib.sha256(json.dumps(config, sort_keys=True, default=str).encode()).hexdigest()[:16]


def collect(config: dict) -> dict:
    """The run's provenance for ``meta.json``; ``libraries`` are the versions of the libraries the code of the study's
    rows imports, as their cache keys hold them (``experiments.codekeys.libraries``)."""
    from experiments.codekeys import blas, libraries
    versions = {"python": sys.version.split()[0]}
    for pkg in PACKAGES:
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = None
    status = _git("status", "--porcelain", "--", ".", ":!results", ":!paper")  # outputs do not make the code dirty
    return {
        "git_commit": _git("rev-parse", "HEAD"),
        "git_dirty": bool(status) if status is not None else None,
        "versions": versions,
        "libraries": libraries(),
        "blas": blas(),
        "cpu": _cpu(),
        "cores": os.cpu_count(),
        "platform": platform.platform(),
        "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "config": config,
        "config_hash": config_hash(config),
    }
