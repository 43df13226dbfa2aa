"""The registered multilateration methods: the paper's four schemes (Holub et al., Machines 2022, 10, 833)
and two better ones. Each runs step 1 (stations and dead paths from the nominal points, skipped when the
stations are known) and step 2 (actual points from the stations) with the same scheme."""
from __future__ import annotations

import numpy as np

from methods._errors import InvalidInputError
from methods._registry import register
from methods.multilateration.results import MultilaterationFit
from methods.multilateration import solvers
from methods.multilateration.data import MultilaterationData, validate

REF = "Holub et al., Machines 2022, 10, 833"
#: Largest condition number of a solved system whose solution is still determined (to ~1e-2 relative at
#: worst: rounding is amplified by kappa, eps kappa <= 1e-2); above it a direction is left free.
COND_LIMIT = 1e-2 / np.finfo(float).eps
#: Singular-value ratio of the stations' spread below which they count as collinear / coplanar.
GEOMETRY_RTOL = 1e-9


def check_station_geometry(stations, lengths, *, need_3d: bool, who: str) -> None:
    """Refuse stations that cannot determine a point: for every point, the stations that measured it must
    not lie on one line (the point could turn about it), and for the linear Case B point system (unknowns
    x, y, z and C from rows [2 LT(k), -1]) not in one plane either (those rows are then dependent).
    Scale-free: singular values of the stations' spread about their centroid, relative to the largest."""
    w = np.isfinite(lengths).astype(float)                       # (N, K)
    S = np.asarray(stations, float)[:, :3]
    c = (w @ S) / w.sum(axis=1, keepdims=True)                   # (N, 3) centroid of each point's stations
    D = (S[None, :, :] - c[:, None, :]) * np.sqrt(w)[..., None]  # (N, K, 3)
    sv = np.linalg.svd(D, compute_uv=False)                      # (N, 3), largest first
    big = np.where(sv[:, 0] > 0, sv[:, 0], 1.0)
    line = sv[:, 1] <= GEOMETRY_RTOL * big
    plane = sv[:, 2] <= GEOMETRY_RTOL * big
    if line.any():
        i = int(np.flatnonzero(line)[0])
        raise InvalidInputError(f"{who}: the stations measuring point {i} lie on one straight line, so the point can "
                                f"turn about it and is not determined; measure from stations in general position")
    if need_3d and plane.any():
        i = int(np.flatnonzero(plane)[0])
        raise InvalidInputError(f"{who}: the stations measuring point {i} lie in one plane, which makes the linear "
                                f"Case B point system singular; use stations off that plane, or case_a_distance")


def _undetermined(cond: dict) -> str:
    """The systems whose condition number exceeds COND_LIMIT, as a reason, or ''."""
    bad = [f"{name} (kappa {float(np.max(c['svd'])):.2e})" for name, c in cond.items()
           if not np.max(c["svd"]) <= COND_LIMIT]
    return ("the solution is not determined: condition number above 1e-2/eps in " + ", ".join(bad)
            + " (degenerate station or point geometry)") if bad else ""


def _result(data: MultilaterationData, stations, points, cond, *, converged=True, iterations=None, message="",
            frame="measurement"):
    why = _undetermined(cond)
    if why:
        converged, message = False, f"{why}; {message}"
    d = points[:, None, :] - stations[None, :, :3]
    res = np.sqrt(np.einsum("nki,nki->nk", d, d)) - (stations[None, :, 3] + data.lengths)
    vol = points - data.points
    return MultilaterationFit(station_ids=list(data.stations), stations=stations, points=points, volumetric_errors=vol,
                              condition_numbers=cond, residuals=res, frame=frame,
                              form_error=float(np.max(np.linalg.norm(vol, axis=1))), converged=bool(converged),
                              iterations=iterations, message=message)


def _case_a(data, squared, max_iter, label, label_id="multilateration"):
    cond, its, ok = {}, [], True
    if data.known_stations is None:
        init, _ = solvers.stations_centred(data.points, data.lengths)
        stations, H, it, done = solvers.stations_case_a(data.points, data.lengths, init, squared=squared, max_iter=max_iter)
        cond["stations"] = solvers.conditioning(H, f"4 x 4 J^T J of {label} at the solution (stations)")
        its.append(it)
        ok &= bool(done.all())
    else:
        stations = data.known_stations
    check_station_geometry(stations, data.lengths, need_3d=False, who=label_id)
    points, H, it, done = solvers.points_case_a(stations, data.lengths, data.points.copy(), squared=squared,
                                                max_iter=max_iter)
    cond["points"] = solvers.conditioning(H, f"3 x 3 J^T J of {label} at the solution (points)")
    its.append(it)
    ok &= bool(done.all())
    msg = "trust region (Levenberg-Marquardt) converged" if ok else \
        f"not converged within max_iter={max_iter} for some stations or points"
    return _result(data, stations, points, cond, converged=ok, iterations=max(its), message=msg)


@register("multilateration.case_a_distance", summary="Case A, eq. 7: trust-region least squares of the distance residuals",
          reference=f"{REF}, eq. 5 and 7", kind="iterative", validator=validate)
def case_a_distance(data, *, max_iter: int = 100):
    """min sum (||X_i - LT|| - (L + P_i))^2 per station (eq. 7), then per point (section 3.2)."""
    return _case_a(data, False, max_iter, "eq. 7", "multilateration.case_a_distance")


@register("multilateration.case_a_squared", summary="Case A, eq. 8: trust-region least squares of the squared residuals",
          reference=f"{REF}, eq. 6 and 8", kind="iterative", validator=validate)
def case_a_squared(data, *, max_iter: int = 100):
    """min sum (||X_i - LT||^2 - (L + P_i)^2)^2 per station (eq. 8), then per point."""
    return _case_a(data, True, max_iter, "eq. 8", "multilateration.case_a_squared")


def _case_b(data, taylor: bool):
    cond = {}
    if data.known_stations is None:
        stations, A = solvers.stations_case_b(data.points, data.lengths)
        cond["stations"] = solvers.conditioning(A, "5 x 5 Case B system (eq. 11), unscaled")
        if taylor:
            stations, A = solvers.stations_taylor(data.points, data.lengths, stations)
            cond["stations_taylor"] = solvers.conditioning(A, "3 x 3 Taylor correction (eq. 13)")
    else:
        stations = data.known_stations
    check_station_geometry(stations, data.lengths, need_3d=True,
                           who="multilateration.case_b_taylor" if taylor else "multilateration.case_b_linear")
    points, A = solvers.points_case_b(stations, data.lengths)
    cond["points"] = solvers.conditioning(A, "4 x 4 Case B point system (section 3.2), unscaled")
    if taylor:
        points, A = solvers.points_taylor(stations, data.lengths, points)
        cond["points_taylor"] = solvers.conditioning(A, "3 x 3 Taylor correction of the points")
    return _result(data, stations, points, cond, message="linear system solved" + (" + one Taylor correction" if taylor else ""))


@register("multilateration.case_b_linear", summary="Case B, eq. 11: the linear 'extremal principle' system as published",
          reference=f"{REF}, eq. 9-11", kind="closed form", validator=validate)
def case_b_linear(data):
    """The 5 x 5 normal system (eq. 11) per station, the 4 x 4 one per point, unscaled as published."""
    return _case_b(data, False)


@register("multilateration.case_b_taylor", summary="Case B plus the first-order Taylor correction of eq. 12-13",
          reference=f"{REF}, eq. 12-13", kind="closed form", validator=validate)
def case_b_taylor(data):
    """Case B, then one linearised correction of each station (L_k held, eq. 13) and of each point."""
    return _case_b(data, True)


@register("multilateration.case_b_centred", summary="Case B centred and scaled, solved by QR (well conditioned)",
          reference=f"{REF}, eq. 9-11; centring and scaling as in Golub & Van Loan, Matrix Computations, 5.3",
          kind="closed form", validator=validate)
def case_b_centred(data):
    """The Case B equations in centred, scaled coordinates with centred lengths, solved by QR of the design
    matrix. Same estimator as Case B; the condition numbers are those of its (scaled) normal matrix."""
    cond = {}
    if data.known_stations is None:
        stations, A = solvers.stations_centred(data.points, data.lengths)
        cond["stations"] = solvers.conditioning(A, "5 x 5 normal matrix of the centred, scaled Case B (solved by QR)")
    else:
        stations = data.known_stations
    check_station_geometry(stations, data.lengths, need_3d=True, who="multilateration.case_b_centred")
    points, A = solvers.points_centred(stations, data.lengths)
    cond["points"] = solvers.conditioning(A, "4 x 4 normal matrix of the centred, scaled point system (solved by QR)")
    return _result(data, stations, points, cond, message="centred, scaled linear least squares (QR)")


@register("multilateration.joint", summary="All stations and points adjusted together (sparse/Schur Levenberg-Marquardt)",
          reference="joint adjustment of stations and points as in bundle adjustment (Triggs et al. 2000); "
                    "Schwenke et al., CIRP Ann. 2005, 54, 475 (self-calibrating tracking interferometer)",
          kind="iterative", validator=validate)
def joint(data, *, max_iter: int = 100):
    """Minimise eq. 7's distance residuals over all stations, dead paths and actual points together. Its
    stations are not biased by the machine's errors (step 1 of the paper uses the nominal points). Without
    known stations the result is defined up to a rigid motion: reported aligned (least squares) to the
    nominal points. With known stations it is Case A's step 2."""
    if data.known_stations is not None:
        return _case_a(data, False, max_iter, "eq. 7", "multilateration.joint")
    start = _case_a(data, False, max_iter, "eq. 7", "multilateration.joint")
    stations, points, S, Hpp, it, ok = solvers.joint_adjustment(data.points, data.lengths, start.stations,
                                                                start.points, max_iter=max_iter)
    cond = {"stations": solvers.conditioning(S[None], f"{S.shape[0]} x {S.shape[0]} Schur complement (stations, gauge fixed)"),
            "points": solvers.conditioning(Hpp, "3 x 3 point blocks of J^T J")}
    msg = "joint Levenberg-Marquardt converged; aligned to the nominal points" if ok else \
        f"joint adjustment not converged within max_iter={max_iter}; aligned to the nominal points"
    return _result(data, stations, points, cond, converged=ok, iterations=it, message=msg, frame="nominal")
