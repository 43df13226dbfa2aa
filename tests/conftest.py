"""Shared fixtures. Tests import fitbench's own ``datasets``/``methods`` from the repository."""
import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


def nist_dir() -> Path | None:
    """Directory of the NIST Circle2d reference sets, from FITBENCH_NIST_DIR (None if unset/missing)."""
    value = os.environ.get("FITBENCH_NIST_DIR")
    if not value:
        return None
    path = Path(value)
    return path if path.is_dir() else None
