import timeit, numpy as np, methods
from datasets.synthetic import circle_points
from methods._validation import validate_points
from methods.circle import _ckernels as ck
from methods.circle._frame import frame_and_moments, kasa_moments
from methods._result import circle_result
P=circle_points((1200.0, 650.0), 299.0, 3358, noise=0.005, rng=np.random.default_rng(1))
def t(label, f, n=3000):
    v=min(timeit.repeat(f, number=n, repeat=5))/n*1e6; print(f"{label:40s} {v:8.2f} us")
t("fit kasa", lambda: methods.fit("circle.kasa", P))
t("fit pratt", lambda: methods.fit("circle.pratt", P))
t("fit hyper", lambda: methods.fit("circle.hyper", P))
t("fit gn", lambda: methods.fit("circle.gauss_newton", P), 500)
import circle_fit
t("hyperLSQ", lambda: circle_fit.hyperLSQ(P))
t("validate", lambda: validate_points(P))
t("ck.frame_stats", lambda: ck.frame_stats(P))
t("ck.moments", lambda: ck.moments(P, 1200., 650., 211.))
o=np.empty(3358)
t("ck.radial", lambda: ck.radial(P, 1200., 650., 299., o))
t("ck.geometric", lambda: ck.geometric(P, 1200., 650., 211., (0.,0.,1.)))
t("ck.geometric prev", lambda: ck.geometric(P, 1200., 650., 211., (0.,0.,1.), (0.,0.,1.)))
def fm():
    validate_points(P); return frame_and_moments(P)
t("validate+frame_and_moments", fm)
m = fm()[1]
t("kasa_moments", lambda: kasa_moments(m))
t("circle_result", lambda: circle_result(P, (1200.,650.), 299., converged=True, message="x"))
t("np.linalg.eigh 4x4", lambda: np.linalg.eigh(m))
t("np.linalg.solve 3x3", lambda: np.linalg.solve(m[:3,:3], m[:3,3]))
