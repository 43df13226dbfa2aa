import sys, time, numpy as np
sys.path.insert(0, sys.argv[1])
import methods
from datasets.synthetic import circle_points
for n in (3358, 10**6):
    pts = circle_points((1200.0, 650.0), 299.0, n, noise=0.005, rng=np.random.default_rng(3358))
    for m in ('circle.minimum_zone','circle.max_inscribed'):
        if n > 10**5 and m == 'circle.max_inscribed': continue
        methods.fit(m, pts); ts=[]
        for _ in range(5 if n < 10**5 else 3):
            t=time.perf_counter(); r=methods.fit(m, pts); ts.append(time.perf_counter()-t)
        print(sys.argv[1], n, m, f"{np.median(ts)*1e3:.1f} ms", r.extra.get('certified'), flush=True)
