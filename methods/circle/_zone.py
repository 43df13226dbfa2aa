"""Shared machinery of the zone methods (minimum zone, MIC, MCC, Chebyshev): active sets,
closed-form centres of contact configurations, optimality certificates, the clarabel interface.

The certificates here are LOCAL for the non-convex minimum zone and MIC (alternating / surrounding
contacts); :func:`fit_zone` adds the global stage of :mod:`methods.circle._global` for those, and reports
``extra["certified"]`` as "global", "local" or False.

All work happens in the unit frame of :class:`~methods.circle._frame.Frame` (1-D arrays x, y).
"""
from __future__ import annotations

from itertools import combinations

import numpy as np

from methods._frame import dot
from methods._lazy import lazy_module
from methods.circle import _global
from methods.circle._geometry import hulls_meet, radii
from methods.circle.results import zone_result

clarabel = lazy_module("clarabel")
sp = lazy_module("scipy.sparse")

#: relative slack of the final check of every point (rounding of radii in the unit frame)
CHECK_RTOL = 1e-12
#: a zone narrower than this (unit frame, i.e. relative to the data's size) is an exact circle:
#: data 10^6 away from the origin are themselves rounded at ~4e-13 of a 299 mm radius
ZERO_WIDTH = 1e-11


def kasa_normal(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """A fast start centre: Kåsa's fit from its 2x2 normal equations on centred unit-frame data
    (a few streaming passes; accuracy only matters for the speed of what follows)."""
    z = x * x + y * y
    sxx, sxy, syy = dot(x, x), dot(x, y), dot(y, y)   # not BLAS: the same bits on every CPU (methods._frame.dot)
    bx, by = 0.5 * dot(x, z), 0.5 * dot(y, z)
    det = sxx * syy - sxy * sxy
    if not det > 1e-300:
        return np.zeros(2)
    return np.array([(bx * syy - sxy * by) / det, (sxx * by - sxy * bx) / det])


def extremes(r: np.ndarray, k: int, largest: bool) -> np.ndarray:
    """Indices of the k largest (or smallest) entries of r, unordered."""
    k = min(k, r.size)
    if k >= r.size:
        return np.arange(r.size)
    # copies of the k indices: a slice would keep argpartition's N indices alive (peak memory)
    return np.argpartition(r, r.size - k)[r.size - k:].copy() if largest else np.argpartition(r, k - 1)[:k].copy()


def sector_extremes(x: np.ndarray, y: np.ndarray, c, m: int) -> tuple[np.ndarray, np.ndarray]:
    """(outer, inner): the farthest and the nearest point about c in each of m equal angular sectors about c
    (empty sectors give none). An active set holding them surrounds the centre: its sub-problem cannot
    narrow the zone by walking off towards a straight zone, as the k most extreme radii of a dense smooth
    profile (all neighbours of one peak and one valley) let it."""
    dx, dy = x - c[0], y - c[1]
    r = np.sqrt(dx * dx + dy * dy)
    sec = np.minimum(((np.arctan2(dy, dx) + np.pi) * (m / (2 * np.pi))).astype(np.intp), m - 1)
    order = np.lexsort((r, sec))
    first = np.searchsorted(sec[order], np.arange(m), side="left")
    last = np.searchsorted(sec[order], np.arange(m), side="right") - 1
    full = last >= first
    return np.unique(order[last[full]]), np.unique(order[first[full]])


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


def directions(x, y, idx, c) -> np.ndarray:
    d = np.column_stack([x[idx] - c[0], y[idx] - c[1]])
    return d / np.linalg.norm(d, axis=1)[:, None]


class SolverFailure(Exception):
    """The conic/linear solver did not return an optimal solution (carries its words)."""


def _dense_to_csc(D: np.ndarray) -> sp.csc_matrix:
    """CSC of a small dense matrix (explicit zeros dropped), built directly: scipy's dense -> COO -> CSC
    path costs ~0.4 ms a call, more than clarabel's solve."""
    nz = D.T != 0
    counts = nz.sum(axis=1)
    indptr = np.concatenate([[0], np.cumsum(counts)])
    rows = np.nonzero(nz)[1]
    return sp.csc_matrix((D.T[nz], rows, indptr), shape=D.shape)


def clarabel_solve(q, rows, b, cones, settings_overrides=None):
    """min q.x s.t. A x + s = b, s in cones, with clarabel. Returns (x, z, iterations)."""
    A = _dense_to_csc(np.asarray(rows, dtype=np.float64))
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


#: candidate centres further than this from the solver's centre (unit frame) are discarded: the
#: solver is accurate to ~1e-8, and far-away circumcentres of near-collinear points are spurious.
CANDIDATE_RADIUS = 1e-3
#: rows per block of the 2 + 2 configurations' centres (peak memory; the values do not depend on it)
CENTRE_BLOCK = 256


class _Rows:
    """P[i] = the points i as rows (x_i, y_i), gathered on demand: no N x 2 copy of the data for a few contacts."""

    def __init__(self, x, y):
        self.x, self.y = x, y

    def __getitem__(self, i):
        return np.column_stack([self.x[i], self.y[i]])


class Candidates:
    """Candidate centres ``C`` (K rows, unit frame) and, on demand, each one's contact configuration
    (:meth:`row`: 4 point indices, -1 = none, or 3 for one-sided fits, then the number of outer contacts).

    Built from blocks of candidates (:meth:`add`), each with a function that gives the configuration of its
    i-th row and a mask of the rows that are configurations at all, and filtered block by block (:meth:`near`):
    only the kept centres are stacked, a block's kept rows are a boolean mask, and no configuration is
    materialised except the one asked for (a few bytes per candidate besides the centres)."""

    def __init__(self):
        self._blocks = []   # (centres, config(i) -> row, valid rows or None)
        self.C = np.empty((0, 2))
        self._kept = []     # (offset in C, mask of the block's kept rows, config)

    def add(self, centres: np.ndarray, config, valid: np.ndarray | None = None) -> None:
        if len(centres):
            self._blocks.append((centres, config, valid))

    def near(self, near) -> "Candidates":
        """Keep the valid candidates within CANDIDATE_RADIUS of ``near``; if none is, every finite valid one (the
        final check decides). The kept centres are stacked in their order."""
        finite = [np.isfinite(C).all(axis=1) & (True if v is None else v) for C, _, v in self._blocks]
        close = [f & (np.hypot(C[:, 0] - near[0], C[:, 1] - near[1]) <= CANDIDATE_RADIUS)
                 for (C, _, _), f in zip(self._blocks, finite)]
        keep = close if any(k.any() for k in close) else finite
        self.C = np.empty((sum(int(k.sum()) for k in keep), 2))
        self._kept = []
        offset = 0
        for (C, config, _), k in zip(self._blocks, keep):
            count = int(k.sum())
            np.compress(k, C, axis=0, out=self.C[offset:offset + count])
            self._kept.append((offset, k, config))
            offset += count
        self._blocks = []
        return self

    def __len__(self) -> int:
        return len(self.C)

    def row(self, k: int) -> np.ndarray:
        """The configuration of candidate ``k`` (a row of C)."""
        for offset, kept, config in reversed(self._kept):
            if k >= offset:
                return np.asarray(config(int(np.flatnonzero(kept)[k - offset])), dtype=np.intp)
        raise IndexError(k)


def zone_candidates(x, y, outer_c, inner_c, near) -> Candidates:
    """Closed-form centres of the minimum-zone contact configurations: 2 outer + 2 inner (the two
    bisectors meet), 3 + 1 and 1 + 3 (circumcentres), and 3 + 0. Configuration rows: 4 point indices and the
    number of outer contacts."""
    P = _Rows(x, y)
    out = Candidates()
    po, pi = pairs(outer_c), pairs(inner_c)
    if len(po) and len(pi):
        # row i of the block: the outer pair i div Q with the inner pair i mod Q (Q inner pairs); valid unless they
        # share a point (a point cannot be an outer and an inner contact at once); centres a block of rows at a time
        q = len(pi)
        o0, o1, i0, i1 = po[:, 0, None], po[:, 1, None], pi[None, :, 0], pi[None, :, 1]
        distinct = ((o0 != i0) & (o0 != i1) & (o1 != i0) & (o1 != i1)).ravel()
        centres = np.empty((len(distinct), 2))
        for s in range(0, len(distinct), CENTRE_BLOCK):
            i = np.arange(s, min(s + CENTRE_BLOCK, len(distinct)))
            a, b = po[i // q], pi[i % q]
            centres[s:s + len(i)] = bisector_centres(P[a[:, 0]], P[a[:, 1]], P[b[:, 0]], P[b[:, 1]])
        out.add(centres, lambda i, po=po, pi=pi, q=q: (*po[i // q], *pi[i % q], 2), distinct)
    for tri, singles, n_outer in ((triples(outer_c), inner_c, 3), (triples(inner_c), outer_c, 1)):
        if len(tri) and len(singles):
            cc = bisector_centres(P[tri[:, 0]], P[tri[:, 1]], P[tri[:, 1]], P[tri[:, 2]])
            # row i of the block: the triangle i mod T with the single i div T (T triangles); valid unless the single
            # is one of the triangle's points
            singles = np.asarray(singles)
            t = len(tri)
            valid = (np.tile(tri, (len(singles), 1)) != np.repeat(singles, t)[:, None]).all(axis=1)
            config = ((lambda i, tri=tri, singles=singles, t=t: (*tri[i % t], singles[i // t], 3)) if n_outer == 3
                      else (lambda i, tri=tri, singles=singles, t=t: (singles[i // t], *tri[i % t], 1)))
            out.add(np.tile(cc, (len(singles), 1)), config, valid)
    tri = triples(outer_c)
    if len(tri):  # 3 + 0: the circle through three points (an exact circle, or N = 3)
        out.add(bisector_centres(P[tri[:, 0]], P[tri[:, 1]], P[tri[:, 1]], P[tri[:, 2]]),
                lambda i, tri=tri: (*tri[i], -1, 3))
    return out.near(near)


def circle_candidates(x, y, idx, near, side: str) -> Candidates:
    """Closed-form centres of circles touching 2 points as a diameter (midpoints) or 3 points
    (circumcentres), for MCC (side='outer') or MIC (side='inner'). Configuration rows: 3 indices (-1 = none) and
    the number of outer contacts (all or none)."""
    P = _Rows(x, y)
    pr, tr = pairs(idx), triples(idx)
    out = Candidates()
    outer = side == "outer"
    if len(pr):
        out.add(0.5 * (P[pr[:, 0]] + P[pr[:, 1]]), lambda i, pr=pr: (*pr[i], -1, 2 if outer else 0))
    if len(tr):
        out.add(bisector_centres(P[tr[:, 0]], P[tr[:, 1]], P[tr[:, 1]], P[tr[:, 2]]),
                lambda i, tr=tr: (*tr[i], 3 if outer else 0))
    return out.near(near)


def candidate_extremes(x, y, act, C, *, squared: bool = False):
    """(largest, smallest) distance from each of K candidate centres to the M active points (``squared``: of the
    squared distances, each a distance squared). The (K, M) distances are formed a block of candidates at a time
    in two buffers of at most max(1536, N / 8) numbers, never K x M at
    once; the values are those of the whole matrix."""
    ax, ay = x[act], y[act]
    k, m = len(C), len(ax)
    step = max(1, max(1536, len(x) // 8) // max(m, 1))
    hi, lo = np.empty(k), np.empty(k)
    bx, by = np.empty((min(step, k), m)), np.empty((min(step, k), m))
    for s in range(0, k, step):
        rows = min(step, k - s)
        dx, dy = bx[:rows], by[:rows]
        np.subtract(ax[None, :], C[s:s + rows, 0:1], out=dx)
        np.subtract(ay[None, :], C[s:s + rows, 1:2], out=dy)
        dx *= dx
        dy *= dy
        dx += dy
        np.sqrt(dx, out=dx)
        if squared:
            dx *= dx
        dx.max(axis=1, out=hi[s:s + rows])
        dx.min(axis=1, out=lo[s:s + rows])
    return hi, lo


def pick(cands: Candidates, score, minimise: bool):
    """Best candidate (the first of equal scores) and its (outer, inner) contact index tuples."""
    score = np.where(np.isfinite(score), score, np.inf if minimise else -np.inf)
    best = int(np.argmin(score) if minimise else np.argmax(score))
    row = cands.row(best)
    c = cands.C[best].copy()  # not a view: the candidates are not held by the centre (peak memory)
    width = row.size - 1
    members = [int(i) for i in row[:width] if i >= 0]
    n_outer = int(row[width])
    if width == 3:  # single-sided (MIC / MCC)
        return c, ((tuple(members), ()) if n_outer else ((), tuple(members)))
    if len(members) == 3:  # 3 + 0: every point on one circle; the inner contacts are the same points
        return c, (tuple(members), tuple(members))
    return c, (tuple(members[:n_outer]), tuple(members[n_outer:]))


def relabel_extremes(x, y, act, c, contacts):
    """Among tied candidate configurations the one picked may name a contact that is not extreme about
    the (right) centre: name the extreme active points instead (same counts)."""
    oc, ic = contacts
    r = radii(x[act], y[act], c)
    order = np.argsort(r)
    if oc and r.max() > r[np.searchsorted(act, list(oc))].max() * (1 + CHECK_RTOL):
        oc = tuple(int(i) for i in act[order[::-1][:len(oc)]])
    if ic and r.min() < r[np.searchsorted(act, list(ic))].min() * (1 - CHECK_RTOL):
        ic = tuple(int(i) for i in act[order[:len(ic)]])
    return c, (oc, ic)


def active_set_fit(x, y, *, start, local_solve, exact, certify, sides, k, max_rounds, sectors: int = 0):
    """The loop shared by the zone methods.

    ``local_solve(out, inn, c) -> (c_approx, solves, solver_iterations, history)`` solves the convex
    (sub)problem on the active points; ``exact(act, c_approx) -> (c, (outer, inner))`` gives the exact
    centre from the contact configurations; every point is then checked in one vectorised pass
    against the contacts' radii on the used ``sides`` ('outer', 'inner'); violators join the active
    set. ``certify(c, outer, inner) -> (bool, message)`` checks optimality. ``sectors`` > 0: the start's
    active set also holds the extreme points of that many angular sectors (:func:`sector_extremes`). Raises
    SolverFailure.
    """
    c = start
    r_all = radii(x, y, c)
    out = extremes(r_all, max(k, 4), True) if "outer" in sides else np.empty(0, dtype=np.intp)
    inn = extremes(r_all, max(k, 4), False) if "inner" in sides else np.empty(0, dtype=np.intp)
    if sectors:
        so, si = sector_extremes(x, y, c, sectors)
        out = np.union1d(out, so) if "outer" in sides else out
        inn = np.union1d(inn, si) if "inner" in sides else inn
    stats = {"solves": 0, "solver_iterations": 0, "history": [], "rounds": 0}
    for stats["rounds"] in range(1, max_rounds + 1):
        ck, solves, iters, hist = local_solve(out, inn, c)
        stats["solves"] += solves
        stats["solver_iterations"] += iters
        stats["history"] += hist
        act = np.union1d(out, inn)
        r_all = None  # the previous pass's radii are not held during the exact step and the next pass (peak memory)
        c, (oc, ic) = relabel_extremes(x, y, act, *exact(act, ck))
        r_all = radii(x, y, c)
        before = out.size + inn.size
        violated = False
        if "outer" in sides:
            over = r_all - r_all[list(oc)].max() * (1 + CHECK_RTOL) - 1e-15
            if (over > 0).any():
                out, violated = add_violators(out, over, k), True
            over = None  # not held into the next pass (peak memory)
        if "inner" in sides:
            under = r_all[list(ic)].min() * (1 - CHECK_RTOL) - 1e-15 - r_all
            if (under > 0).any():
                inn, violated = add_violators(inn, under, k), True
            under = None
        if violated and out.size + inn.size == before:
            stats["active"] = np.union1d(out, inn)
            stats["active_points"] = int(stats["active"].size)
            return c, (oc, ic), False, ("the contacts found are not the extreme points about their centre and no "
                                        "new point can be added: no optimum is claimed"), stats
        if violated:
            continue
        r_all = None
        ok, message = certify(c, oc, ic)
        if not ok and sides == ("outer",):
            # an MCC whose contacts do not surround the centre: the solver's centre may have ranked the points of
            # one flat peak first (extreme points nearly on a semicircle); the k outermost points about the exact
            # centre join the active set and the round is repeated, while that adds points (the MIC is left to its
            # global stage: on a partial arc it has no optimum to find)
            grown = np.union1d(out, extremes(radii(x, y, c), k, True))
            if grown.size > out.size:
                out = grown
                continue
        stats["active"] = np.union1d(out, inn)
        stats["active_points"] = int(stats["active"].size)
        return c, (oc, ic), ok, message, stats
    stats["active"] = np.union1d(out, inn)
    stats["active_points"] = int(stats["active"].size)
    return c, ((), ()), False, f"active set not settled within max_rounds={max_rounds}", stats


def fit_zone(points, frame, *, start, local_solve, exact, certify, sides, k, max_rounds, radius_rule,
             proof="convex", global_search="always"):
    """Run :func:`active_set_fit` and build the result in data units (SolverFailure -> converged=False).

    ``proof``: "convex" (the program is convex: its optimality condition is a global certificate),
    "zone" or "inscribed" (non-convex: the local certificate is followed, unless
    ``global_search == "never"``, by the branch and bound of :mod:`methods.circle._global`).
    ``extra["certified"]`` is "global", "local" or False and the message says which and why."""
    x, y = frame.x, frame.y

    def run(s, sectors=0):
        return active_set_fit(x, y, start=s, local_solve=local_solve, exact=exact, certify=certify, sides=sides,
                              k=k, max_rounds=max_rounds, sectors=sectors)
    info = {}
    try:
        c, (oc, ic), ok, message, stats = run(start)
        if proof == "convex":
            certified = "global" if ok else False
            if ok:
                message = f"certified global optimum of a convex program over all centres ({message})"
        elif global_search == "never":
            if ok and proof == "inscribed" and not _global.ProfilePolygon(x, y).contains(np.asarray(c)[None, :])[0]:
                ok, message = False, ("the local centre lies outside the profile polygon (points in angular order "
                                      "about their centroid): not an inscribed circle")
            certified = "local" if ok else False
            if ok:
                message = f"local optimum only ({message}); the global search was not run (global_search='never')"
        else:
            c, (oc, ic), ok, certified, message, info = _global.globalise(
                x, y, kind=proof, c=c, contacts=(oc, ic), ok=ok, message=message, stats=stats, rerun=run,
                hulls_meet=hulls_meet, scale=frame.scale, shift=frame.shift, solver_failure=SolverFailure)
    except SolverFailure as exc:
        c, (oc, ic), ok, certified, message = start, ((), ()), False, False, f"{exc}; no result is claimed"
        stats = {"solves": None, "solver_iterations": None, "history": [], "rounds": None, "active_points": None}
    center = info.pop("center_data", None)
    if center is None:
        center, _ = frame.circle_to_data(np.array([c[0], c[1], 1.0]))
    # the radius rule runs in the unit frame and is mapped back (radius = scale x rule(r / scale)): radii
    # squared in data units overflow beyond ~1e154 and underflow below ~1e-154
    radius = frame.scale * float(radius_rule(radii(x, y, c), c))
    if not (np.isfinite(radius) and np.all(np.isfinite(center))):
        ok, certified = False, False
        message = (f"the circle is not representable in float64 at this scale (centre {center}, radius {radius}); "
                   f"no result is claimed (solver said: {message})")
    return zone_result(points, center, radius, {"outer": sorted(oc), "inner": sorted(ic)}, converged=bool(ok),
                       message=message, iterations=stats["solves"], nfev=stats["solver_iterations"],
                       history=[h * frame.scale for h in stats["history"]],
                       extra={"certified": certified, "rounds": stats["rounds"], "active_points": stats["active_points"],
                              **{f"global_{k}": v for k, v in info.items()}})


def surrounding_contacts(x, y, c, idx, tol: float = 1e-12):
    """Two or three of the points ``idx`` whose unit directions from c hold c in their convex hull, or None.

    The directions surround c exactly when no open half-plane through c holds them all, i.e. when the
    largest angular gap between consecutive directions is at most pi (+ ``tol`` rad). Then, from the first
    direction a, the last direction b within pi of it and the next one c' (b -> c' is one gap) span c: every
    arc between them is at most pi. Angles sorted once: O(T log T) for T tied points, no limit on T."""
    idx = np.asarray(idx, dtype=np.intp)
    if idx.size < 2:
        return None
    ang = np.arctan2(y[idx] - c[1], x[idx] - c[0])
    order = np.argsort(ang, kind="stable")
    ang, ids = ang[order], idx[order]
    gaps = np.diff(np.append(ang, ang[0] + 2 * np.pi))
    if gaps.max() > np.pi + tol:
        return None
    k = int(np.searchsorted(ang, ang[0] + np.pi, side="right")) - 1
    if abs(ang[k] - ang[0] - np.pi) <= tol:
        pick = (ids[0], ids[k])
    elif k + 1 < ids.size:
        pick = (ids[0], ids[k], ids[k + 1])
    else:
        return None
    return tuple(int(i) for i in pick) if hulls_meet(directions(x, y, list(pick), c), np.zeros((1, 2))) else None


def tie_tolerance(r_extreme: float) -> float:
    """Radii within this of the extreme radius (unit frame) count as one-sided contacts: the slack of the final
    check of every point in :func:`active_set_fit` (CHECK_RTOL relative + 1e-15), so a point the check let through
    as "not beyond the contacts" is also a contact for the certificate."""
    return CHECK_RTOL * abs(r_extreme) + 1e-15


def certify_hulls(x, y, *, zero_tol=ZERO_WIDTH):
    """Certificate factory: minimum zone (both sides) or MIC/MCC (one side against the origin);
    a zone of width <= zero_tol (unit frame) about the centre is an exact circle.

    One side (MCC, MIC): the points whose radius is within :func:`tie_tolerance` of the extreme radius (the final
    check's slack) must surround the centre (:func:`surrounding_contacts`). That proves (convexity of |p - c|:
    r_i(c') >= r_i(c) - e_i.(c' - c), and some tied e_i has e_i.(c' - c) <= 0) that no centre c' gives a
    circumscribed circle smaller (MCC), or a local inscribed circle larger (MIC), by more than the tolerance."""
    def certify(c, oc, ic):
        r = radii(x, y, c)
        if r.max() - r.min() <= zero_tol:  # every point is a contact: the zone is a single circle
            return True, "points lie on one circle (zone width at rounding level)"
        if oc and ic:
            ok = hulls_meet(directions(x, y, list(oc), c), directions(x, y, list(ic), c))
            return ok, ("optimal: contacts alternate (conv(outer) meets conv(inner) directions)" if ok else
                        "stationary zone whose contacts do not satisfy the alternation condition")
        side = list(oc or ic)
        if len(side) < 2:
            return False, "fewer than two contacts: no optimality certificate"
        if hulls_meet(directions(x, y, side, c), np.zeros((1, 2))):
            return True, "optimal: the centre lies in the convex hull of the contacts"
        extreme = r.max() if oc else r.min()
        tol = tie_tolerance(extreme)
        tied = np.flatnonzero(r >= extreme - tol) if oc else np.flatnonzero(r <= extreme + tol)
        found = surrounding_contacts(x, y, c, tied)
        if found is not None:
            return True, (f"optimal to {CHECK_RTOL:g} x the radius: the {tied.size} points within {CHECK_RTOL:g} x the "
                          f"radius of the {'largest' if oc else 'smallest'} one (the final check's slack) surround the "
                          f"centre (e.g. points {', '.join(map(str, found))})")
        if oc:  # the MCC's extreme points nearly on a semicircle: a dual bound decides instead
            lower, subset = enclosing_lower_bound(x, y, np.argsort(r)[::-1][:DUAL_POINTS])
            if r.max() - lower <= tol:
                return True, (f"optimal to {(r.max() - lower) / r.max():.1e} x the radius (tolerance {CHECK_RTOL:g}, the "
                              f"final check's slack): the smallest circle holding points {', '.join(map(str, subset))} "
                              "alone, a lower bound of the smallest circle holding all, has a radius that much smaller")
        return False, ("the contacts do not surround the centre, nor do the points within "
                       f"{CHECK_RTOL:g} x the radius of the {'largest' if oc else 'smallest'} one: not an optimum")
    return certify


#: the most extreme points whose pairs and triples give the MCC's dual bound (:func:`enclosing_lower_bound`)
DUAL_POINTS = 24


def enclosing_lower_bound(x, y, idx):
    """max over the pairs and triples of the points ``idx`` of the radius of the smallest circle holding them: a
    lower bound of the smallest circle holding all points (it holds every subset). Two points: half their
    distance; three: the circumradius |ab||bc||ca| / (2 x twice the area) when no angle is obtuse, else half
    the longest side. Lowered by 64 eps relative for the rounding. Returns (bound, the subset attaining it)."""
    idx = np.asarray(idx, dtype=np.intp)
    P = np.column_stack([x[idx], y[idx]])
    pr = pairs(np.arange(len(idx)))
    best = np.hypot(*(P[pr[:, 0]] - P[pr[:, 1]]).T) / 2
    j = int(np.argmax(best))
    value, subset = float(best[j]), tuple(int(idx[i]) for i in pr[j])
    tr = triples(np.arange(len(idx)))
    if len(tr):
        a, b, c = P[tr[:, 0]], P[tr[:, 1]], P[tr[:, 2]]
        ab, bc, ca = b - a, c - b, a - c
        lab, lbc, lca = np.hypot(*ab.T), np.hypot(*bc.T), np.hypot(*ca.T)
        acute = ((-ca * ab).sum(1) > 0) & ((-ab * bc).sum(1) > 0) & ((-bc * ca).sum(1) > 0)
        # twice the area from the two sides at the vertex opposite the longest side (its angle is 60-90 deg in an
        # acute triangle, so the cross product loses no digits to cancellation: relative rounding ~4 eps)
        at_a = abs(ab[:, 0] * ca[:, 1] - ab[:, 1] * ca[:, 0])
        at_b = abs(bc[:, 0] * ab[:, 1] - bc[:, 1] * ab[:, 0])
        at_c = abs(ca[:, 0] * bc[:, 1] - ca[:, 1] * bc[:, 0])
        longest = np.argmax(np.column_stack([lab, lbc, lca]), axis=1)   # ab -> vertex c, bc -> a, ca -> b
        cross = np.choose(longest, [at_c, at_a, at_b])
        with np.errstate(divide="ignore", invalid="ignore"):
            rad = np.where(acute & (cross > 0), lab * lbc * lca / (2 * cross), np.maximum(np.maximum(lab, lbc), lca) / 2)
        rad = np.where(np.isfinite(rad), rad, 0.0)
        k = int(np.argmax(rad))
        if rad[k] > value:
            value, subset = float(rad[k]), tuple(int(idx[i]) for i in tr[k])
    return value * (1 - 64 * np.finfo(float).eps), subset
