"""The study statuses that differ between the compiled and the NumPy path (convergence: Gauss-Newton from
starts 2 radii away; roundness: MCCI certification of filtered profiles) are decided by the last bit of the input
on EITHER path: each case is refitted with the start (convergence) or the data (roundness) moved by one ulp.

Run from the repository root:  FITBENCH_KERNELS=numpy python tests/benchmarks/circle_status_last_bit.py
(and without FITBENCH_KERNELS for the compiled path). Prints the status (ok/no, iterations) of each refit.
"""
import os
import sys

sys.path.insert(0, os.getcwd())  # this checkout's methods, not an installed copy
import numpy as np  # noqa: E402

import methods  # noqa: E402
from experiments import config as C  # noqa: E402
from experiments.rows import load_data  # noqa: E402
from experiments.studies import convergence as conv  # noqa: E402
from experiments.studies import roundness as rs  # noqa: E402

cfg = C.load("convergence", quick=True)
eps = np.finfo(float).eps
for task in conv.ConvergenceStudy().tasks(cfg):
    if task["method"] not in ("circle.gauss_newton", "circle.levenberg_marquardt") or task["x_start_distance"] < 1:
        continue
    points, truth = load_data(task["dataset"], task["seed"], task["stream"])
    R = truth["radius"]
    phi = 2 * np.pi * task["x_start_direction"] / task["x_directions"]
    start = np.array([truth["center"][0] + task["x_start_distance"] * R * np.cos(phi),
                      truth["center"][1] + task["x_start_distance"] * R * np.sin(phi), R])
    out = []
    for k, s in enumerate([start, start * (1 + eps), start * (1 - eps), start + np.array([0, 0, eps])]):
        r = methods.fit(task["method"], points, start=list(s))
        out.append(("ok" if r.converged else "no") + f"/{r.iterations}")
    print(task["method"], task["dataset"].get("params", {}).get("arc_deg", task["dataset"]), task["x_start_direction"], out)


print("-- roundness: MCCI certification and RONt (um), data moved by one ulp (random signs)")
cfg = C.load("roundness", quick=True)
eps = np.finfo(float).eps
for task in rs.RoundnessStudy().tasks(cfg):
    if task["dataset"]["label"] not in ("turned shaft, D 25 mm, 3600 points", "centreless ground, D 10 mm, 7200 points"):
        continue
    if task["params"]["cutoff_upr"] not in (50.0, 3.0):
        continue
    pts = rs.load(task["dataset"], task["seed"], task["stream"])
    out = []
    rng = np.random.default_rng(0)
    for k in range(4):
        q = pts if k == 0 else pts * (1 + eps * rng.choice([-1.0, 1.0], size=pts.shape))
        res = methods.fit(task["method"], q, **task["params"])
        m = res.references["mcci"]
        out.append(f"{'cert' if m['converged'] else 'UNcert'} {m['RONt']*1e3:.6f}")
    print(task["dataset"]["label"][:18], task["params"]["cutoff_upr"], task["repetition"], out)
