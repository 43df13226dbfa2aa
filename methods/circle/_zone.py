"""Shared machinery of the zone methods (minimum zone, MIC, MCC, Chebyshev): active sets,
closed-form centres of contact configurations, optimality certificates, the clarabel interface.

All work happens in the unit frame of :class:`~methods.circle._frame.Frame` (1-D arrays x, y).
"""
from __future__ import annotations

from itertools import combinations

import clarabel
import numpy as np
import scipy.sparse as sp

#: relative slack of the final check of every point (rounding of radii in the unit frame)
CHECK_RTOL = 1e-12


def radii(x: np.ndarray, y: np.ndarray, c) -> np.ndarray:
    dx = x - c[0]
    dy = y - c[1]
    return np.sqrt(dx * dx + dy * dy)


def kasa_normal(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """A fast start centre: Kåsa's fit from its 2x2 normal equations on centred unit-frame data
    (a few streaming passes; accuracy only matters for the speed of what follows)."""
    z = x * x + y * y
    sxx, sxy, syy = x @ x, x @ y, y @ y
    bx, by = 0.5 * (x @ z), 0.5 * (y @ z)
    det = sxx * syy - sxy * sxy
    if not det > 1e-300:
        return np.zeros(2)
    return np.array([(bx * syy - sxy * by) / det, (sxx * by - sxy * bx) / det])


def extremes(r: np.ndarray, k: int, largest: bool) -> np.ndarray:
    """Indices of the k largest (or smallest) entries of r, unordered."""
    k = min(k, r.size)
    if k >= r.size:
        return np.arange(r.size)
    return np.argpartition(r, r.size - k)[r.size - k:] if largest else np.argpartition(r, k - 1)[:k]


def add_violators(active: np.ndarray, excess: np.ndarray, k: int) -> np.ndarray:
    """Add up to k of the worst violators (excess > 0) to an active index set."""
    bad = np.flatnonzero(excess > 0)
    if bad.size > k:
        bad = bad[np.argpartition(excess[bad], bad.size - k)[bad.size - k:]]
    return np.union1d(active, bad)


def bisector_centres(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Centres equidistant from a and b and from c and d, for stacks (K, 2) of points:
    (b - a).z = (b - a).(a + b)/2 and (d - c).z = (d - c).(c + d)/2. Circumcentres: (a, b, b, c).
    Parallel bisectors give non-finite rows."""
    n1, n2 = b - a, d - c
    h1 = 0.5 * np.einsum("ij,ij->i", n1, a + b)
    h2 = 0.5 * np.einsum("ij,ij->i", n2, c + d)
    det = n1[:, 0] * n2[:, 1] - n1[:, 1] * n2[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.column_stack([(h1 * n2[:, 1] - n1[:, 1] * h2) / det, (n1[:, 0] * h2 - h1 * n2[:, 0]) / det])


def pairs(idx):
    return np.array(list(combinations(idx, 2)), dtype=np.intp).reshape(-1, 2)


def triples(idx):
    return np.array(list(combinations(idx, 3)), dtype=np.intp).reshape(-1, 3)


def _inside_triangle(p, a, b, c, tol=1e-12) -> bool:
    """p in the closed triangle abc (2-D points)."""
    def cross(o, u, v):
        return (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])
    d1, d2, d3 = cross(a, b, p), cross(b, c, p), cross(c, a, p)
    return not ((min(d1, d2, d3) < -tol) and (max(d1, d2, d3) > tol))


def _segments_cross(a, b, c, d, tol=1e-12) -> bool:
    """Closed segments ab and cd intersect."""
    def cross(o, u, v):
        return (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])
    d1, d2, d3, d4 = cross(c, d, a), cross(c, d, b), cross(a, b, c), cross(a, b, d)
    return d1 * d2 <= tol and d3 * d4 <= tol


def hulls_meet(u: np.ndarray, v: np.ndarray) -> bool:
    """Do conv(u) and conv(v) intersect? u, v: unit direction vectors (rows) of up to 3 points each;
    the cases of the minimum-zone (2+2, 3+1, 1+3) and MIC/MCC (0 against 2 or 3 directions)."""
    if len(u) == 2 and len(v) == 2:
        return _segments_cross(u[0], u[1], v[0], v[1])
    if len(u) == 3 and len(v) == 1:
        return _inside_triangle(v[0], *u)
    if len(u) == 1 and len(v) == 3:
        return _inside_triangle(u[0], *v)
    if len(u) == 2 and len(v) == 1:
        return _segments_cross(u[0], u[1], v[0], v[0])
    if len(u) == 1 and len(v) == 2:
        return _segments_cross(v[0], v[1], u[0], u[0])
    return False


def directions(x, y, idx, c) -> np.ndarray:
    d = np.column_stack([x[idx] - c[0], y[idx] - c[1]])
    return d / np.linalg.norm(d, axis=1)[:, None]


class SolverFailure(Exception):
    """The conic/linear solver did not return an optimal solution (carries its words)."""


def clarabel_solve(q, rows, b, cones, settings_overrides=None):
    """min q.x s.t. A x + s = b, s in cones, with clarabel. Returns (x, z, iterations)."""
    A = sp.csc_matrix(np.asarray(rows, dtype=np.float64))
    P = sp.csc_matrix((len(q), len(q)))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = 1e-10
    settings.tol_feas = 1e-10
    for k, v in (settings_overrides or {}).items():
        setattr(settings, k, v)
    sol = clarabel.DefaultSolver(P, np.asarray(q, dtype=np.float64), A, np.asarray(b, dtype=np.float64),
                                 cones, settings).solve()
    status = str(sol.status)
    if status not in ("Solved", "AlmostSolved"):
        raise SolverFailure(f"clarabel: {status} after {sol.iterations} iterations")
    return np.asarray(sol.x), np.asarray(sol.z), int(sol.iterations)


def trust_rows(ck, delta, nvar):
    """Box |c - ck|_inf <= delta as 4 nonnegative rows on the first two variables."""
    rows, b = [], []
    for j in range(2):
        e = np.zeros(nvar)
        e[j] = 1.0
        rows += [e, -e]
        b += [ck[j] + delta, delta - ck[j]]
    return rows, b
