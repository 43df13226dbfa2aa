"""Timing of fits: rounds of repeated calls until the timer's resolution does not matter."""
from __future__ import annotations

import time

import numpy as np


def time_call(func, *, min_time_s: float = 0.02, rounds: int = 5) -> dict:
    """Median, IQR and count of per-call times (seconds) over ``rounds`` rounds; each round repeats
    ``func`` until it has run for at least ``min_time_s`` (microsecond fits are averaged)."""
    t0 = time.perf_counter()
    func()
    single = max(time.perf_counter() - t0, 1e-7)
    inner = max(1, int(np.ceil(min_time_s / single)))
    per_call = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(inner):
            func()
        per_call.append((time.perf_counter() - t0) / inner)
    q1, med, q3 = np.percentile(per_call, [25, 50, 75])
    return {"time_median_s": float(med), "time_iqr_s": float(q3 - q1), "time_rounds": rounds,
            "time_calls_per_round": inner}
