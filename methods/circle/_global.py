"""Global certificates for the minimum zone and the maximum inscribed circle (MIC).

Both objectives are non-convex in the centre c, so a local optimality condition (alternating
contacts) proves only a local optimum. This module proves a *global* one by branch and bound over
the centre, seeded by the fast local solution (c*, f*), all in the unit frame:

* **Rigorous box bounds.** For a square box B and any point p_i, the exact least and greatest
  distances dmin_i(B), dmax_i(B) from B to p_i bound r_i(c) = |p_i - c| for every c in B. Hence for
  every c in B, over ANY subset S of the points:
  width(c) = max_i r_i - min_i r_i >= max_S dmin_i - min_S dmax_i      (minimum zone),
  min_i r_i(c) <= min_S dmax_i                                          (MIC).
  A subset gives a valid bound, so the bounds use a small working set S (the local solver's active
  points); where S is too weak to discard a box, the width of ALL points at the box centre is
  computed once (one vectorised pass): either that centre beats the incumbent (the local solution
  was not global: the local solver is restarted there) or its extreme points join S.
* **A certified ball around c*.** With the tied contacts at c* (outer O, inner I, unit directions e),
  r_i(c* + d) = r_i(c*) - e_i.d + q_i with 0 <= q_i <= |d|^2 / (2 (r_i - |d|)) (convexity of |.|), so
  width(c* + d) >= f* + kappa |d| - |d|^2 / (2 (r_in - |d|)), kappa = min_{|d|=1} max_O(-e.d) + max_I(e.d),
  and width >= f* on |d| <= 2 kappa r_in / (1 + 2 kappa) (kappa > 0 exactly when the contacts strictly
  alternate). Likewise for the MIC with kappa = min_{|d|=1} max_I e.d (contacts surround c*).
* **Far field (minimum zone).** With the origin at the centroid, rho >= max |p_i| and W the least
  width of the points over all directions, every centre at distance t > rho has
  width >= W - rho^2 / (2 (t - rho)); so no centre beyond T = rho + rho^2 / (2 (W - f*)) can do better, and
  the search region is the disc |c| <= T: the certificate then holds over ALL of R^2. When W <= f*
  (nearly straight data: the zone of a straight line is as good) no finite T exists; the region is then
  the disc of radius ``FALLBACK_RADIUS`` x rho about the centroid, and the message says so.
* **MIC region.** The MIC is defined for centres inside the profile polygon (the points joined in
  angular order about their centroid); boxes wholly outside it are discarded (a box centre outside the
  polygon farther than the box's half-diagonal from every edge), candidate centres must be inside.

A box is discarded when its bound shows it cannot beat the incumbent by more than
eps = EPS_REL f* + EPS_ABS + 4 TIE_REL max r (unit frame; :func:`resolution`); "global" therefore means: no centre in the stated region has
a width below f* - eps (MIC: a radius above f* + eps), where f* is attained by the reported centre.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from methods.circle._geometry import radii

#: relative and absolute (unit-frame) resolution of the global certificate
EPS_REL = 1e-10
EPS_ABS = 1e-13
#: contacts within TIE_REL x the largest radius of the extreme radius count as tied (rounding of radii)
TIE_REL = 1e-14
#: region radius (multiples of the data radius about the centroid) when no far-field bound exists
FALLBACK_RADIUS = 10.0
MAX_LEVELS = 90
MAX_BOXES = 20_000
MAX_FULL_PASSES = 400
#: local-solver restarts from better centres the branch and bound finds, at most
MAX_RESTARTS = 10
#: angular sectors whose extreme points start a restart's active set (:func:`methods.circle._zone.sector_extremes`)
RESTART_SECTORS = 32


def growth_rate(A: np.ndarray, B: np.ndarray | None) -> float:
    """kappa = min over unit d of max_{a in A} a.d + max_{b in B} b.d (B None: the second term is 0).

    The function is convex and positively homogeneous, linear on each arc between its breakpoints;
    its minimum on the unit circle is therefore at a breakpoint (d orthogonal to a difference of two
    vectors of one set) or at the minimiser -l/|l| of one linear piece l = a + b."""
    B = np.zeros((1, 2)) if B is None or len(B) == 0 else B
    cands = []
    for V in (A, B):
        if len(V) > 1:
            i, j = np.triu_indices(len(V), 1)
            diff = V[i] - V[j]
            nrm = np.column_stack([-diff[:, 1], diff[:, 0]])
            cands += [nrm, -nrm]
    pieces = (A[:, None, :] + B[None, :, :]).reshape(-1, 2)
    cands.append(-pieces)
    D = np.vstack(cands)
    n = np.hypot(D[:, 0], D[:, 1])
    D = D[n > 0] / n[n > 0, None]
    if not len(D):
        return 0.0
    return float((_max_projection(D, A) + _max_projection(D, B)).min())


def _max_projection(D: np.ndarray, V: np.ndarray, block: int = 65536) -> np.ndarray:
    """max over the rows v of V of d.v, for each row d of D: products and sums, not BLAS (``D @ V.T``, whose bits
    depend on the CPU's BLAS kernel), a block of rows of D at a time (at most ``block`` products: with many tied
    contacts D has |V|^2 rows)."""
    out = np.empty(len(D))
    step = max(1, block // max(len(V), 1))
    for s in range(0, len(D), step):
        d = D[s:s + step]
        p = np.multiply.outer(d[:, 0], V[:, 0])
        p += np.multiply.outer(d[:, 1], V[:, 1])
        p.max(axis=1, out=out[s:s + step])
    return out


def least_width_lower_bound(x: np.ndarray, y: np.ndarray, rho: float, m: int = 2048) -> float:
    """A lower bound of min over directions u of (max p.u - min p.u) for the points (x, y) (any subset
    of the data gives a lower bound of the data's), sampled at m directions: between samples the
    extent changes by at most 2 rho |dtheta| (|d(p.u)/dtheta| <= |p| <= rho)."""
    t = np.arange(m) * (np.pi / m)
    proj = np.outer(np.cos(t), x) + np.outer(np.sin(t), y)
    return float((proj.max(axis=1) - proj.min(axis=1)).min() - rho * np.pi / m)


def box_distance_bounds(cx, cy, h, xs, ys):
    """Least and greatest distances (K, M) from the K square boxes (centres cx, cy, half-side h) to the
    M points (xs, ys), and the distances from the box centres."""
    dx = np.abs(xs[None, :] - cx[:, None])
    dy = np.abs(ys[None, :] - cy[:, None])
    dmin = np.hypot(np.maximum(dx - h, 0.0), np.maximum(dy - h, 0.0))
    dmax = np.hypot(dx + h, dy + h)
    return dmin, dmax, np.hypot(dx, dy)


#: boxes x working points per block of :func:`box_values` (at least; N / 8 for larger data)
BOX_BLOCK = 1024


def box_values(cx, cy, h, xs, ys, zone: bool, budget: int):
    """For each box, a lower bound of the zone width over it (``zone``; the distance intervals and
    :func:`pair_bound`) or an upper bound of the inscribed radius (the least greatest distance), and the value
    at its centre; computed for blocks of boxes of at most ``budget`` box-point pairs (memory), the same
    numbers as for all boxes at once."""
    k = len(cx)
    bound, centre = np.empty(k), np.empty(k)
    step = max(1, budget // max(len(xs), 1))
    for s in range(0, k, step):
        b = slice(s, s + step)
        dmin, dmax, dc = box_distance_bounds(cx[b], cy[b], h, xs, ys)
        if zone:
            np.maximum(dmin.max(axis=1) - dmax.min(axis=1), pair_bound(cx[b], cy[b], h, xs, ys, dc), out=bound[b])
            centre[b] = dc.max(axis=1) - dc.min(axis=1)
        else:
            dmax.min(axis=1, out=bound[b])
            dc.min(axis=1, out=centre[b])
    return bound, centre


def pair_bound(cx, cy, h, xs, ys, dc, k: int = 4):
    """A first-order lower bound of the width over each box, from pairs (i outer, j inner) of the k
    farthest and k nearest working points about the box centre c_B (|d| = |c - c_B| <= sqrt(2) h):
    r_i(c) >= D_i - e_i.d (convexity) and r_j(c) <= D_j - e_j.d + |d|^2 / (2 (D_j - |d|)), so
    width(c) >= r_i - r_j >= D_i - D_j - h |e_i - e_j|_1 - h^2 / (D_j - sqrt(2) h).
    Much tighter than the distance intervals when i and j are seen in similar directions (short arcs)."""
    m = dc.shape[1]
    k = min(k, m)
    if k < 1:
        return np.full(len(cx), -np.inf)
    rows = np.arange(len(cx))[:, None]
    far = np.argpartition(dc, m - k, axis=1)[:, m - k:]
    near = np.argpartition(dc, k - 1, axis=1)[:, :k]
    Di, Dj = dc[rows, far], dc[rows, near]                     # (K, k)
    with np.errstate(divide="ignore", invalid="ignore"):
        exi, eyi = (xs[far] - cx[:, None]) / Di, (ys[far] - cy[:, None]) / Di
        exj, eyj = (xs[near] - cx[:, None]) / Dj, (ys[near] - cy[:, None]) / Dj
        room = Dj - np.sqrt(2.0) * h
        quad = np.where(room > 0, h * h / room, np.inf)
        lb = (Di[:, :, None] - Dj[:, None, :]
              - h * (np.abs(exi[:, :, None] - exj[:, None, :]) + np.abs(eyi[:, :, None] - eyj[:, None, :]))
              - quad[:, None, :])
    lb = np.where(np.isfinite(lb), lb, -np.inf)
    return lb.reshape(len(cx), -1).max(axis=1)


@dataclass
class Outcome:
    certified: bool
    better: np.ndarray | None = None       # a centre that beats the incumbent (the local optimum is not global)
    reason: str = ""
    boxes: int = 0
    levels: int = 0
    full_passes: int = 0
    working_set: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.intp))


class ProfilePolygon:
    """The points joined in angular order about the centroid (the origin of the unit frame), built on
    first use."""

    def __init__(self, x, y):
        self.x, self.y = x, y
        self._path = None

    def _build(self):
        """The closed vertex list (N + 1 rows, the first repeated last), once: the path, and the edges' starts
        ``_a`` and ends ``_b`` as views of it (no rolled copy)."""
        if self._path is None:
            order = np.argsort(np.arctan2(self.y, self.x))
            V = np.empty((len(order) + 1, 2))
            np.take(self.x, order, out=V[:-1, 0])
            np.take(self.y, order, out=V[:-1, 1])
            V[-1] = V[0]
            self._path = V
            self._a, self._b = V[:-1], V[1:]
        return self._path

    def contains(self, C: np.ndarray) -> np.ndarray:
        """Inside the polygon by the even-odd crossing rule (a ray towards +x), over blocks of centres x edges
        of at most max(512, N/8) pairs: the temporaries stay a fraction of the points' memory at any N."""
        self._build()
        a, b = self._a, self._b
        C = np.asarray(C, dtype=float)
        n = len(a)
        budget = max(512, n // 8)
        E = min(n, budget)
        R = max(1, budget // E)
        crossings = np.zeros(len(C), dtype=np.intp)
        for s in range(0, len(C), R):
            px, py = C[s:s + R, 0:1], C[s:s + R, 1:2]
            for e in range(0, n, E):
                ax, ay, bx, by = a[e:e + E, 0], a[e:e + E, 1], b[e:e + E, 0], b[e:e + E, 1]
                dy = by - ay
                slope = np.divide(bx - ax, dy, out=np.zeros_like(dy), where=dy != 0)
                straddles = (ay > py) != (by > py)
                crossings[s:s + R] += np.count_nonzero(straddles & (px < ax + (py - ay) * slope), axis=1)
        return crossings % 2 == 1

    def boundary_distance(self, C: np.ndarray) -> np.ndarray:
        """Distance from each centre to the polygon's boundary (all edges; vectorised)."""
        self._build()
        a, b = self._a, self._b
        ab = b - a
        L2 = np.maximum((ab * ab).sum(axis=1), 1e-300)
        out = np.empty(len(C))
        for s in range(0, len(C), 256):
            P = C[s:s + 256]
            t = np.clip(((P[:, None, 0] - a[None, :, 0]) * ab[None, :, 0] +
                         (P[:, None, 1] - a[None, :, 1]) * ab[None, :, 1]) / L2[None, :], 0.0, 1.0)
            qx = a[None, :, 0] + t * ab[None, :, 0] - P[:, None, 0]
            qy = a[None, :, 1] + t * ab[None, :, 1] - P[:, None, 1]
            out[s:s + 256] = np.sqrt((qx * qx + qy * qy).min(axis=1))
        return out


def branch_and_bound(x, y, *, kind: str, c0, f0: float, S, ball: float, region: float, eps: float,
                     polygon: ProfilePolygon | None = None) -> Outcome:
    """Prove that no centre in the disc |c| <= region beats the incumbent (c0, f0) by more than eps,
    or find a centre that does. ``kind``: "zone" (minimise max r - min r) or "inscribed" (maximise
    min r over centres inside ``polygon``). Boxes inside the ball |c - c0| <= ``ball`` are known not
    to beat f0 (the local bound of the module docstring)."""
    zone = kind == "zone"
    S = np.unique(np.asarray(S, dtype=np.intp))
    xs, ys = x[S], y[S]
    budget = max(BOX_BLOCK, len(x) // 8)  # numbers per (boxes x working points) array: peak memory
    g = 8
    h = region / g
    ticks = -region + h * (2 * np.arange(g) + 1)
    cx, cy = (a.ravel() for a in np.meshgrid(ticks, ticks))
    boxes = full = 0
    for level in range(MAX_LEVELS):
        # discard boxes outside the region disc or inside the certified ball
        far = np.hypot(np.maximum(np.abs(cx) - h, 0.0), np.maximum(np.abs(cy) - h, 0.0)) >= region
        near = np.hypot(np.abs(cx - c0[0]) + h, np.abs(cy - c0[1]) + h) <= ball
        keep = ~(far | near)
        cx, cy = cx[keep], cy[keep]
        boxes += cx.size
        while True:
            bound, centre_val = box_values(cx, cy, h, xs, ys, zone, budget)
            if zone:
                keep = bound < f0 - eps
                suspect = keep & (centre_val < f0 - eps)
            else:
                keep = bound > f0 + eps
                suspect = keep & (centre_val > f0 + eps)
                if suspect.any():  # a candidate centre must lie inside the profile
                    idx = np.flatnonzero(suspect)
                    suspect[idx[~polygon.contains(np.column_stack([cx[idx], cy[idx]]))]] = False
            if not suspect.any():
                break
            j = int(np.flatnonzero(suspect)[np.argmin(centre_val[suspect]) if zone else np.argmax(centre_val[suspect])])
            c = np.array([cx[j], cy[j]])
            dx, dy = x - c[0], y - c[1]
            r = np.sqrt(dx * dx + dy * dy)
            full += 1
            val = r.max() - r.min() if zone else r.min()
            if (val < f0 - eps) if zone else (val > f0 + eps):
                return Outcome(False, better=c, reason="a better centre was found", boxes=boxes, levels=level,
                               full_passes=full, working_set=S)
            new = [int(np.argmax(r)), int(np.argmin(r))] if zone else [int(np.argmin(r))]
            S = np.union1d(S, new)
            xs, ys = x[S], y[S]
            if full >= MAX_FULL_PASSES:
                return Outcome(False, reason=f"the working set did not settle within {MAX_FULL_PASSES} passes",
                               boxes=boxes, levels=level, full_passes=full, working_set=S)
        cx, cy = cx[keep], cy[keep]
        if not zone and cx.size:  # boxes wholly outside the profile polygon hold no admissible centre
            C = np.column_stack([cx, cy])
            out = ~polygon.contains(C)
            if out.any():
                idx = np.flatnonzero(out)
                wholly = polygon.boundary_distance(C[idx]) > h * np.sqrt(2.0) * (1 + 1e-12)
                drop = np.zeros(cx.size, dtype=bool)
                drop[idx[wholly]] = True
                cx, cy = cx[~drop], cy[~drop]
        if not cx.size:
            return Outcome(True, boxes=boxes, levels=level + 1, full_passes=full, working_set=S)
        if cx.size * 4 > MAX_BOXES:
            return Outcome(False, reason=f"more than {MAX_BOXES} boxes remain open at level {level}",
                           boxes=boxes, levels=level + 1, full_passes=full, working_set=S)
        h *= 0.5
        cx = np.concatenate([cx - h, cx + h, cx - h, cx + h])
        cy = np.concatenate([cy - h, cy - h, cy + h, cy + h])
    return Outcome(False, reason=f"boxes remain open after {MAX_LEVELS} bisection levels (half-side {h:.1e})",
                   boxes=boxes, levels=MAX_LEVELS, full_passes=full, working_set=S)


def resolution(f: float, r_max: float) -> float:
    """eps of the certificate (unit frame): EPS_REL f + EPS_ABS + 4 TIE_REL r_max (the tied contacts'
    radii differ by up to TIE_REL r_max, which the local ball bound may lose twice)."""
    return EPS_REL * abs(f) + EPS_ABS + 4 * TIE_REL * r_max


def _tied(r: np.ndarray):
    """Indices of the tied outer and inner contacts (within TIE_REL x max r of the extreme radii)."""
    tol = TIE_REL * r.max()
    return np.flatnonzero(r >= r.max() - tol), np.flatnonzero(r <= r.min() + tol)


def _unit_directions(x, y, idx, c):
    d = np.column_stack([x[idx] - c[0], y[idx] - c[1]])
    return d / np.hypot(d[:, 0], d[:, 1])[:, None]


def alternating_contacts(x, y, c, O, I, hulls_meet, limit: int = 12, normalise: bool = True):
    """An alternating choice among the tied contacts: (outer, inner) index tuples whose directions'
    convex hulls meet (2 + 2, 3 + 1 or 1 + 3; for the MIC, O is empty and the hull of 2 or 3 inner
    contacts must hold the centre), or None. Searches the ``limit`` most extreme ties of each side."""
    from itertools import combinations
    O, I = list(O[:limit]), list(I[:limit])
    vec = _unit_directions if normalise else (lambda x, y, idx, c: np.column_stack([x[idx] - c[0], y[idx] - c[1]]))
    EO = dict(zip(O, vec(x, y, O, c))) if O else {}
    EI = dict(zip(I, vec(x, y, I, c)))
    if not O:
        for m in (2, 3):
            for t in combinations(I, m):
                if hulls_meet(np.array([EI[i] for i in t]), np.zeros((1, 2))):
                    return (), tuple(int(i) for i in t)
        return None
    for mo, mi in ((2, 2), (3, 1), (1, 3)):
        for to in combinations(O, mo):
            for ti in combinations(I, mi):
                if set(to) & set(ti):
                    continue
                if hulls_meet(np.array([EO[i] for i in to]), np.array([EI[i] for i in ti])):
                    return tuple(int(i) for i in to), tuple(int(i) for i in ti)
    return None


def _value(x, y, c, zone):
    r = radii(x, y, c)
    return (r.max() - r.min() if zone else r.min()), r


def _first_hit(x, y, c, u, p1):
    """Along c + t u (t > 0), the first t at which some point becomes as near as p1 (the nearest point
    at c; |c + t u - p_i|^2 - |c + t u - p_1|^2 is linear in t), and that point."""
    gx, gy = x - x[p1], y - y[p1]
    slope = 2 * (u[0] * gx + u[1] * gy)                        # decrease rate of the squared-distance gap
    gap = (x - c[0]) ** 2 + (y - c[1]) ** 2 - ((x[p1] - c[0]) ** 2 + (y[p1] - c[1]) ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(slope > 0, gap / slope, np.inf)
    t[p1] = np.inf
    j = int(np.argmin(t))
    return float(t[j]), j


def polish_inscribed(x, y, c, polygon: ProfilePolygon, steps: int = 12):
    """Grow the empty circle from an admissible centre c to the exact local MIC nearby: move directly
    away from the nearest point until a second is as near, then along their bisector (away from both)
    until a third is; while the contacts do not surround the centre, continue along the bisector of the
    pair that leaves the obtuse contact behind. Each step is one vectorised pass. Returns (centre,
    radius); the start itself if the walk leaves the profile polygon or does not improve."""
    c0 = np.asarray(c, dtype=float)
    f0, r = _value(x, y, c0, False)
    c = c0.copy()
    p1 = int(np.argmin(r))
    u = c - np.array([x[p1], y[p1]])
    if not np.hypot(*u) > 0:
        return c0, f0
    u /= np.hypot(*u)
    t, p2 = _first_hit(x, y, c, u, p1)
    if not np.isfinite(t):
        return c0, f0
    c = c + t * u
    pair = (p1, p2)
    for _ in range(steps):
        a, b = pair
        v = np.array([-(y[b] - y[a]), x[b] - x[a]])
        length = np.hypot(*v)
        if not length > 0:  # the two contacts coincide (repeated points): no bisector to walk along
            break
        v /= length
        if v @ (c - 0.5 * np.array([x[a] + x[b], y[a] + y[b]])) < 0:
            v = -v                                                  # away from the pair's midpoint
        t, p3 = _first_hit(x, y, c, v, a)
        if not np.isfinite(t):
            break
        c = c + t * v
        E = np.array([[x[i] - c[0], y[i] - c[1]] for i in (a, b, p3)])
        E /= np.hypot(E[:, 0], E[:, 1])[:, None]
        if growth_rate(E, None) > 0:                                # the three contacts surround c: a local MIC
            break
        # keep the pair whose bisector leads on: drop the contact the other two see across the centre
        pair = max(((a, p3), (b, p3), (a, b)), key=lambda q: -(E[[a, b, p3].index(q[0])] @ E[[a, b, p3].index(q[1])]))
    f, _ = _value(x, y, c, False)
    if f > f0 and polygon.contains(c[None, :])[0]:
        return c, f
    return c0, f0


def _sector_rerun(rerun, start, solver_failure):
    """``rerun(start)`` with the extreme points of RESTART_SECTORS angular sectors in its first active set, or None
    when its convex program fails (raises ``solver_failure``: the centre the branch and bound found stands then)."""
    try:
        return rerun(start, sectors=RESTART_SECTORS)
    except solver_failure:
        return None


def globalise(x, y, *, kind, c, contacts, ok, message, stats, rerun, hulls_meet, scale, shift=None,
              unit="data units", solver_failure: type[Exception]):
    """The global stage of :mod:`methods.circle._zone`'s fits (see the module docstring).

    ``rerun(start)`` runs the local solver from another start and returns what
    ``active_set_fit`` returns, or raises ``solver_failure`` when its convex program fails. Returns (centre, contacts, converged, certified, message, info) with
    certified one of "global", "local", False. With the frame's ``shift``, the centre is also chosen among the
    float centres in data units (:func:`float_centre`): ``info["center_data"]`` is the one to return, ``centre``
    its unit-frame image, and ``info["bound"]`` (data units, certified "global" only) what the message states:
    the zone about the returned centre exceeds the optimum's (the empty circle falls short of it) by at most that."""
    zone = kind == "zone"
    polygon = None if zone else ProfilePolygon(x, y)
    S = np.asarray(stats.get("active", np.empty(0, dtype=np.intp)), dtype=np.intp)
    # the points extreme along x, y, x + y, x - y: they keep the working set's extent (far-field bound) honest
    ext = [f(v) for v in (x, y, x + y, x - y) for f in (np.argmax, np.argmin)]
    S = np.union1d(S, ext)
    info = {"boxes": 0, "full_passes": 0, "restarts": 0, "region": None}
    valid = True
    if not zone and not polygon.contains(np.asarray(c, dtype=float)[None, :])[0]:
        valid = False  # the local centre is outside the profile: not an admissible MIC
    outcome = None
    for attempt in range(MAX_RESTARTS + 1):
        f, r = _value(x, y, c, zone)
        if zone and f <= 1e-11:
            outcome = Outcome(True, reason="zero width")
            info["region"] = "all of R^2 (a zone of zero width)"
            break
        rho = float(np.hypot(c[0], c[1]) + r.max())  # >= max |p_i| about the centroid (the origin)
        O, I = _tied(r)
        if not valid:
            f0, ball = 0.0, 0.0
        elif zone:
            kappa = growth_rate(-_unit_directions(x, y, O, c), _unit_directions(x, y, I, c))
            r_in = r.min()
            ball = 0.9 * 2 * kappa * r_in / (1 + 2 * kappa) if kappa > 0 else 0.0
            f0 = f
        else:
            kappa = growth_rate(_unit_directions(x, y, I, c), None)
            ball = 0.9 * 2 * kappa * f / (1 + 2 * kappa) if kappa > 0 else 0.0
            f0 = f
        eps = resolution(f0, r.max())
        if zone:
            W = least_width_exact(x[S], y[S])  # a subset's least width bounds the data's from below
            if W > f0:
                region = rho + rho * rho / (2 * (W - f0 + eps))
                info["region"] = "all of R^2"
            else:
                region = FALLBACK_RADIUS * rho
                info["region"] = (f"centres within {region * scale:.6g} {unit} of the centroid (the points are nearly "
                                  "straight: a straight zone at infinity is about as narrow)")
        else:
            region = rho
            info["region"] = "centres inside the profile polygon (points joined in angular order about their centroid)"
        r = None  # the radii are not held during the branch and bound (peak memory)
        outcome = branch_and_bound(x, y, kind=kind, c0=np.asarray(c, dtype=float), f0=f0, S=S, ball=ball,
                                   region=region, eps=eps, polygon=polygon)
        info["boxes"] += outcome.boxes
        info["full_passes"] += outcome.full_passes
        S = outcome.working_set
        if outcome.better is None:
            break
        if attempt == MAX_RESTARTS:  # no restart left: return the better centre found, never the one it beats
            c, contacts, ok, message, valid = outcome.better, ((), ()), False, "centre from the branch and bound", True
            outcome = Outcome(False, reason=f"the branch and bound still found better centres after {MAX_RESTARTS} "
                                            "restarts of the local solver (the best centre found is returned)")
            break
        info["restarts"] += 1
        fb, _ = _value(x, y, outcome.better, zone)
        if not zone:  # the MIC's local LP can walk out of a lobed profile: climb by exact candidates; and restart
            # the LP with the extreme points of every angular sector in its active set (they surround the centre)
            cp, fp = polish_inscribed(x, y, outcome.better, polygon)
            second = _sector_rerun(rerun, outcome.better, solver_failure)
            c2, contacts2, ok2, message2, stats2 = second or (cp, ((), ()), False, "", {})
            f2, _ = _value(x, y, c2, zone)
            if f2 > max(fb, fp) and polygon.contains(np.asarray(c2, dtype=float)[None, :])[0]:
                c, contacts, ok, message, valid = c2, contacts2, ok2, message2, True
                S = np.union1d(S, stats2.get("active", []))
            else:
                c, contacts, ok, message, valid = cp, ((), ()), False, "polished from the branch and bound", True
            continue
        c2, contacts2, ok2, message2, stats2 = rerun(outcome.better)
        f2, _ = _value(x, y, c2, zone)
        if f2 > fb:  # walked off: on a dense smooth profile the k most extreme radii are neighbours of one peak and
            # one valley, and the sub-problem on them narrows towards a straight zone; restart with the extreme
            # points of every angular sector in the active set too (they surround the centre)
            second = _sector_rerun(rerun, outcome.better, solver_failure)
            f3 = _value(x, y, second[0], zone)[0] if second is not None else np.inf
            if f3 < f2:
                (c2, contacts2, ok2, message2, stats2), f2 = second, f3
        inside2 = zone or polygon.contains(np.asarray(c2, dtype=float)[None, :])[0]
        if inside2 and ((f2 <= fb) if zone else (f2 >= fb)):
            c, contacts, ok, message = c2, contacts2, ok2, message2
            S = np.union1d(S, stats2.get("active", []))
        else:  # keep the better centre itself (no exact contact configuration there)
            c, contacts, ok, message = outcome.better, ((), ()), False, "centre from the branch and bound"
        valid = True
    exact_note = ""
    overlay = zone and EXACT_MAX_POINTS < len(x) <= OVERLAY_MAX_POINTS
    if outcome is not None and not outcome.certified and (len(x) <= EXACT_MAX_POINTS or overlay):
        cb, fb = overlay_enumeration(x, y) if overlay else exact_enumeration(x, y, kind, polygon)
        f, _ = _value(x, y, c, zone)
        if cb is not None and ((fb < f) if zone else (fb > f or not valid)):
            c, contacts, ok, message, valid = cb, ((), ()), False, "exact enumeration", True
            f = fb
        if zone:
            W = least_width_exact(x, y)  # minus its rounding: a strict lower bound of the straight zones' width
            W -= WIDTH_ROUNDING * np.finfo(float).eps * max(float(np.abs(x).max()), float(np.abs(y).max()))
            if f < W:
                outcome = Outcome(True)
                info["region"] = "all of R^2"
            else:
                outcome = Outcome(False, reason=("every finite centre is beaten by a straight zone (centre at "
                                                 f"infinity): least strip width {W * scale:.6g} {unit}"))
        elif valid:
            outcome = Outcome(True)
        exact_note = (" by exact enumeration of the Voronoi-overlay vertices" +
                      (" (nearest- and farthest-point diagrams by Qhull)" if overlay else "") +
                      " (branch and bound inconclusive)")
        info["exact_enumeration"] = True
    r = None  # the loop's radii are not held while the final ones are computed (peak memory)
    f, r = _value(x, y, c, zone)
    O, I = _tied(r)
    alt = alternating_contacts(x, y, c, O if zone else np.empty(0, dtype=np.intp), I, hulls_meet)
    if alt is not None:
        contacts = alt
    elif zone and f <= 1e-11:
        pass
    local = valid and (alt is not None or bool(ok) or (zone and f <= 1e-11))
    what = "zone narrower" if zone else "empty circle larger"
    cost, searched = 0.0, False
    if valid and shift is not None:
        centre_data, c, cost, searched = float_centre(x, y, c, f, r, shift, scale, zone, polygon)
        info["center_data"] = centre_data
    if valid and outcome is not None and outcome.certified:
        certified = "global"
        # the certificate's resolution (a zero zone: width >= 0), the centre's float resolution and the rounding
        # of the unit-frame coordinates (points and centre, :data:`FRAME_ROUNDING`)
        rho = float(np.hypot(c[0], c[1]) + r.max())
        rounding = FRAME_ROUNDING * np.finfo(float).eps * rho
        eps = (resolution(f, r.max()) + (f if zone and f <= 1e-11 else 0.0) + max(cost, 0.0) + rounding) * scale
        eps = round_up(eps)
        info["bound"] = eps
        centre_note = (f"; of which {max(cost, 0.0) * scale:.2g} {unit} for the centre's float resolution (the best of "
                       f"the {(2 * FLOAT_STEPS + 1) ** 2} float centres about the optimum)" if searched else "")
        if zone and f <= 1e-11:
            msg = (f"certified global optimum: the points lie on one circle (zone width {f * scale:.2g} {unit}, at "
                   f"rounding level; no zone is narrower than 0, none than this one's by more than {eps:.3g} {unit}"
                   f"{centre_note})")
        else:
            msg = (f"certified global optimum over {info['region']}{exact_note}: no centre there gives a {what} than "
                   f"the returned centre by more than {eps:.3g} {unit}{centre_note} (branch and bound over the centre: "
                   f"{info['boxes']} boxes, {info['full_passes']} extra passes over the points")
            msg += f", local solver restarted {info['restarts']} time(s) from better centres)" if info["restarts"] else ")"
        if f > 1e-11:
            msg += ("; contacts alternate" if alt is not None else
                    "; the contacts found do not alternate (a tie the local test cannot resolve)")
    elif local:
        certified = "local"
        msg = (f"local optimum only (tied contacts alternate: {'conv(outer) meets conv(inner) directions' if zone else 'the contacts surround the centre'}); "
               f"no global certificate: {outcome.reason if outcome is not None else 'not attempted'}")
    else:
        certified = False
        msg = message if valid else "no admissible centre inside the profile was found"
        msg += f"; no global certificate: {outcome.reason if outcome is not None else 'not attempted'}"
    info.pop("region") if info["region"] is None else None
    return c, contacts, certified in ("global", "local"), certified, msg, info


#: float neighbours per coordinate either side of the rounded data centre searched by :func:`float_centre`
FLOAT_STEPS = 3
#: the search runs when the centre's rounding could cost more than this fraction of the certificate's resolution
FLOAT_SEARCH_REL = 0.05
#: the unit-frame coordinates of the points and of a centre are (p - shift) / scale rounded twice: each distance
#: is off by at most 4 eps (|p| + |c|) <= 8 eps rho, a width (two distances) by 16 eps rho
FRAME_ROUNDING = 16


def float_centre(x, y, c, f, r, shift, scale, zone: bool, polygon: ProfilePolygon | None = None):
    """The centre to return in data units for the unit-frame centre ``c`` (value ``f``, radii ``r``): the best of the
    (2 FLOAT_STEPS + 1)^2 float pairs nearest ``c scale + shift``, each evaluated in the unit frame (centred on the
    data: its image (p - shift) / scale is exact to a few eps of the data's size). Far from the origin the data-unit
    centre's own resolution (an ulp of its coordinates) can exceed the certificate's: rounding ``c scale + shift``
    to the nearest floats moves it by up to half an ulp a coordinate, which can widen the zone by up to
    |grad width| <= 2 times that (1 for the MIC's radius), and the nearest float is not always the best one.

    Only the points whose radius about c is within the candidates' reach (2 x their largest distance from c) of the
    extreme radii can be extreme about a candidate, so the candidates are evaluated on those alone (exactly the
    values over all points). Returns (centre in data units, its unit-frame image, cost, searched) with cost =
    value(returned) - f (zone: wider; MIC: smaller circle), or its a-priori bound when not searched, which the
    certificate's bound adds."""
    c = np.asarray(c, dtype=float)
    base = c * scale + shift
    if not np.isfinite(base).all():
        return base, c, 0.0, False
    # rounding c scale + shift moves the centre by at most half an ulp a coordinate plus eps |c scale|: the zone
    # widens by at most twice that. Where this a-priori cost is below FLOAT_SEARCH_REL of the certificate's
    # resolution (data within ~100 radii of the origin), the rounded centre is returned with it, unsearched.
    apriori = float(np.hypot(*np.spacing(np.abs(base))) + 4 * np.finfo(float).eps * np.hypot(*(c * scale))) / scale
    if apriori <= FLOAT_SEARCH_REL * resolution(f, float(r.max())):
        return base, c, apriori, False
    grid_x = _float_steps(base[0], FLOAT_STEPS)
    grid_y = _float_steps(base[1], FLOAT_STEPS)
    X, Y = np.meshgrid(grid_x, grid_y)
    cand = np.column_stack([X.ravel(), Y.ravel()])
    U = (cand - shift) / scale
    reach = float(np.hypot(U[:, 0] - c[0], U[:, 1] - c[1]).max())
    slack = 2 * reach + 1e-14 * float(r.max())
    near = np.flatnonzero(r <= r.min() + slack)
    if zone:
        near = np.union1d(np.flatnonzero(r >= r.max() - slack), near)
    R = np.hypot(x[near][None, :] - U[:, 0:1], y[near][None, :] - U[:, 1:2])
    val = R.max(axis=1) - R.min(axis=1) if zone else -R.min(axis=1)
    for j in np.argsort(val, kind="stable"):  # the MIC's centre must lie in the profile polygon (one test, rarely more)
        if not np.isfinite(val[j]):
            break
        if zone or polygon.contains(U[j:j + 1])[0]:
            return cand[j], U[j], float(val[j] - f) if zone else float(f + val[j]), True
    return base, c, apriori, False


def round_up(v: float, digits: int = 3) -> float:
    """v rounded up to ``digits`` significant digits: printed with that many, it is still a bound."""
    if not (np.isfinite(v) and v > 0):
        return v
    step = 10.0 ** (np.floor(np.log10(v)) - (digits - 1))
    return float(np.ceil(v / step * (1 + 1e-15)) * step)


def _float_steps(v: float, k: int) -> np.ndarray:
    """The 2k + 1 consecutive floats centred on v."""
    lo, hi = [v], [v]
    for _ in range(k):
        lo.append(np.nextafter(lo[-1], -np.inf))
        hi.append(np.nextafter(hi[-1], np.inf))
    return np.array(lo[:0:-1] + hi)


#: below this many points a failed branch and bound falls back to the exact enumeration
EXACT_MAX_POINTS = 60


def _equidistant(a, b, c, d):
    """Centres z with |z - a| = |z - b| and |z - c| = |z - d| (rows; non-finite when parallel)."""
    n1, n2 = b - a, d - c
    h1 = 0.5 * ((b * b).sum(axis=1) - (a * a).sum(axis=1))
    h2 = 0.5 * ((d * d).sum(axis=1) - (c * c).sum(axis=1))
    det = n1[:, 0] * n2[:, 1] - n1[:, 1] * n2[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.column_stack([(h1 * n2[:, 1] - n1[:, 1] * h2) / det, (n1[:, 0] * h2 - h1 * n2[:, 0]) / det])


def exact_enumeration(x, y, kind: str, polygon: ProfilePolygon | None = None):
    """The exact global optimum for small N (Voronoi-overlay vertices enumerated directly).

    Minimum zone: the optimum over R^2, when attained, has four active contacts: 2 + 2 (the two
    bisectors meet: a vertex of the overlay of the nearest- and farthest-point Voronoi diagrams),
    3 + 1 or 1 + 3 (a circumcentre). MIC over the profile polygon: a Voronoi vertex (circumcentre)
    inside the polygon, or a bisector of two points crossing a polygon edge. Returns (centre, value)."""
    from itertools import combinations
    P = np.column_stack([x, y])
    n = len(P)
    tri = np.array(list(combinations(range(n), 3)), dtype=np.intp)
    C = [_equidistant(P[tri[:, 0]], P[tri[:, 1]], P[tri[:, 1]], P[tri[:, 2]])]
    if kind == "zone":
        q = np.array(list(combinations(range(n), 4)), dtype=np.intp)
        for (i, j), (k, l) in (((0, 1), (2, 3)), ((0, 2), (1, 3)), ((0, 3), (1, 2))):
            C.append(_equidistant(P[q[:, i]], P[q[:, j]], P[q[:, k]], P[q[:, l]]))
    else:
        polygon._build()
        a, b = polygon._a, polygon._b
        pr = np.array(list(combinations(range(n), 2)), dtype=np.intp)
        A = np.repeat(pr, len(a), axis=0)
        E = np.tile(np.arange(len(a)), len(pr))
        u, v = P[A[:, 0]], P[A[:, 1]]
        s0, s1 = a[E], b[E]
        nrm = v - u
        den = (nrm * (s1 - s0)).sum(axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (0.5 * ((v * v).sum(axis=1) - (u * u).sum(axis=1)) - (nrm * s0).sum(axis=1)) / den
        ok = np.isfinite(t) & (t >= 0) & (t <= 1)
        edge_pts = s0[ok] + t[ok, None] * (s1[ok] - s0[ok])
    C = np.vstack(C)
    C = C[np.isfinite(C).all(axis=1)]
    if kind != "zone":
        C = C[polygon.contains(C)]
        C = np.vstack([C, edge_pts])
    best_c, best = None, np.inf if kind == "zone" else -np.inf
    for s in range(0, len(C), 4096):
        B = C[s:s + 4096]
        R = np.hypot(x[None, :] - B[:, 0:1], y[None, :] - B[:, 1:2])
        val = R.max(axis=1) - R.min(axis=1) if kind == "zone" else R.min(axis=1)
        j = int(np.argmin(val) if kind == "zone" else np.argmax(val))
        if (val[j] < best) if kind == "zone" else (val[j] > best):
            best, best_c = float(val[j]), B[j]
    return best_c, best


#: largest N for which a minimum zone the branch and bound leaves open is decided by :func:`overlay_enumeration`
OVERLAY_MAX_POINTS = 5000


def _bisector_edges(P, simplices, neighbours, ok, cc, outward: bool):
    """The Voronoi edges dual to the triangulation ``simplices`` (rows of point indices; ``ok`` marks the
    triangles of this diagram, ``cc`` their circumcentres): for each pair of adjacent triangles the segment
    between their circumcentres, and for each triangle side without a neighbour in the diagram the ray from the
    circumcentre along the side's normal (``outward``: away from the triangle's third vertex, as the nearest-point
    diagram's unbounded edges go; else towards it, as the farthest-point diagram's). Returns the two sites of each
    edge (E, 2), its origin (E, 2), direction (E, 2) and whether it is a ray (E,)."""
    sites, origin, direction, ray = [], [], [], []
    idx = np.flatnonzero(ok)
    for k in range(3):
        i, j = simplices[idx, (k + 1) % 3], simplices[idx, (k + 2) % 3]
        nb = neighbours[idx, k]
        inner = (nb >= 0) & ok[np.maximum(nb, 0)] & (nb > idx)
        sites.append(np.column_stack([i[inner], j[inner]]))
        origin.append(cc[idx[inner]])
        direction.append(cc[nb[inner]] - cc[idx[inner]])
        ray.append(np.zeros(inner.sum(), dtype=bool))
        edge = ~((nb >= 0) & ok[np.maximum(nb, 0)])
        e = P[j[edge]] - P[i[edge]]
        n = np.column_stack([-e[:, 1], e[:, 0]])
        towards = ((P[simplices[idx[edge], k]] - P[i[edge]]) * n).sum(axis=1) > 0
        flip = towards if outward else ~towards
        n[flip] *= -1.0
        sites.append(np.column_stack([i[edge], j[edge]]))
        origin.append(cc[idx[edge]])
        direction.append(n)
        ray.append(np.ones(edge.sum(), dtype=bool))
    return np.vstack(sites), np.vstack(origin), np.vstack(direction), np.concatenate(ray)


def overlay_enumeration(x, y):
    """The minimum zone's global optimum over the finite centres, from the overlay of the nearest- and the
    farthest-point Voronoi diagrams (Qhull, through scipy.spatial): the optimum centre is a vertex of either
    diagram or a crossing of an edge of one with an edge of the other (Roy & Zhang, Comput.-Aided Des. 24 (1992)
    161-168; Le & Lee, CAD 23 (1991) 591-599), where its nearest and farthest points are the sites of the two
    edges. Every crossing's width |z - p_far| - |z - p_near| is computed from those sites (O(1)); the candidates
    are then evaluated over all points in increasing order of that width until it exceeds the best width found
    (a crossing's own width is its true width), the diagrams' vertices over all points. Cocircular points (a
    degenerate lifted hull) are triangulated from Qhull's joggled input; every candidate is still evaluated on the
    true points. Returns (centre, width), or (None, inf) when Qhull cannot build the diagrams (collinear points)."""
    from scipy.spatial import ConvexHull, Delaunay, QhullError

    P = np.column_stack([x, y])
    L = np.column_stack([x, y, x * x + y * y])
    near = far = None
    for options in (None, "QJ"):  # cocircular points lift to a plane: then Qhull's joggled input (QJ)
        try:
            near = Delaunay(P, qhull_options=options)
            far = ConvexHull(L, qhull_options=options)
            break
        except (QhullError, ValueError):
            near = far = None
    if near is None:
        return None, np.inf
    up = far.equations[:, 2] > 0  # the upper hull of the lifted points: the farthest-point triangulation
    ccn = _equidistant(P[near.simplices[:, 0]], P[near.simplices[:, 1]], P[near.simplices[:, 1]],
                       P[near.simplices[:, 2]])
    ccf = _equidistant(P[far.simplices[:, 0]], P[far.simplices[:, 1]], P[far.simplices[:, 1]], P[far.simplices[:, 2]])
    okn = np.isfinite(ccn).all(axis=1)
    okf = up & np.isfinite(ccf).all(axis=1)
    sn, on, dn, rn = _bisector_edges(P, near.simplices, near.neighbors, okn, ccn, outward=True)
    sf, of, df, rf = _bisector_edges(P, far.simplices, far.neighbors, okf, ccf, outward=False)
    best_c, best = None, np.inf

    def gap(z, a, b):
        """|z - a| - |z - b| as (b - a).(2 z - a - b) / (|z - a| + |z - b|): exact to rounding also for centres far
        from the points (the plain difference of two nearly equal distances loses every digit there)."""
        num = (b[..., 0] - a[..., 0]) * (2 * z[..., 0] - a[..., 0] - b[..., 0]) + \
            (b[..., 1] - a[..., 1]) * (2 * z[..., 1] - a[..., 1] - b[..., 1])
        den = np.hypot(z[..., 0] - a[..., 0], z[..., 1] - a[..., 1]) + np.hypot(z[..., 0] - b[..., 0], z[..., 1] - b[..., 1])
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(den > 0, num / den, 0.0)

    def widths(C):
        """max r - min r at each centre, from the gaps to point 0 (:func:`gap`); non-finite centres get inf."""
        out = np.full(len(C), np.inf)
        for s in range(0, len(C), 256):
            Z = C[s:s + 256]
            g = gap(Z[:, None, :], P[None, :, :], P[None, :1, :])
            w = g.max(axis=1) - g.min(axis=1)
            out[s:s + 256] = np.where(np.isfinite(Z).all(axis=1) & np.isfinite(w), w, np.inf)
        return out

    vertices = np.vstack([ccn[okn], ccf[okf]])
    if len(vertices):
        w = widths(vertices)
        j = int(np.argmin(w))
        if np.isfinite(w[j]):
            best_c, best = vertices[j], float(w[j])
    # crossings of a nearest-point edge (o1 + t d1) with a farthest-point edge (o2 + u d2), t and u within
    # their ranges ([0, 1] for segments, [0, inf) for rays), with a generous slack: an extra candidate costs
    # an evaluation, a missed one the certificate
    slack = 1e-6
    cand, cand_w = [], []
    step = max(1, 2_000_000 // max(len(sf), 1))
    for a in range(0, len(sn), step):
        o1, d1, r1, s1 = on[a:a + step, None, :], dn[a:a + step, None, :], rn[a:a + step, None], sn[a:a + step]
        det = d1[..., 0] * df[None, :, 1] - d1[..., 1] * df[None, :, 0]
        b = of[None, :, :] - o1
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (b[..., 0] * df[None, :, 1] - b[..., 1] * df[None, :, 0]) / det
            u = (b[..., 0] * d1[..., 1] - b[..., 1] * d1[..., 0]) / det
        hit = np.isfinite(t) & np.isfinite(u) & (t >= -slack) & (u >= -slack) & \
            (r1 | (t <= 1 + slack)) & (rf[None, :] | (u <= 1 + slack))
        ia, ib = np.nonzero(hit)
        if not ia.size:
            continue
        z = on[a + ia] + t[ia, ib, None] * dn[a + ia]
        fin = np.isfinite(z).all(axis=1)
        z, ia, ib = z[fin], ia[fin], ib[fin]
        cand.append(z)
        cand_w.append(gap(z, P[sf[ib, 0]], P[s1[ia, 0]]))
    if cand:
        Z, W = np.vstack(cand), np.concatenate(cand_w)
        order = np.argsort(W)
        for s in range(0, len(order), 256):
            block = order[s:s + 256]
            if not W[block[0]] <= best:
                break
            w = widths(Z[block])
            j = int(np.argmin(w))
            if w[j] < best:
                best_c, best = Z[block[j]], float(w[j])
    return best_c, best


def least_width_exact(x, y) -> float:
    """The least width of a point set over all directions (0.0 when Qhull finds the points flat).

    It is attained normal to an edge of the convex hull (Qhull's vertices, counter-clockwise): for each
    edge, rotating calipers (Shamos 1978) find the antipodal vertex, the vertex whose two edges' direction
    angles bracket the edge's angle + pi (one ``searchsorted`` over the unwrapped angles; the two
    vertices either side are taken too, against rounding of the angles). O(h) memory and time for h
    hull vertices. Projections are products and sums, never BLAS, so the value does not depend on the
    CPU. A missed antipode or a vertex Qhull merged away can only lower the value; rounding can raise it
    by a few ulps of the coordinates (``WIDTH_ROUNDING`` eps max|coordinate| bounds that): a caller that needs a
    strict lower bound subtracts it, or compares with a margin larger than it."""
    from scipy.spatial import ConvexHull, QhullError
    P = np.column_stack([x, y])
    if len(P) < 3:
        return 0.0
    try:
        H = P[ConvexHull(P).vertices]
    except QhullError:
        return 0.0
    e = np.roll(H, -1, axis=0) - H
    n = np.hypot(e[:, 0], e[:, 1])
    keep = n > 0
    H, e, n = H[keep], e[keep], n[keep]
    h = len(H)
    if h < 3:
        return 0.0
    nx, ny = -e[:, 1] / n, e[:, 0] / n  # inward (left) unit normals of the counter-clockwise edges
    angle = np.arctan2(e[:, 1], e[:, 0])
    turn = np.diff(angle)
    turn[turn < 0] += 2 * np.pi  # counter-clockwise: every turn between consecutive edges is in (0, pi)
    angle[1:] = angle[0] + np.cumsum(turn)
    turn = np.concatenate([angle, angle + 2 * np.pi, angle[:1] + 4 * np.pi])
    k = np.searchsorted(turn, angle + np.pi)  # vertex k (mod h) starts the first edge turned by >= pi
    cand = (k[:, None] + np.arange(-2, 3)[None, :]) % h
    far = (nx[:, None] * H[cand, 0] + ny[:, None] * H[cand, 1]).max(axis=1)
    ends = np.stack([np.arange(h), (np.arange(h) + 1) % h], axis=1)
    near = (nx[:, None] * H[ends, 0] + ny[:, None] * H[ends, 1]).min(axis=1)
    return float((far - near).min())


#: least_width_exact may exceed the exact least width by at most this many eps times the largest |coordinate|
#: (two rounded products and a sum per projection, a difference of two projections)
WIDTH_ROUNDING = 8
