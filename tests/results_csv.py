"""A study's results.csv without its timing columns (``time_*``): what two runs of the same rows must agree on."""
from __future__ import annotations

from pathlib import Path

import pandas as pd


def non_timing(path: Path) -> pd.DataFrame:
    """``path`` (a results.csv) read, its ``time_*`` columns left out."""
    df = pd.read_csv(path)
    return df[[c for c in df.columns if not c.startswith("time_")]]
