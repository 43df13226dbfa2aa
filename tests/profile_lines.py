"""Measured profiles as instruments export them (the lines of an x, y profile, for the tests that build files around
them; a shaft's profile file) and a circular test's two runs in one file."""
from __future__ import annotations

import numpy as np

from datasets.circular_test import MachineErrors, TestConditions, circular_test


def circle_lines(radius, n=360, phase=0.0):
    """``n`` points of a circle of ``radius`` mm with 1.5 µm of 3-lobing, from ``phase`` degrees, as 'x,y' lines."""
    t = np.radians(np.arange(n) * 360.0 / n + phase)
    r = radius + 0.0015 * np.cos(3 * t)
    return [f"{x:.7f},{y:.7f}" for x, y in zip(r * np.cos(t), r * np.sin(t))]


def profile_file(path, n=3600, seed=3):
    """A Ø40 mm shaft with three lobes and noise, x, y in mm."""
    t = 2 * np.pi * np.arange(n) / n
    r = 20.0 + 1.5e-3 * np.cos(3 * t + 0.4) + 2e-5 * np.random.default_rng(seed).standard_normal(n)
    np.savetxt(path, np.c_[r * np.cos(t), r * np.sin(t)], delimiter=",", header="x,y", comments="", fmt="%.9f")
    return path


def circular_runs_file(path, seed=0):
    """A circular test's CW and CCW runs (R 100 mm, 20 µrad squareness, 0.2 µm noise) in one file, labelled by a
    'run' column."""
    cond = TestConditions(nominal_radius=100.0, nominal_center=(0.0, 0.0), sampling_hz=50.0)
    cw, ccw, _ = circular_test(cond, MachineErrors(squareness=20e-6, noise=0.0002), seed=seed)
    path.write_text("run,x,y\n" + "".join(f"{lab},{x:.7f},{y:.7f}\n" for lab, pts in (("cw", cw), ("ccw", ccw))
                                          for x, y in pts))
    return path
