"""Positioning deviations as an export writes them and ISO 230-2's bidirectional accuracy A computed here by its
definition (k = 2), for the positioning-table tests to check fitbench's figures against."""
from __future__ import annotations

import numpy as np

from datasets.positioning import axis_test, to_frame

TARGETS = np.array([0.0, 97.3, 201.6, 298.1, 402.7])
#: the six targets of the long tables of 5 runs (mm)
LONG_TARGETS = np.array([0.0, 97.3, 201.6, 298.1, 402.7, 499.2])


def runs(seed):
    """{'+': (targets, runs), '-': ...} in µm to 3 decimals, as written: 3 runs at :data:`TARGETS`."""
    rng = np.random.default_rng(seed)
    return {d: np.round((8 * TARGETS / 1000 + b)[:, None] + rng.normal(0, 0.6, (len(TARGETS), 3)), 3)
            for d, b in (("+", -1.8), ("-", 1.8))}


def iso_a_um(dev, directions="+-") -> float:
    """ISO 230-2 bidirectional accuracy A (k = 2) by its definition: max(mean + 2 s) - min(mean - 2 s) over the
    ``directions`` given and every target, s with n - 1 (``dev``: {direction: (targets, runs)} in µm)."""
    hi = max(float(np.max(dev[d].mean(axis=1) + 2 * dev[d].std(axis=1, ddof=1))) for d in directions)
    lo = min(float(np.min(dev[d].mean(axis=1) - 2 * dev[d].std(axis=1, ddof=1))) for d in directions)
    return hi - lo


def axis_csv(folder, seed=7):
    """``folder/axis.csv``: a simulated axis test (``datasets.positioning.axis_test``, seed ``seed``) as its deviation
    table (``to_frame(actual=False)``); (its path, the test's data)."""
    data, _ = axis_test(rng=np.random.default_rng(seed))
    path = folder / "axis.csv"
    to_frame(data, actual=False).to_csv(path, index=False)
    return path, data


def capture_order(path, dev, header, cells):
    """A long table of 5 runs at :data:`LONG_TARGETS`, each run up then down, as laser software records it
    (``dev``: {direction: (targets, runs)}; ``cells(target, direction, run, deviation)``: a line's text)."""
    lines = [header]
    for r in range(5):
        lines += [cells(LONG_TARGETS[i], "+", r + 1, dev["+"][i, r]) for i in range(len(LONG_TARGETS))]
        lines += [cells(LONG_TARGETS[i], "-", r + 1, dev["-"][i, r]) for i in reversed(range(len(LONG_TARGETS)))]
    path.write_text("\n".join(lines) + "\n")
    return path
