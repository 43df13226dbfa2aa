"""Do the iterative circle methods' statuses flip when every coordinate moves by one ulp?
The noise study's grid (arcs 360/180/90/45 deg, sigma 0.001/0.01/0.05, N 20/100) x REPS repetitions.
Run from the repository root:  python tests/benchmarks/circle_status_flips.py 4
"""
import sys, numpy as np, methods, collections
from datasets.synthetic import circle_points
# noise-study grid: arcs x noise x n, perturb by 1 ulp, compare status
rng = np.random.default_rng(1996)
flips = collections.Counter(); total = collections.Counter(); nconv = collections.Counter(); iters = collections.defaultdict(list)
reps = int(sys.argv[1]) if len(sys.argv) > 1 else 10
for arc in [360.0, 180.0, 90.0, 45.0]:
    for noise in [0.001, 0.01, 0.05]:
        for n in [20, 100]:
            for rep in range(reps):
                pts = circle_points((0, 0), 1.0, n, arc=(0, np.deg2rad(arc)), noise=noise, rng=rng)
                pert = np.nextafter(pts, np.where(rng.random(pts.shape) < 0.5, np.inf, -np.inf))
                for m, kw in [("circle.nelder_mead", {}), ("circle.nelder_mead", {"backend": "nlopt"}), ("circle.powell_hybrid", {}),
                              ("circle.gauss_newton", {}), ("circle.levenberg_marquardt", {})]:
                    key = m + str(kw)
                    a = methods.fit(m, pts, **kw); b = methods.fit(m, pert, **kw)
                    total[key] += 1; nconv[key] += a.converged; iters[key].append(a.nfev or 0)
                    if a.converged != b.converged:
                        flips[key] += 1
                        print("FLIP", key, arc, noise, n, rep, a.nfev, a.message, "|", b.nfev, b.message)
for k in total:
    print(f"{k}: {total[k]} sets, converged {nconv[k]}, status flips under 1-ulp noise {flips[k]}, median nfev {np.median(iters[k]):.0f}, max {max(iters[k])}")
