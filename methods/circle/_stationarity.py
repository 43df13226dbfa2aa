"""The check behind every ``converged=True`` of an iterative circle method: is the returned point a
first-order optimum of the method's own objective, and is it a circle at all?

Both objectives are sums of squares F = sum e_i^2 (geometric: e_i = r_i - R, roundness paper eq. 3-4,
circle/ellipse paper eq. 8-9; algebraic: e_i = r_i^2 - R^2, circle/ellipse paper eq. 4-5). At the
returned point p the Gauss–Newton model of F promises the decrease

    D = g^T (J^T J)^-1 g,   g = J^T e   (the decrease a local least-squares solver started at p finds
                                        to first order; D = 0 exactly at a stationary point).

p is accepted when D <= ``REL_DECREASE`` * F + the rounding noise of F (every e_i carries an absolute
error ~4 eps (|terms|)) + trace(J^T J) (1024 ulp)^2 (moving the circle by 1024 ulps = 2.3e-13 of the data: exact data
have F ~ 0, where a relative test means nothing; ``ulp`` = eps max(1, |shift| / scale) in the unit frame), in the unit frame (data centred, RMS radius 1), so the test does not depend
on the unit or the position of the data. A point whose radius collapses (R < ``MIN_RADIUS`` of the
data's size) or whose centre runs off to infinity (R > ``MAX_RADIUS``: the points are then a
straight line to the precision of the fit) is reported as degenerate, never as converged.

D is the same in every parametrisation of the circle (J -> J T, g -> T^T g for an invertible T), but not its
rounding: for a centre far from the data (beyond ``FAR_CENTRE`` data sizes) the columns of J in (xc, yc, R)
agree to O(1/R^2), J^T J has the condition number ~R^4, and its pseudo-inverse drops the direction of curvature
along which the objective still falls (a Nelder–Mead simplex stranded at R = 1.6e7 on a 45-degree arc:
D = 1e-16 in (xc, yc, R), 38 % of S_CG in the parametrisation below). There D is computed in a parametrisation
that stays well conditioned up to the straight line: for S_CG the direction phi of the centre from the data's
centroid, the distance d = |c| - R of the circle from it and the curvature k = 1/R, with the residual
e_i = (k (w_i^2 + v_i^2) - 2 w_i) / (1 + sqrt((1 - k w_i)^2 + k^2 v_i^2)) (w_i, v_i the point's coordinates
along and across phi, w_i from the circle's nearest point to the centroid; Karimäki, Nucl. Instrum. Methods
A 305 (1991) 187-191; Chernov & Lesort, J. Math. Imaging Vision 23 (2005) 239-252, sec. 6); for S_CA the linear
parameters (2 xc, 2 yc, R^2 - xc^2 - yc^2), J = -[x_i, y_i, 1] (Kåsa's).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from methods._frame import dot

EPS = float(np.finfo(float).eps)
#: a local solver started at an accepted point cannot lower F by more than this fraction (+ rounding)
REL_DECREASE = 1e-9
#: unit-frame radii outside (MIN_RADIUS, MAX_RADIUS) are degenerate circles
MIN_RADIUS, MAX_RADIUS = 1e-8, 1e8
#: a point this many ulps of the data (unit frame; 1024 eps = 2.3e-13 of its size) from the optimum counts as the optimum
DATA_ULPS = 1024
#: unit-frame distance of the centre from the data's centroid beyond which D is computed in the well-conditioned
#: parametrisation (in (xc, yc, R) the direction of curvature is known to ~eps R^4 only: 2e-8 at 100)
FAR_CENTRE = 1e2


@dataclass(frozen=True)
class Stationarity:
    ok: bool
    degenerate: bool
    decrease: float      # D, unit frame
    tolerance: float     # REL_DECREASE * F + rounding noise of F, unit frame
    objective: float     # F, unit frame
    text: str            # what was checked, for the result's message

    def extra(self, scale_power: float) -> dict:
        """The check's numbers in data units (F scales as scale**scale_power)."""
        return {"stationarity_decrease": self.decrease * scale_power, "stationarity_tolerance": self.tolerance * scale_power,
                "stationarity_ok": self.ok, "degenerate": self.degenerate}


def _degenerate(p) -> str | None:
    a, b, rr = (float(v) for v in p)
    if not (math.isfinite(a) and math.isfinite(b) and math.isfinite(rr)):
        return "degenerate: non-finite circle parameters"
    if abs(rr) < MIN_RADIUS:
        return f"degenerate: radius collapsed to {abs(rr):.1e} of the data's size (R = 0 is no circle)"
    if abs(rr) > MAX_RADIUS or math.hypot(a, b) > MAX_RADIUS:
        return (f"degenerate: centre {max(abs(rr), math.hypot(a, b)):.1e} data sizes away "
                "(a circle of infinite radius is a straight line, no circle)")
    return None


def _far(p) -> bool:
    """A centre beyond FAR_CENTRE data sizes, on the side of a positive radius (the objectives' valley towards
    the straight line; a negative R is far from every data point's distance and well conditioned)."""
    return float(p[2]) > 0 and math.hypot(float(p[0]), float(p[1])) > FAR_CENTRE


def _curvature_geometric(x, y, p, noise, ulp) -> Stationarity:
    """D of S_CG at a far centre in the parameters (d, phi, k) of the module docstring (one sweep, used
    only there). dr_i/dd = (1 - k w_i) / s_i, dr_i/dphi = -(1 + k d) v_i / s_i,
    dr_i/dk = v_i^2 / (s_i (s_i + 1 - k w_i)), s_i = sqrt((1 - k w_i)^2 + k^2 v_i^2): no cancellation as k -> 0."""
    a, b, rr = (float(v) for v in p)
    h = math.hypot(a, b)
    cph, sph, k = a / h, b / h, 1.0 / rr
    d = h - rr
    w = x * cph + y * sph
    w -= d
    v = y * cph - x * sph
    m = 1.0 - k * w
    s = np.hypot(m, k * v)
    e = (k * (w * w + v * v) - 2.0 * w) / (1.0 + s)
    jd = m / s
    jphi = (-(1.0 + k * d)) * v / s
    with np.errstate(divide="ignore", invalid="ignore"):  # a point beyond the centre (m < 0): the other form
        jk = np.where(m >= 0, v * v / (s * (s + m)), (s - m) / (s * k * k))
    jtj = np.array([[dot(jd, jd), dot(jd, jphi), dot(jd, jk)], [dot(jd, jphi), dot(jphi, jphi), dot(jphi, jk)],
                    [dot(jd, jk), dot(jphi, jk), dot(jk, jk)]])
    g = np.array([dot(jd, e), dot(jphi, e), dot(jk, e)])
    return _decide(g, jtj, dot(e, e), noise, "S_CG", ulp, frame="(d, phi, 1/R) frame: the centre is far")


def _decide(g, jtj, f, noise, label, ulp, ck=None, frame="") -> Stationarity:
    # + the decrease of moving the circle by DATA_ULPS ulps of the data: below it the data, rounded to
    # float64, do not define the circle any better (exact data have F ~ 0, where 1e-9 F means nothing)
    tol = REL_DECREASE * f + noise + float(np.trace(jtj)) * (DATA_ULPS * ulp) ** 2
    try:  # ck: the same pseudo-inverse by the compiled kernels' Jacobi eigensolver (no NumPy call overhead)
        dec = (ck.psd_decrease(tuple(jtj.ravel().tolist()), tuple(g.tolist())) if ck is not None
               else float(g @ np.linalg.lstsq(jtj, g, rcond=None)[0]))
    except np.linalg.LinAlgError:
        dec = float("inf")
    ok = bool(np.isfinite(dec) and dec <= tol)
    word = "stationary" if ok else "NOT stationary"
    text = (f"{word}: Gauss–Newton decrease of {label} at the returned point {dec:.1e} "
            f"{'<=' if ok else '>'} 1e-9 F + rounding + 1024 data ulps = {tol:.1e} (unit frame{'; ' + frame if frame else ''})")
    return Stationarity(ok, False, dec, tol, f, text)


def _refuse(reason: str) -> Stationarity:
    return Stationarity(False, True, float("nan"), float("nan"), float("nan"), reason)


def geometric(x: np.ndarray, y: np.ndarray, p, ulp: float = EPS) -> Stationarity:
    """Stationarity of S_CG = sum (r_i - R)^2 at unit-frame p = (xc, yc, R)."""
    reason = _degenerate(p)
    if reason:
        return _refuse(reason)
    dx, dy = x - p[0], y - p[1]
    r = dx * dx  # r = sqrt(dx dx + dy dy), d, c, s, delta in place: the same operations, four arrays of N
    d = dy * dy
    r += d
    np.sqrt(r, out=r)
    if not r.all():
        return _refuse("the centre coincides with a data point (S_CG not differentiable there)")
    np.subtract(r, p[2], out=d)
    c, s = np.divide(dx, r, out=dx), np.divide(dy, r, out=dy)
    jtj = np.array([[dot(c, c), dot(c, s), c.sum()], [dot(c, s), dot(s, s), s.sum()], [c.sum(), s.sum(), float(len(x))]])
    g = np.array([dot(c, d), dot(s, d), d.sum()])
    f = dot(d, d)
    delta = np.add(r, abs(p[2]), out=r)
    delta *= 4 * EPS
    noise = 2 * dot(np.abs(d, out=c), delta) + dot(delta, delta)
    if _far(p):
        return _curvature_geometric(x, y, p, noise, ulp)
    return _decide(g, jtj, f, noise, "S_CG", ulp)


def algebraic(x: np.ndarray, y: np.ndarray, p, ulp: float = EPS) -> Stationarity:
    """Stationarity of S_CA = sum ((x_i - xc)^2 + (y_i - yc)^2 - R^2)^2 at unit-frame p; its
    stationary point R = 0 (dS/dR = -4 R sum e_i vanishes there) is reported as degenerate."""
    reason = _degenerate(p)
    if reason:
        return _refuse(reason)
    du, dv = x - p[0], y - p[1]
    q = du * du  # q = du du + dv dv and e = q - R^2 in place (the same operations; peak memory)
    e = dv * dv
    q += e
    np.subtract(q, p[2] * p[2], out=e)
    # residual Jacobian rows -2 [du, dv, R]
    jtj = 4 * np.array([[dot(du, du), dot(du, dv), p[2] * du.sum()], [dot(du, dv), dot(dv, dv), p[2] * dv.sum()],
                        [p[2] * du.sum(), p[2] * dv.sum(), p[2] * p[2] * len(x)]])
    g = -2 * np.array([dot(e, du), dot(e, dv), p[2] * e.sum()])
    f = dot(e, e)
    delta = np.add(q, p[2] * p[2], out=q)
    delta *= 4 * EPS
    noise = 2 * dot(np.abs(e, out=du), delta) + dot(delta, delta)
    if _far(p):  # Kåsa's linear parameters: J = -[x_i, y_i, 1], as well conditioned as the data
        jtj = np.array([[dot(x, x), dot(x, y), x.sum()], [dot(x, y), dot(y, y), y.sum()], [x.sum(), y.sum(), float(len(x))]])
        g = -np.array([dot(e, x), dot(e, y), e.sum()])
        return _decide(g, jtj, f, noise, "S_CA", ulp, frame="(2 xc, 2 yc, R^2 - xc^2 - yc^2) frame: the centre is far")
    return _decide(g, jtj, f, noise, "S_CA", ulp)


def geometric_from_state(p, state, ulp: float, ck, coordinates) -> Stationarity:
    """:func:`geometric` from the normal equations at p that an iteration already computed
    (``methods.circle._frame.geometric_normal_equations``), so the check costs no extra sweep, except for
    a far centre (``coordinates()``: the unit-frame (x, y), then one sweep in the (d, phi, 1/R) frame).
    The rounding noise of F is bounded by Cauchy–Schwarz: 8 eps sqrt(F sum (r_i + R)^2) + 16 eps^2
    sum (r_i + R)^2, with sum (r_i + R)^2 = F + 4 R sum d_i + 4 N R^2."""
    reason = _degenerate(p)
    if reason:
        return _refuse(reason)
    if state is None:
        return _refuse("the centre coincides with a data point (S_CG not differentiable there)")
    f, jtj, jtd, _ = state
    rr = abs(float(p[2]))
    s2 = max(f - 4 * rr * float(jtd[2]) + 4 * jtj[2, 2] * rr * rr, 0.0)
    noise = 8 * EPS * math.sqrt(f * s2) + 16 * EPS * EPS * s2
    if _far(p):
        return _curvature_geometric(*coordinates(), p, noise, ulp)
    return _decide(-jtd, jtj, f, noise, "S_CG", ulp, ck)


def unit_coordinates(points, frame, coordinates=None):
    """For :func:`geometric_from_state`: a function giving the unit-frame (x, y) of ``points`` in ``frame`` (the
    iteration's ``coordinates`` when it has them; on the compiled path, made only when a far centre needs them)."""
    if coordinates is not None:
        return lambda: coordinates
    pts = np.asarray(points, dtype=np.float64)
    return lambda: ((pts[:, 0] - frame.shift[0]) / frame.scale, (pts[:, 1] - frame.shift[1]) / frame.scale)
