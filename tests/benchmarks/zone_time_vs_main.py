"""Time circle.minimum_zone (N = 3358, 10^6) and circle.max_inscribed (N = 3358) from a given worktree,
so that today's code (a checkout of the baseline) and this branch are measured by the same script on the same data:

    cd /tmp && python CHECKOUT/tests/benchmarks/zone_time_vs_main.py BASELINE_CHECKOUT
    cd /tmp && python CHECKOUT/tests/benchmarks/zone_time_vs_main.py CHECKOUT

Prints min and median wall time of repeated calls (the min is the robust figure on a shared machine)."""
import sys
import time

import numpy as np

sys.path.insert(0, sys.argv[1])
import methods  # noqa: E402
from datasets.synthetic import circle_points  # noqa: E402

assert methods.__file__.startswith(sys.argv[1]), methods.__file__
for n, reps in ((3358, 25), (10**6, 5)):
    pts = circle_points((1200.0, 650.0), 299.0, n, noise=0.005, rng=np.random.default_rng(3358))
    for m in ("circle.minimum_zone", "circle.max_inscribed"):
        if n > 10**5 and m == "circle.max_inscribed":
            continue
        methods.fit(m, pts)
        ts = []
        for _ in range(reps):
            t = time.perf_counter()
            r = methods.fit(m, pts)
            ts.append(time.perf_counter() - t)
        print(f"{sys.argv[1]} n={n} {m}: min {min(ts) * 1e3:.1f} ms, median {np.median(ts) * 1e3:.1f} ms, "
              f"certified={r.extra.get('certified')}, width={r.form_error:.9g} mm", flush=True)
