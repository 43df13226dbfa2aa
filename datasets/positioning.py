"""Synthetic linear-axis positioning tests (ISO 230-2) with known truth.

The true deviation at position P approaching upwards is pitch(P) + periodic(P) + B/2, downwards
pitch(P) + periodic(P) - B/2; every approach adds repeatability noise; the measuring instrument adds
one common error delta per test (uniform within +-MPE, the paper's model of the instrument, eq. 4).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from methods.positioning.data import PositioningData

if TYPE_CHECKING:  # the annotation's name only: pandas is imported where a frame is made
    import pandas as pd


def pitch_curve(P, coefficients):
    """Smooth pitch-error curve: a polynomial in the relative position (P - start) / length."""
    return np.polynomial.polynomial.polyval(P, coefficients)


def axis_test(*, travel=(0.0, 1000.0), targets=11, runs=5, pitch=(0.0, 0.004, -0.010, 0.006), reversal=0.003,
              repeatability=0.001, periodic_amplitude=0.0, periodic_period=100.0, mpe=0.0, instrument_sd=0.0,
              rng: np.random.Generator | None = None, irregular=0.0):
    """A test: returns (PositioningData, truth) with truth['up'](P), truth['down'](P) the true deviation
    functions (mm) and truth['delta'] the instrument's error in this test. ``pitch`` are coefficients in
    the relative position u = (P - start) / length (increasing powers). The instrument's error is
    uniform within +-``mpe`` (the paper's model) or Gaussian with s.d. ``instrument_sd``."""
    rng = rng or np.random.default_rng(0)
    start, end = travel
    length = end - start
    P = np.linspace(start, end, targets)
    if irregular:
        P[1:-1] += rng.uniform(-irregular, irregular, targets - 2) * length / (targets - 1)

    def base(x):
        u = (np.asarray(x, float) - start) / length
        return pitch_curve(u, pitch) + periodic_amplitude * np.sin(2 * np.pi * (np.asarray(x, float) - start) / periodic_period)

    def up(x):
        return base(x) + reversal / 2

    def down(x):
        return base(x) - reversal / 2

    delta = (rng.uniform(-mpe, mpe) if mpe else 0.0) + (rng.normal(0.0, instrument_sd) if instrument_sd else 0.0)
    dev_up = up(P)[:, None] + delta + rng.normal(0.0, repeatability, (targets, runs))
    dev_down = down(P)[:, None] + delta + rng.normal(0.0, repeatability, (targets, runs))
    data = PositioningData(targets=P, up=dev_up, down=dev_down, unit="mm")
    return data, {"up": up, "down": down, "delta": delta, "mpe": mpe, "instrument_sd": instrument_sd}


def to_frame(data: PositioningData, *, actual=True) -> pd.DataFrame:
    """The long table of a test (columns target, direction, run, actual or deviation)."""
    import pandas as pd  # here: a study's workers import this module (the simulator) and need no pandas
    rows = []
    for d, arr in (("+", data.up), ("-", data.down)):
        for i, t in enumerate(data.targets):
            for j in range(arr.shape[1]):
                rows.append({"target": t, "direction": d, "run": j + 1,
                             ("actual" if actual else "deviation"): (t + arr[i, j]) if actual else arr[i, j]})
    return pd.DataFrame(rows)
