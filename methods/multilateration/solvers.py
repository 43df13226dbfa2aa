"""Numerical kernels of multilateration (Holub et al., Machines 2022, 10, 833, section 3), vectorised
over stations (step 1) and over points (step 2).

Step 1 locates each station k and its dead path L_k from the nominal points X_i and lengths P_i(k):
||X_i - LT(k)|| = L_k + P_i(k) (eq. 5). Step 2 locates each actual point from the stations:
||X_a,i - LT(k)|| = L_k + P_i(k) (section 3.2). Every kernel takes the lengths as an (N, K) array with NaN
where a station did not see a point.
"""
from __future__ import annotations

import numpy as np

from methods._errors import InvalidInputError


# ---------------------------------------------------------------- condition numbers

def cond_svd(A) -> np.ndarray:
    """2-norm condition number sigma_max / sigma_min of each (stacked) square matrix, by SVD."""
    s = np.linalg.svd(np.asarray(A, float), compute_uv=False)
    with np.errstate(divide="ignore"):
        return s[..., 0] / s[..., -1]


def cond_theorem1(A) -> np.ndarray:
    """The paper's lower estimate of kappa (Theorem 1, after Qi 1984): sigma_max >= the largest row or column
    2-norm and sigma_min <= the smallest one, so kappa >= max(row, column norms) / min(row, column norms)."""
    A = np.asarray(A, float)
    rows = np.linalg.norm(A, axis=-1)
    cols = np.linalg.norm(A, axis=-2)
    hi = np.maximum(rows.max(axis=-1), cols.max(axis=-1))
    lo = np.minimum(rows.min(axis=-1), cols.min(axis=-1))
    with np.errstate(divide="ignore"):
        return hi / lo


def conditioning(A, system: str) -> dict:
    return {"system": system, "svd": cond_svd(A), "theorem1": cond_theorem1(A)}


# ---------------------------------------------------------------- batched Levenberg-Marquardt

def batched_lm(fun, theta0, *, size: float, max_iter: int = 100, xtol: float = 1e-13):
    """Levenberg-Marquardt (a trust-region method, Moré 1978) on B independent small least-squares
    problems at once: ``fun(theta (B, P), active) -> r (B, M), J (B, M, P)`` for the active problems. Returns theta, the normal matrices
    J^T J at the solution, iterations, and a per-problem converged flag (step <= ``xtol`` x (|theta| + ``size``),
    ``size`` a typical length of the problem, so that a solution at the origin converges too)."""
    theta = np.array(theta0, float)
    B, P = theta.shape
    r, J = fun(theta, slice(None))
    cost = np.einsum("bm,bm->b", r, r)
    H = np.einsum("bmp,bmq->bpq", J, J)
    lam = np.full(B, 1e-3)
    done = np.zeros(B, bool)
    it = 0
    eye = np.eye(P)
    for it in range(1, max_iter + 1):
        act = ~done
        if not act.any():
            break
        g = np.einsum("bmp,bm->bp", J[act], r[act])
        Ha = H[act]
        D = np.einsum("bpp->bp", Ha)
        D = np.where(D > 0, D, 1.0)
        A = Ha + lam[act, None, None] * (D[:, :, None] * eye)
        try:
            step = -np.linalg.solve(A, g[..., None])[..., 0]
        except np.linalg.LinAlgError:
            raise InvalidInputError("the geometry is degenerate: a least-squares system is singular "
                                    "(check that stations and points are not coplanar or collinear)") from None
        trial = theta[act] + step
        r_t, J_t = fun(trial, act)
        cost_t = np.einsum("bm,bm->b", r_t, r_t)
        better = cost_t <= cost[act]
        idx = np.flatnonzero(act)
        acc = idx[better]
        theta[acc] = trial[better]
        r[acc], J[acc], cost[acc] = r_t[better], J_t[better], cost_t[better]
        H[acc] = np.einsum("bmp,bmq->bpq", J[acc], J[acc])
        small = np.linalg.norm(step, axis=1) <= xtol * (np.linalg.norm(theta[idx], axis=1) + size)
        # converged: a tiny accepted step, or a tiny rejected one while the damping is mild (the step is then
        # close to the Gauss-Newton step, and the cost only fails to decrease by rounding)
        done[idx[small & (better | (lam[idx] <= 1.0))]] = True
        lam[acc] = np.maximum(lam[acc] / 3.0, 1e-12)
        lam[idx[~better]] *= 4.0
        done[idx[~better & (lam[idx] > 1e20)]] = True    # no further decrease possible at this precision
        done[idx[cost[idx] == 0.0]] = True
    return theta, H, it, done


# ---------------------------------------------------------------- step 1: stations (eq. 7, 8, 11, 12-13)

def _masked(points, lengths):
    """Per-station views: Q (K, N, 3) points, P (K, N) lengths with 0 where missing, w (K, N) mask."""
    w = np.isfinite(lengths).T.astype(float)
    P = np.where(w > 0, lengths.T, 0.0)
    Q = np.broadcast_to(points, (lengths.shape[1],) + points.shape)
    return Q, P, w


def stations_case_a(points, lengths, init, *, squared: bool, max_iter: int = 100):
    """Case A (eq. 7, or eq. 8 with ``squared``): min over (LT(k), L_k) of the sum of squared residuals
    ||X_i - LT(k)|| - (L_k + P_i(k)) (or their squared form), all stations at once."""
    Q, P, w = _masked(points, lengths)

    def fun(theta, act=slice(None)):
        q, p, ww = Q[act], P[act], w[act]
        d = theta[:, None, :3] - q                      # LT - X_i
        rho = theta[:, None, 3] + p
        if squared:
            r = np.einsum("bni,bni->bn", d, d) - rho ** 2
            J = np.concatenate([2 * d, -2 * rho[..., None]], axis=2)
        else:
            t = np.sqrt(np.einsum("bni,bni->bn", d, d))
            r = t - rho
            J = np.concatenate([d / t[..., None], -np.ones_like(t)[..., None]], axis=2)
        return r * ww, J * ww[..., None]

    return batched_lm(fun, init, size=float(np.nanmean(np.abs(lengths))), max_iter=max_iter)


def stations_case_b(points, lengths):
    """Case B (eq. 9-11) as published: the 5 x 5 normal system in (x_LT, y_LT, z_LT, L_k, C_k), unscaled."""
    Q, P, w = _masked(points, lengths)
    V = np.concatenate([Q, P[..., None]], axis=2) * w[..., None]   # (K, N, 4): x_i, y_i, z_i, P_i
    g = (np.einsum("kni,kni->kn", Q, Q) - P ** 2) * w              # |X_i|^2 - P_i^2
    A, b = _extremal_system(V, g, w)
    return _solve(A, b, "Case B station system (eq. 11)")[:, :4], A


def _extremal_system(V, g, w):
    """The paper's 'extremal principle' normal system for unknowns (v, C) of the residuals
    g_i - 2 V_i . v + C, written as printed (eq. 11 and section 3.2): rows [2 sum V V^T, -sum V | sum V g]
    and [sum V, -n / 2 | sum g / 2], stacked over the leading axis."""
    m = V.shape[2]
    A = np.zeros((V.shape[0], m + 1, m + 1))
    A[:, :m, :m] = 2 * np.einsum("bni,bnj->bij", V, V)
    A[:, :m, m] = -V.sum(axis=1)
    A[:, m, :m] = V.sum(axis=1)
    A[:, m, m] = -w.sum(axis=1) / 2
    b = np.concatenate([np.einsum("bni,bn->bi", V, g), 0.5 * g.sum(axis=1)[:, None]], axis=1)
    return A, b


def stations_centred(points, lengths):
    """Case B centred and scaled: the same equations in coordinates centred on the measured points and
    divided by their RMS radius, lengths centred on their mean, solved by QR (never the normal equations)."""
    Q, P, w = _masked(points, lengths)
    n = w.sum(axis=1)
    c0 = np.einsum("kni,kn->ki", Q, w) / n[:, None]
    Xc = (Q - c0[:, None, :]) * w[..., None]
    h = np.sqrt(np.einsum("kni,kni->k", Xc, Xc) / n)
    pbar = (P * w).sum(axis=1) / n
    Xs = Xc / h[:, None, None]
    Ps = (P - pbar[:, None]) * w / h[:, None]
    M = np.concatenate([2 * Xs, 2 * Ps[..., None], -w[..., None]], axis=2)      # (K, N, 5)
    g = (np.einsum("kni,kni->kn", Xs, Xs) - Ps ** 2) * w
    theta = _qr_lstsq(M, g, "centred Case B station system")
    s = c0 + h[:, None] * theta[:, :3]
    L = h * theta[:, 3] - pbar
    return np.column_stack([s, L]), np.einsum("kni,knj->kij", M, M)


def stations_taylor(points, lengths, stations):
    """The first-order correction of eq. 12-13: linearise ||X_i - LT(k)|| about the Case B station and solve
    the 3 x 3 system for (dx, dy, dz) with L_k held."""
    Q, P, w = _masked(points, lengths)
    d = stations[:, None, :3] - Q
    t = np.sqrt(np.einsum("kni,kni->kn", d, d))
    a = d / t[..., None] * w[..., None]
    h = (t - (stations[:, 3][:, None] + P)) * w
    A = np.einsum("kni,knj->kij", a, a)
    b = -np.einsum("kni,kn->ki", a, h)
    delta = _solve(A, b, "Taylor correction system (eq. 13)")
    return np.column_stack([stations[:, :3] + delta, stations[:, 3]]), A


# ---------------------------------------------------------------- step 2: points (section 3.2)

def _rho(stations, lengths):
    w = np.isfinite(lengths).astype(float)
    rho = np.where(w > 0, stations[None, :, 3] + np.where(w > 0, lengths, 0.0), 0.0)
    return rho, w


def points_case_a(stations, lengths, init, *, squared: bool, max_iter: int = 100):
    """Case A for the points: min over X_a,i of sum_k (||X_a,i - LT(k)|| - (L_k + P_i(k)))^2, or the squared form."""
    rho, w = _rho(stations, lengths)
    S = stations[:, :3]

    def fun(theta, act=slice(None)):
        d = theta[:, None, :] - S[None]                 # (B, K, 3)
        rr, ww = rho[act], w[act]
        if squared:
            r = np.einsum("bki,bki->bk", d, d) - rr ** 2
            J = 2 * d
        else:
            t = np.sqrt(np.einsum("bki,bki->bk", d, d))
            r = t - rr
            J = d / t[..., None]
        return r * ww, J * ww[..., None]

    return batched_lm(fun, init, size=float(np.nanmean(np.abs(lengths))), max_iter=max_iter)


def points_case_b(stations, lengths):
    """Case B for the points as published: the 4 x 4 system in (x_a, y_a, z_a, C_i), unscaled."""
    rho, w = _rho(stations, lengths)
    S = stations[:, :3]
    Sw = S[None] * w[..., None]                              # (N, K, 3)
    g = (np.sum(S ** 2, axis=1)[None] - rho ** 2) * w        # |LT|^2 - (L + P)^2
    A, b = _extremal_system(Sw, g, w)
    return _solve(A, b, "Case B point system")[:, :3], A


def points_centred(stations, lengths):
    """Case B for the points in coordinates centred on the stations and scaled by their RMS radius, by QR."""
    rho, w = _rho(stations, lengths)
    S = stations[:, :3]
    c0 = S.mean(axis=0)
    h = np.sqrt(np.mean(np.sum((S - c0) ** 2, axis=1)))
    Ss = (S - c0) / h
    M = np.concatenate([2 * Ss[None] * w[..., None], -w[..., None]], axis=2)   # (N, K, 4)
    g = (np.sum(Ss ** 2, axis=1)[None] - (rho / h) ** 2) * w
    theta = _qr_lstsq(M, g, "centred Case B point system")
    return c0 + h * theta[:, :3], np.einsum("nki,nkj->nij", M, M)


def points_taylor(stations, lengths, points):
    """One first-order correction of each point (the eq. 12-13 idea applied in step 2)."""
    rho, w = _rho(stations, lengths)
    d = points[:, None, :] - stations[None, :, :3]
    t = np.sqrt(np.einsum("nki,nki->nk", d, d))
    a = d / t[..., None] * w[..., None]
    A = np.einsum("nki,nkj->nij", a, a)
    b = -np.einsum("nki,nk->ni", a, (t - rho) * w)
    return points + _solve(A, b, "Taylor correction of the points"), A


# ---------------------------------------------------------------- shared linear algebra

def _solve(A, b, what):
    try:
        return np.linalg.solve(A, b[..., None])[..., 0]
    except np.linalg.LinAlgError:
        raise InvalidInputError(f"{what} is singular: the stations or points are in a degenerate position "
                                f"(coplanar or collinear); measure from stations in general position") from None


def _qr_lstsq(M, g, what):
    Qm, R = np.linalg.qr(M)
    diag = np.abs(np.einsum("bii->bi", R))
    if np.any(diag <= 1e-12 * diag.max(axis=1, keepdims=True)):
        raise InvalidInputError(f"{what} is rank deficient: the stations or points are in a degenerate position "
                                f"(coplanar or collinear); measure from stations in general position")
    return np.linalg.solve(R, np.einsum("bmi,bm->bi", Qm, g)[..., None])[..., 0]


# ---------------------------------------------------------------- joint adjustment (stations + points)

def _gauge(stations):
    """Six station coordinates held fixed to remove the rigid-body freedom of the joint adjustment:
    all of a first station, two of the station farthest from it, one of the station farthest from their line."""
    S = stations[:, :3]
    a = int(0)
    b = int(np.argmax(np.linalg.norm(S - S[a], axis=1)))
    axis = (S[b] - S[a]) / np.linalg.norm(S[b] - S[a])
    lever = np.cross(axis, S - S[a])
    c = int(np.argmax(np.linalg.norm(lever, axis=1)))
    if np.linalg.norm(lever[c]) <= 1e-6 * np.linalg.norm(S[b] - S[a]):
        raise InvalidInputError("all stations lie on one line: the joint adjustment cannot fix the orientation; "
                                "place the stations in general position")
    fixed = [4 * a + i for i in range(3)]
    fixed += [4 * b + i for i in np.argsort(np.abs(axis))[:2]]
    fixed += [4 * c + int(np.argmax(np.abs(lever[c])))]
    return np.array(fixed)


def kabsch(source, target):
    """Rotation R and translation t minimising sum ||R source_i + t - target_i||^2 (SVD, proper rotation)."""
    cs, ct = source.mean(axis=0), target.mean(axis=0)
    U, _, Vt = np.linalg.svd((source - cs).T @ (target - ct))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    return R, ct - R @ cs


def joint_adjustment(nominal, lengths, stations0, points0, *, max_iter: int = 100, xtol: float = 1e-13):
    """All stations (with L_k) and all actual points from all lengths at once: Levenberg-Marquardt on
    ||X_a,i - LT(k)|| - (L_k + P_i(k)), the 3 x 3 point blocks eliminated by the Schur complement (as in bundle
    adjustment), six station coordinates fixed, then the whole solution moved by the rigid motion that best
    aligns the actual points with the nominal ones. Returns stations, points, Schur matrix, point blocks,
    iterations, converged."""
    w = np.isfinite(lengths).astype(float)
    Pl = np.where(w > 0, lengths, 0.0)
    K, N = stations0.shape[0], nominal.shape[0]
    fixed = _gauge(stations0)
    free = np.setdiff1d(np.arange(4 * K), fixed)
    s, X = stations0.astype(float).copy(), points0.astype(float).copy()

    def evaluate(s, X):
        d = X[:, None, :] - s[None, :, :3]                        # (N, K, 3)
        t = np.sqrt(np.einsum("nki,nki->nk", d, d))
        r = (t - (s[None, :, 3] + Pl)) * w
        u = d / t[..., None] * w[..., None]
        return r, u

    def normal(r, u):
        Hpp = np.einsum("nki,nkj->nij", u, u)
        Jps = np.concatenate([-u, -w[..., None]], axis=2)       # d r / d (LT_k, L_k), (N, K, 4)
        Hss = np.einsum("nki,nkj->kij", Jps, Jps)
        Hps = np.einsum("nki,nkj->nikj", u, Jps).reshape(N, 3, 4 * K)
        gp = np.einsum("nki,nk->ni", u, r)
        gs = np.einsum("nki,nk->ki", Jps, r).reshape(-1)
        Hss_full = np.zeros((4 * K, 4 * K))
        for k in range(K):                                       # K <= a dozen stations
            Hss_full[4 * k:4 * k + 4, 4 * k:4 * k + 4] = Hss[k]
        return Hpp, Hss_full, Hps, gp, gs

    def schur(Hpp, Hss, Hps, gp, gs, lam):
        Dp = np.einsum("nii->ni", Hpp)
        Hpp_d = Hpp + lam * Dp[:, :, None] * np.eye(3)
        Hss_d = Hss + lam * np.diag(np.diag(Hss))
        try:
            inv = np.linalg.inv(Hpp_d)
        except np.linalg.LinAlgError:
            raise InvalidInputError("joint adjustment: a point is seen by too few stations in general position") from None
        W = np.einsum("nij,njk->nik", inv, Hps)                  # Hpp^-1 Hps
        S = Hss_d - np.einsum("nim,nik->mk", Hps, W)
        rhs = -gs + np.einsum("nim,ni->m", Hps, np.einsum("nij,nj->ni", inv, gp))
        return S, rhs, inv

    r, u = evaluate(s, X)
    cost = float(np.sum(r ** 2))
    lam = 1e-3
    converged = False
    it = 0
    for it in range(1, max_iter + 1):
        Hpp, Hss, Hps, gp, gs = normal(r, u)
        S, rhs, inv = schur(Hpp, Hss, Hps, gp, gs, lam)
        ds = np.zeros(4 * K)
        try:
            ds[free] = np.linalg.solve(S[np.ix_(free, free)], rhs[free])
        except np.linalg.LinAlgError:
            raise InvalidInputError("joint adjustment: the stations and points are not determined by these lengths "
                                    "(too few points per station, or a degenerate geometry)") from None
        dX = -np.einsum("nij,nj->ni", inv, gp + np.einsum("nim,m->ni", Hps, ds))
        s_t, X_t = s + ds.reshape(K, 4), X + dX
        r_t, u_t = evaluate(s_t, X_t)
        cost_t = float(np.sum(r_t ** 2))
        step = np.sqrt(np.sum(ds ** 2) + np.sum(dX ** 2))
        size = np.sqrt(np.sum(s ** 2) + np.sum(X ** 2))
        if cost_t <= cost:
            s, X, r, u, cost = s_t, X_t, r_t, u_t, cost_t
            lam = max(lam / 3.0, 1e-12)
            if step <= xtol * size or cost == 0.0:
                converged = True
                break
        else:
            lam *= 4.0
            if lam > 1e20:
                converged = step <= 1e-9 * size
                break
    Hpp, Hss, Hps, gp, gs = normal(r, u)
    S, _, _ = schur(Hpp, Hss, Hps, gp, gs, 0.0)
    R, t = kabsch(X, nominal)
    X = X @ R.T + t
    s = np.column_stack([s[:, :3] @ R.T + t, s[:, 3]])
    return s, X, S[np.ix_(free, free)], Hpp, it, converged
