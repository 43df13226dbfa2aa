"""Write the example input files of docs/examples/ (run from the repository root:
``python docs/examples/make_examples.py``; it rewrites every file but ``roundness.csv`` the same way each time).

* ``trace.csv``: a 2-D trace of a bore, R 50 mm about (120, 80) mm, 240 points with a 3-lobe form error of
  2 µm peak to peak and 0.3 µm noise, header ``x [mm],y [mm]`` (for ``fitbench fit``).
* ``cw.csv``, ``ccw.csv``: both runs of an ISO 230-4 circular test, R 150 mm about (0, 0) mm, 2000 mm/min,
  10 Hz, from ``datasets.circular_test.circular_test`` with 20 µrad squareness, 15 µm/m scale mismatch,
  3 µm X backlash, 0.2 ms servo mismatch and 0.3 µm noise (seed 11), header ``x [mm],y [mm]``.
* ``ballbar.csv``: the same test as one ballbar export, a direction column with the angle (°) and the radial
  deviation (µm) of each sample about the nominal circle.
* ``profile.csv``: a polar roundness profile of a shaft, 720 angles (°) with the radial deviation (µm):
  amplitudes of 0.6 µm at 3 UPR, 0.25 µm at 2 and 0.1 µm at 15 UPR, and 0.05 µm noise (seed 5).
* ``positioning.csv``: an ISO 230-2 test of a 1000 mm axis as a laser interferometer's wide export (targets in
  mm, one deviation column per run and direction in µm): ``datasets.positioning.axis_test`` with seed 7 and a
  -3 µm reversal.
* ``positioning_unlabelled.csv``: the same test with its run columns named ``Run 1 (µm)`` ... ``Run 10 (µm)``
  (odd runs approached in +, even runs in -, nothing in the file says so).
* ``positioning_periodic.csv``: an ISO 230-2 long table (target, direction, run and deviation, in mm) of a 1000 mm
  ball-screw axis, 21 irregular targets, 5 runs per direction: 10 µm/m linear, -12 µm/m² and a 1.5 µm periodic
  error of period 130 mm, ±1.5 µm reversal, 0.3 µm noise (seed 21), which a cubic cannot describe.
* ``roundness.csv`` (not written here): a turned profile as x, y in mm, R 12.5 mm, 3600 points, lobes of
  1.5 µm at 3 UPR, 0.6 µm at 2, 0.3 µm at 17, 0.2 µm at 180 and 0.08 µm noise.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from datasets.circular_test import MachineErrors, TestConditions, circular_test
from datasets.positioning import axis_test

HERE = Path(__file__).resolve().parent


def _write(path: Path, header: str, rows: list[str]) -> None:
    path.write_text("\n".join([header, *rows]) + "\n", encoding="utf-8")


def trace() -> tuple[str, list[str]]:
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 2 * np.pi, 240, endpoint=False)
    r = 50.0 + 0.001 * np.cos(3 * t + 0.4) + rng.normal(0.0, 0.0003, t.size)
    return "x [mm],y [mm]", [f"{x:.6f},{y:.6f}" for x, y in zip(120.0 + r * np.cos(t), 80.0 + r * np.sin(t))]


def ballbar_test():
    cond = TestConditions(nominal_radius=150.0, nominal_center=(0.0, 0.0), feed_mm_min=2000.0, sampling_hz=10.0,
                          start_angle_deg=0.0, machine="example")
    err = MachineErrors(squareness=20e-6, scale_x=7.5e-6, scale_y=-7.5e-6, backlash_x=0.003, lag_x=0.0002,
                        noise=0.0003)
    return circular_test(cond, err, seed=11)


def profile() -> tuple[str, list[str]]:
    rng = np.random.default_rng(5)
    deg = np.arange(720) * 0.5
    t = np.radians(deg)
    dev = (0.6 * np.cos(3 * t + 1.0) + 0.25 * np.cos(2 * t - 0.5) + 0.1 * np.cos(15 * t + 2.0)
           + rng.normal(0.0, 0.05, t.size))
    return "Angle [deg],Radial deviation [um]", [f"{a:.1f},{d:.4f}" for a, d in zip(deg, dev)]


def positioning() -> tuple[str, list[str]]:
    data, _ = axis_test(reversal=-0.003, rng=np.random.default_rng(7))
    runs = data.up.shape[1]
    names = [f"Run {j + 1} {s} (µm)" for j in range(runs) for s in "+-"]
    rows = []
    for i, p in enumerate(data.targets):
        values = [v for j in range(runs) for v in (data.up[i, j], data.down[i, j])]
        rows.append(";".join([f"{p:.3f}", *(f"{1000 * v:.3f}" for v in values)]))
    return ";".join(["Target (mm)", *names]), rows


def positioning_unlabelled() -> tuple[str, list[str]]:
    header, rows = positioning()
    runs = header.count("Run")
    return ";".join(["Target (mm)", *(f"Run {k} (µm)" for k in range(1, runs + 1))]), rows


def positioning_periodic() -> tuple[str, list[str]]:
    rng = np.random.default_rng(21)
    targets = np.sort(np.r_[0, 1000, rng.uniform(20, 980, 19)]).round(1)

    def err(p):
        return 1e-3 * (10 * (p / 1000) - 12 * (p / 1000) ** 2 + 1.5 * np.sin(2 * np.pi * p / 130))
    rows = []
    for run in range(1, 6):
        for d, off in (("+", 0.0015), ("-", -0.0015)):
            for t in (targets if d == "+" else targets[::-1]):
                rows.append(f"{t},{d},{run},{err(t) + off + rng.normal(0, 0.0003):.6f}")
    return "Target (mm),Direction,Run,Deviation (mm)", rows


def files() -> dict[str, tuple[str, list[str]]]:
    """Every written file: name -> (header line, data lines)."""
    cw, ccw, _ = ballbar_test()
    out = {"trace.csv": trace()}
    for name, run in (("cw.csv", cw), ("ccw.csv", ccw)):
        out[name] = ("x [mm],y [mm]", [f"{x:.6f},{y:.6f}" for x, y in run])
    rows = []
    for label, run in (("CW", cw), ("CCW", ccw)):
        angle = np.degrees(np.arctan2(run[:, 1], run[:, 0])) % 360.0
        dev = 1000.0 * (np.hypot(run[:, 0], run[:, 1]) - 150.0)
        rows += [f"{label},{a:.3f},{d:.3f}" for a, d in zip(angle, dev)]
    out["ballbar.csv"] = ("Direction,Angle [deg],Radial deviation [um]", rows)
    out["profile.csv"] = profile()
    out["positioning.csv"] = positioning()
    out["positioning_unlabelled.csv"] = positioning_unlabelled()
    out["positioning_periodic.csv"] = positioning_periodic()
    return out


def main(target: Path = HERE) -> None:
    for name, (header, rows) in files().items():
        _write(target / name, header, rows)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE)
