"""Ellipse geometry shared by the ellipse methods: normalisation, conic <-> geometric parameters
(including the circle/ellipse paper's eq. 23-25), and the closest point on an ellipse.

Geometric parameters p = (xc, yc, a, b, theta): centre, semi-axes along the rotated x'' and y''
axes, and the rotation theta of the x'' axis (circle/ellipse paper eq. 10-14, with p_x = a, p_y = b,
gamma = theta). Results are canonicalised to a >= b and theta in [0, pi).
"""
from __future__ import annotations

import math

import numpy as np

from methods._compiled import kernels
from methods._frame import UnitFrame, dot

EPS = np.finfo(float).eps


class Frame(UnitFrame):
    """Shift to the centroid, scale to unit RMS distance (as for circles), computed without overflow or
    underflow for every finite input (coordinates up to the largest float64, spreads down to subnormals):
    the sums are formed on values divided by the largest deviation first."""

    @classmethod
    def of(cls, points: np.ndarray):
        x0, y0 = points[:, 0], points[:, 1]
        n = len(x0)
        with np.errstate(over="ignore"):  # x0.mean() is this sum over n (the same bits, less call overhead)
            mx, my = np.add.reduce(x0) / n, np.add.reduce(y0) / n
        if not (np.isfinite(mx) and np.isfinite(my)):  # the sum overflowed: average the scaled values
            mx, my = (x0 / n).sum(), (y0 / n).sum()
        xy = np.empty((2, n))  # x and y as the rows of one buffer: each step below is one operation on both
        x, y = xy
        np.subtract(x0, mx, out=x)
        np.subtract(y0, my, out=y)
        big = float(max(xy.max(), -xy.min()))  # = max |x|, |y| (negation is exact), without a temporary
        if not (np.isfinite(big) and big > 0):
            return super().of(points)  # refused by validation before (identical or non-finite points)
        xy /= big
        rms = float(np.sqrt((dot(x, x) + dot(y, y)) / n))
        xy /= rms
        return cls(shift=np.array([mx, my]), scale=big * rms, x=x, y=y)

    def params_to_unit(self, p) -> np.ndarray:
        p = np.asarray(p, dtype=np.float64)
        return np.array([(p[0] - self.shift[0]) / self.scale, (p[1] - self.shift[1]) / self.scale,
                         p[2] / self.scale, p[3] / self.scale, p[4]])

    def params_to_data(self, p) -> np.ndarray:
        p = np.asarray(p, dtype=np.float64)
        return np.array([p[0] * self.scale + self.shift[0], p[1] * self.scale + self.shift[1],
                         p[2] * self.scale, p[3] * self.scale, p[4]])


def canonical(p) -> np.ndarray:
    """(xc, yc, a, b, theta) with a >= b > 0 and theta in [0, pi) (the same ellipse)."""
    xc, yc, a, b, t = (float(v) for v in p)
    a, b = abs(a), abs(b)
    if b > a:
        a, b, t = b, a, t + np.pi / 2
    t = float(np.mod(t, np.pi))
    if t >= np.pi:  # mod can round up to pi
        t = 0.0
    return np.array([xc, yc, a, b, t])


def params_to_conic(p) -> np.ndarray:
    """(xc, yc, a, b, theta) -> (A, B, C, D, E, F) normalised to 4AC - B^2 = 1, A + C > 0."""
    xc, yc, a, b, t = p
    c, s = np.cos(t), np.sin(t)
    A = (c / a) ** 2 + (s / b) ** 2
    C = (s / a) ** 2 + (c / b) ** 2
    B = 2 * c * s * (1 / a ** 2 - 1 / b ** 2)
    D = -2 * A * xc - B * yc
    E = -B * xc - 2 * C * yc
    F = A * xc ** 2 + B * xc * yc + C * yc ** 2 - 1
    return normalise_conic(np.array([A, B, C, D, E, F]))


def normalise_conic(k) -> np.ndarray:
    """Scale an ellipse's conic vector to 4AC - B^2 = 1 with A + C > 0."""
    k = np.asarray(k, dtype=np.float64)
    disc = 4 * k[0] * k[2] - k[1] ** 2
    if not disc > 0:
        raise ValueError("not an ellipse (4AC - B^2 <= 0)")
    k = k / np.sqrt(disc)
    return -k if k[0] + k[2] < 0 else k


def conic_to_params(k) -> np.ndarray | None:
    """General conic of an ellipse -> canonical (xc, yc, a, b, theta); None if it is no real ellipse.
    Centre from the gradient = 0 (elimination with partial pivoting on the block [[A, B/2], [B/2, C]]), axes from
    that block's eigenvalues and the direction of its smaller one, in closed form: plain floating point, the
    same bits on every CPU (LAPACK's 2 x 2 solve and eigh go through BLAS kernels chosen per CPU)."""
    A, B, C, D, E, F = (float(v) for v in k)
    h = B / 2
    det = A * C - h * h
    if not det > 0:
        return None
    (p0, q0, r0), (p1, q1, r1) = ((A, h, -D / 2), (h, C, -E / 2)) if abs(A) >= abs(h) else ((h, C, -E / 2), (A, h, -D / 2))
    lf = p1 / p0                      # Gaussian elimination with partial pivoting (backward stable, as LAPACK's)
    yc = (r1 - lf * r0) / (q1 - lf * q0)
    xc = (r0 - q0 * yc) / p0
    Fc = F + 0.5 * (D * xc + E * yc)  # value at the centre
    if h == 0.0:  # eigenvalues by one Jacobi rotation, t = tan of its angle (Golub & Van Loan alg. 8.5.1):
        w = (min(A, C), max(A, C))  # A - t h and C + t h, free of the cancellation in det / w_big
    else:
        tau = (C - A) / (2 * h)
        t = math.copysign(1.0, tau) / (abs(tau) + math.hypot(1.0, tau))
        w1, w2 = A - t * h, C + t * h
        w = (min(w1, w2), max(w1, w2))
    if Fc * w[0] >= 0:  # the conic has no real points (or is degenerate)
        return None
    axes = (math.sqrt(-Fc / w[0]), math.sqrt(-Fc / w[1]))  # w[0] <= w[1] -> axes[0] >= axes[1]
    theta = 0.5 * math.atan2(-B, C - A)  # the eigenvector of the smaller eigenvalue: the direction of axes[0]
    return canonical([xc, yc, axes[0], axes[1], theta])


def _sqrt_or_nan(v: float) -> float:
    return math.sqrt(v) if v >= 0 else float("nan")


def paper_gamma_solutions(k) -> dict:
    """The circle/ellipse paper's conversion (eq. 23-25) of a conic (a, b, c, d, e, f), in its sign
    convention (a + c < 0, the interior positive, as its table 5), giving both angle solutions:
    gamma_1 = atan2(b, a - c) / 2 and gamma_2 = gamma_1 + 90 deg, with p_x along gamma and p_y across."""
    sign = -1.0 if k[0] + k[2] > 0 else 1.0
    a, b, c, d, e, f = (sign * float(v) for v in k)
    out = {}
    g1 = math.atan2(b, a - c) / 2  # eq. 23
    for name, g in (("1", g1), ("2", g1 + math.pi / 2 if g1 <= 0 else g1 - math.pi / 2)):
        s2, c2 = math.sin(2 * g), math.cos(2 * g)
        a2 = ((a + c) + b * s2 + (a - c) * c2) / 2  # eq. 24
        c2_ = ((a + c) - b * s2 - (a - c) * c2) / 2
        d2 = d * math.cos(g) + e * math.sin(g)
        e2 = -d * math.sin(g) + e * math.cos(g)
        px = _sqrt_or_nan(d2 ** 2 + a2 * e2 ** 2 / c2_ - 4 * a2 * f) / (2 * a2)  # eq. 25
        py = _sqrt_or_nan(e2 ** 2 + c2_ * d2 ** 2 / a2 - 4 * c2_ * f) / (2 * c2_)
        out[f"gamma{name}"] = float(g)
        out[f"px{name}"] = float(abs(px))
        out[f"py{name}"] = float(abs(py))
    xc = (b * e - 2 * c * d) / (4 * a * c - b * b)  # eq. 23
    yc = (b * d - 2 * a * e) / (4 * a * c - b * b)
    out["xc"], out["yc"] = float(xc), float(yc)
    return out


def to_local(x, y, p):
    """Point coordinates in the ellipse frame O' (circle/ellipse paper eq. 14): u = dx c + dy s,
    v = -dx s + dy c, computed in place (four arrays of N at most; v as dy c - dx s, the same IEEE result)."""
    c, s = np.cos(p[4]), np.sin(p[4])
    dx, dy = x - p[0], y - p[1]
    u = dx * c
    v = dy * s
    u += v
    np.multiply(dy, c, out=v)
    dx *= s
    v -= dx
    return u, v


def _norm(x, y):
    """sqrt(x^2 + y^2) elementwise: the fast formula, np.hypot (slow, but free of over- and underflow)
    only where the squares leave the float64 range."""
    d = np.sqrt(x * x + y * y)
    bad = ~(d >= 1e-150) | (d > 1e150)
    if bad.any():
        d[bad] = np.hypot(x[bad], y[bad])
    return d


def closest_points(u, v, a, b, iterations=60):
    """Closest points (X, Y) on the axis-aligned ellipse (X/a)^2 + (Y/b)^2 = 1 (a >= b > 0) to the
    points (u, v), and the signed distances (positive outside). Vectorised and robust for every
    position: the first-quadrant problem (Eberly, 'Distance from a point to an ellipse', 2013) is
    the root s of G(s) = (r0 z0 / (s + r0))^2 + (z1 / (s + 1))^2 - 1, r0 = (a/b)^2, z = (|u|/a, |v|/b);
    G is convex and decreasing on s > -1, so Newton from the right end of its bracket converges
    monotonically; points on the major axis (z1 = 0) inside the evolute are solved in closed form."""
    au, av = np.abs(u), np.abs(v)
    z0, z1 = au / a, av / b
    r0 = (a / b) ** 2
    n0 = r0 * z0
    g = z0 * z0 + z1 * z1 - 1
    X = np.empty_like(au)
    Y = np.empty_like(av)
    on_axis = z1 == 0
    # general case (z1 > 0), in w = s + 1 > 0 (no cancellation next to the pole s = -1):
    # G(w) = (n0 / (w + r0 - 1))^2 + (z1 / w)^2 - 1, root in [z1, |(n0, z1)|]; Newton from the right
    gen = ~on_axis
    if gen.any():
        every = bool(gen.all())
        n0g, z1g = (n0, z1) if every else (n0[gen], z1[gen])
        lo = z1g
        rm1 = r0 - 1.0
        h = _norm(n0g, z1g)
        if rm1 < 0.1:  # near-circle: first-order root h - n0^2 (r0 - 1) / h^2 (Newton then needs ~2 steps)
            w = np.maximum(h - n0g * n0g * rm1 / (h * h), lo)
        else:
            w = np.maximum(h, lo)
        done = np.zeros(w.shape, dtype=bool)
        for k in range(iterations):
            t0 = w + rm1
            q0s = (n0g / t0) ** 2
            q1s = (z1g / w) ** 2
            step = (q0s + q1s - 1.0) / (2.0 * (q0s / t0 + q1s / w))  # -G / G'
            w_new = np.maximum(w + step, lo)  # never left of the bracket
            rel = np.abs(w_new - w) / w
            w = w_new
            if rel.max() <= 1e-8:  # quadratic convergence: one more step reaches rounding
                t0 = w + rm1
                q0s = (n0g / t0) ** 2
                q1s = (z1g / w) ** 2
                w = np.maximum(w + (q0s + q1s - 1.0) / (2.0 * (q0s / t0 + q1s / w)), lo)
                done[:] = True
                break
            done = rel <= 4 * EPS
        if not done.all():  # slow Newton (points near the centre): finish by bisection in the bracket
            idx = np.flatnonzero(~done)
            lo_b, hi_b = lo[idx].copy(), w[idx].copy()
            n0b, z1b = n0g[idx], z1g[idx]
            for _ in range(1100):
                mid = 0.5 * (lo_b + hi_b)
                pos = (n0b / (mid + rm1)) ** 2 + (z1b / mid) ** 2 - 1.0 > 0
                stuck = (mid == lo_b) | (mid == hi_b)
                lo_b = np.where(pos, mid, lo_b)
                hi_b = np.where(pos, hi_b, mid)
                if stuck.all():
                    break
            w[idx] = 0.5 * (lo_b + hi_b)
        if every:
            X = r0 * au / (w + rm1)
            Y = z1g * b / w
        else:
            X[gen] = r0 * au[gen] / (w + rm1)
            Y[gen] = z1g * b / w
    if on_axis.any():
        au_ax = au[on_axis]
        num = a * au_ax
        den = a * a - b * b
        inside_evolute = num < den
        # (a / den) a u, not a^2 u / den: a^2 u overflows at 1e150 (the compiled kernel's order)
        xa = np.where(inside_evolute, (a / np.where(den > 0, den, 1.0)) * a * au_ax, a)
        xa = np.minimum(xa, a)
        X[on_axis] = xa
        Y[on_axis] = np.where(inside_evolute, b * np.sqrt(np.maximum(1 - (xa / a) ** 2, 0.0)), 0.0)
    X = np.copysign(X, u)
    Y = np.copysign(Y, v)
    d = _norm(u - X, v - Y)
    return X, Y, np.where(g > 0, d, -d)


#: Points per block of :func:`orthogonal_residuals` (at least 4096, ~N/16 above): the closest-point solve
#: needs about twenty temporaries per point, so sixteen blocks keep its memory to ~0.7x the coordinates.
BLOCK_MIN = 4096


def orthogonal_residuals(x, y, p, iterations=60, with_phi=True):
    """Signed orthogonal distances of the points to the ellipse p = (xc, yc, a, b, theta) and (if
    ``with_phi``) the parameter phi of each closest point (x' = a cos phi, y' = b sin phi, eq. 17).
    Compiled: one sweep, point by point (methods/ellipse/_ckernels.c). NumPy reference path
    (FITBENCH_KERNELS=numpy): about sixteen blocks of points, vectorised within each, to bound the temporaries."""
    ck = kernels("methods.ellipse._ckernels")
    xc, yc, a, b, t = (float(v) for v in p)
    if ck is not None and a > 0 and b > 0 and all(map(math.isfinite, (xc, yc, a, b, t))):
        # one compiled sweep, no temporaries (methods/ellipse/_ckernels.c); a degenerate ellipse takes the
        # reference code below, whose NaN/inf distances the callers report
        d = np.empty(len(x))
        phi = np.empty(len(x)) if with_phi else None
        ck.orthogonal(x, y, xc, yc, float(np.cos(t)), float(np.sin(t)), a, b, int(iterations), d, phi)
        return d, phi
    n = len(x)
    block = max(BLOCK_MIN, -(-n // 16))
    if n <= block:
        return _orthogonal_residuals(x, y, p, iterations, with_phi)
    d = np.empty(n)
    phi = np.empty(n) if with_phi else None
    for lo in range(0, n, block):
        hi = min(lo + block, n)
        d[lo:hi], ph = _orthogonal_residuals(x[lo:hi], y[lo:hi], p, iterations, with_phi)
        if with_phi:
            phi[lo:hi] = ph
    return d, phi


def _orthogonal_residuals(x, y, p, iterations, with_phi):
    xc, yc, a, b, t = p
    u, v = to_local(x, y, p)
    if a >= b:
        X, Y, d = closest_points(u, v, a, b, iterations)
    else:  # solve with the axes swapped (the solver wants a >= b)
        Y, X, d = closest_points(v, u, b, a, iterations)
    return d, (np.arctan2(Y / b, X / a) if with_phi else None)
