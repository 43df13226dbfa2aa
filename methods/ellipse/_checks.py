"""Checks behind the ellipse family's flags: ``converged=True`` is a promise that the returned point is a
first-order optimum of the method's own objective, and that the ellipse is not degenerate.

Every objective of the family is a sum of squares S(q) = sum r_i(q)^2 in the unit frame (data centred on
the centroid and scaled to unit RMS radius). :func:`stationarity_probe` starts a few Levenberg–Marquardt steps
at the returned point (a short local solver, as scipy's least_squares would take first)
and measures the decrease it achieves. The point counts as stationary when that decrease is at most
``rtol`` S plus the rounding noise of S (the probe cannot see below it); otherwise the method stopped
at a non-stationary point, whatever its own stopping rule said. A point that no step of the
Levenberg–Marquardt path can lower is a first-order optimum to the probe's resolution: J^T r = 0 makes
every step vanish, and a non-zero J^T r makes the strongly damped step (a short steepest-descent step)
lower S.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from methods._frame import dot

EPS = np.finfo(float).eps
#: Relative decrease of the objective below which a point counts as stationary (the promise is tested
#: at 1e-9 against scipy.optimize.least_squares started at the returned point).
STATIONARY_RTOL = 1e-10
#: Smallest semi-axis, relative to the data's RMS radius, of an ellipse that is not collapsed.
COLLAPSED_RTOL = 1e-6
#: Largest semi-axis, relative to the data's RMS radius, of an ellipse whose centre is not at infinity.
UNBOUNDED_RTOL = 1e6


@dataclass
class Stationarity:
    stationary: bool
    objective: float        # S at the returned point (unit frame)
    decrease: float         # the largest decrease the probe achieved (unit frame)
    noise: float            # rounding noise of S at the returned point (unit frame)
    steps: int              # Levenberg–Marquardt steps tried
    predicted: float = 0.0  # the decrease the Gauss–Newton model promises at the returned point (unit frame)

    def _rel(self, v: float) -> float:
        return v / self.objective if self.objective > 0 else (np.inf if v > 0 else 0.0)

    @property
    def relative(self) -> float:
        return self._rel(self.decrease)

    @property
    def tolerance(self) -> float:
        """The allowed decrease, relative to S: STATIONARY_RTOL plus the rounding bound of S."""
        return STATIONARY_RTOL + self._rel(self.noise)

    def as_dict(self) -> dict:
        return {"stationary": self.stationary, "objective_unit": self.objective, "decrease_found_unit": self.decrease,
                "relative_decrease": self.relative, "predicted_decrease_unit": self.predicted,
                "relative_predicted_decrease": self._rel(self.predicted), "rounding_noise_unit": self.noise,
                "relative_tolerance": self.tolerance, "probe_steps": self.steps,
                "probe": "Gauss-Newton model and Levenberg-Marquardt steps from the returned point (unit frame)"}

    def checked(self) -> str:
        """What was checked, with the numbers (the message of a stationary point)."""
        return (f"the Gauss-Newton model there promises a further decrease of {self._rel(self.predicted):.2e} of the "
                f"objective and a Levenberg-Marquardt probe achieves {self.relative:.2e}, both at most "
                f"{STATIONARY_RTOL:.0e} + {self._rel(self.noise):.2e} (the rounding bound of the objective there)")

    def reason(self) -> str:
        return (f"not a stationary point of the objective: the Gauss-Newton model there promises a decrease of "
                f"{self._rel(self.predicted):.2e} relative and a Levenberg-Marquardt probe achieves {self.relative:.2e} "
                f"(tolerance {STATIONARY_RTOL:.0e} + {self._rel(self.noise):.2e}, the rounding bound of the objective)")


def stationarity_probe(residuals, jacobian, q, *, noise, rtol: float = STATIONARY_RTOL, steps: int = 4,
                       triangular=None) -> Stationarity:
    """Up to ``steps`` Levenberg–Marquardt steps on S = |r(q)|^2 from ``q`` (each trying the Gauss–Newton
    step first, then more and more damping down to a short steepest-descent step, in column-scaled
    variables); ``noise(r, q)`` is the rounding noise of S at q. Stationary when the total decrease
    achieved is at most ``rtol`` S(q) + noise. Damping stops once the model's own decrease
    sum_i (2 m_i - m_i^2) g_i^2, m_i = s_i^2 / (s_i^2 + lambda), falls below that tolerance: no step of the
    trust-region path can then show a significant decrease. ``triangular`` (for N >> 5 points, in place of
    ``jacobian``): p -> the (k+1) x (k+1) R of a QR of [J r] at p (R^T R = [J r]^T [J r]); the singular values, V and
    g = U^T r then come from the SVD of its k x k block scaled by its column norms (J D^-1 = Q R1 D^-1, R1 D^-1 =
    U_R S V^T, so U^T r = U_R^T (Q^T r), Q^T r being R's last column above the diagonal): the same quantities as the
    SVD of J, both backward stable, from (k+1)^2 numbers instead of N x k."""
    q0 = np.asarray(q, dtype=np.float64)
    r = np.asarray(residuals(q0), dtype=np.float64)
    f0 = dot(r, r)
    floor = float(noise(r, q0))
    if not np.isfinite(f0):
        return Stationarity(False, f0, np.inf, floor, 0)
    threshold = rtol * f0 + floor
    qk, fk, rk, taken = q0, f0, r, 0
    predicted = np.inf
    for _ in range(steps):
        if triangular is not None:
            T = np.asarray(triangular(qk), dtype=np.float64)
            if not np.isfinite(T).all():
                break
            k = T.shape[1] - 1
            col = np.sqrt(np.einsum("ij,ij->j", T[:, :k], T[:, :k]))
            col[col == 0] = 1.0
            Ur, sv, Vt = np.linalg.svd(T[:k, :k] / col)
            g = Ur.T @ T[:k, k]
        else:
            J = np.asarray(jacobian(qk), dtype=np.float64)
            if not np.isfinite(J).all():
                break
            col = np.sqrt(np.einsum("ij,ij->j", J, J))
            col[col == 0] = 1.0
            U, sv, Vt = np.linalg.svd(J / col, full_matrices=False)
            g = U.T @ rk
        keep = sv > sv[0] * len(rk) * EPS
        if taken == 0:  # the Gauss-Newton model's decrease at q0: |projection of r on range(J)|^2 = g^T (J^T J)^+ g
            predicted = float(np.sum(np.where(keep, g * g, 0.0)))
        improved = False
        for lam in (0.0, *(sv[0] ** 2 * 10.0 ** np.arange(-12, 5))):
            m = np.where(keep, sv * sv / (sv * sv + lam), 0.0) if lam > 0 else keep.astype(float)
            model = float(np.sum((2 * m - m * m) * g * g))
            if f0 - fk + model <= threshold:  # no step of the path (more damping only shortens it) can show more
                break
            inv = np.divide(m, sv, out=np.zeros_like(sv), where=sv > 0)
            trial = qk - (Vt.T @ (inv * g)) / col
            rt = np.asarray(residuals(trial), dtype=np.float64)
            ft = dot(rt, rt)
            if np.isfinite(ft) and ft < fk:
                qk, fk, rk, improved = trial, ft, rt, True
                break
        taken += 1
        if not improved or f0 - fk > threshold:
            break
    decrease = f0 - fk
    return Stationarity(bool(decrease <= threshold and predicted <= threshold), f0, float(decrease), floor, taken,
                        predicted)


#: Points per block of :func:`sum_of_squares_noise` (its temporaries hold a block, not N values).
NOISE_BLOCK = 2048


def triangular_by_blocks(jacobian, residuals, n: int, block: int | None = None):
    """For :func:`stationarity_probe`'s ``triangular``: p -> the R of a QR of [J r] at p, from the rows of
    ``block`` points at a time (``jacobian(p, part)``, ``residuals(p, part)`` of the slice ``part``; LAPACK's
    Householder QR of [R; next block]): a block's memory instead of the N x k Jacobian and its copies.
    Default block: N / 16 points, at least 256."""
    block = max(256, -(-n // 16)) if block is None else int(block)

    def triangular(p):
        R = None
        for lo in range(0, n, block):
            part = slice(lo, min(lo + block, n))
            J = np.asarray(jacobian(p, part), dtype=np.float64)
            A = np.empty((J.shape[0], J.shape[1] + 1))
            A[:, :-1] = J
            A[:, -1] = residuals(p, part)
            R = np.linalg.qr(A if R is None else np.vstack([R, A]), mode="r")
        k = R.shape[1]
        if R.shape[0] < k:  # fewer rows than columns: the missing rows of R are zero
            R = np.vstack([R, np.zeros((k - R.shape[0], k))])
        return R
    return triangular


def sum_of_squares_noise(r, term_size) -> float:
    """Rounding noise of S = sum r_i^2 when each r_i is a sum of terms of size ``term_size`` computed with a few
    roundings: |dS| <= 2 sum |r_i| dr_i + sum dr_i^2, dr_i = 4 eps term_size_i. ``term_size``: a scalar, an array
    like r, or a function of a slice of the points returning their sizes; taken in blocks of NOISE_BLOCK points,
    so the temporaries stay small for any N."""
    r = np.asarray(r, dtype=np.float64)
    total = 0.0
    for lo in range(0, len(r), NOISE_BLOCK):
        part = slice(lo, min(lo + NOISE_BLOCK, len(r)))
        if callable(term_size):
            size = np.asarray(term_size(part), dtype=np.float64)
        else:
            size = np.asarray(term_size, dtype=np.float64)
            size = size[part] if size.ndim else np.full(part.stop - lo, float(size))
        dr = 4.0 * EPS * size
        total += float(2.0 * dot(np.abs(r[part]), dr) + dot(dr, dr))
    return total


def degenerate_reason(a_unit: float, b_unit: float) -> str | None:
    """Why an ellipse with semi-axes (a, b) in the unit frame (the data's RMS radius is 1) is degenerate,
    or None: axes collapsed to zero, or a semi-axis so long that the fit is a line or its centre is at infinity."""
    lo, hi = min(a_unit, b_unit), max(a_unit, b_unit)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return "the ellipse's semi-axes are not finite"
    if lo <= COLLAPSED_RTOL:
        return (f"degenerate solution: the ellipse collapsed (smallest semi-axis {lo:.3g} x the data's RMS radius, "
                f"below {COLLAPSED_RTOL:g}); the objective's minimum here is not an ellipse through the data")
    if hi >= UNBOUNDED_RTOL:
        return (f"degenerate solution: a semi-axis is {hi:.3g} x the data's RMS radius (above {UNBOUNDED_RTOL:g}): "
                f"the fit runs off to a line or a centre at infinity")
    return None
