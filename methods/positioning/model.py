"""The positioning paper's model: a polynomial through the mean deviations by generalised least
squares with the covariance U(x) = diag(u^2(P_i)) + u^2(delta) 1 1^T (its eq. 2 and 8-10), and the
expanded uncertainty U(P) = k sqrt(x(P)^T Cov x(P)) of the deviation anywhere on the travel, which holds only
where the polynomial describes the axis: :func:`lack_of_fit` tests it against the means at the targets."""
from __future__ import annotations

import numpy as np
from numpy.polynomial import polynomial as npoly

from methods._errors import InvalidInputError
from methods._registry import register
from methods.positioning.results import PositioningFit
from methods._validation import check_positive
from methods.positioning.data import PositioningData, validate
from methods.positioning.iso230_2 import figures
from methods.positioning.nulls import lack_of_fit_null, null_limit


def instrument_uncertainty(instrument_u=None, mpe=None) -> float:
    """u(delta): given directly, or from the instrument's maximum permissible error (rectangular, MPE / sqrt 3)."""
    if instrument_u is not None and mpe is not None:
        raise InvalidInputError("give the instrument's standard uncertainty or its MPE, not both")
    if mpe is not None:
        return float(check_positive("mpe", mpe, "positioning", allow_zero=True)) / np.sqrt(3.0)
    return float(check_positive("instrument_u", instrument_u or 0.0, "positioning", allow_zero=True))


def _to_position_basis(coef_t, cov_t, mid, half):
    """Coefficients in t = (P - mid) / half -> increasing powers of P, with the covariance."""
    deg = len(coef_t) - 1
    sub = np.array([-mid / half, 1.0 / half])  # t as a polynomial in P
    T = np.zeros((deg + 1, deg + 1))
    for j in range(deg + 1):
        poly_p = npoly.polypow(sub, j) if j else np.array([1.0])
        T[: len(poly_p), j] = poly_p
    return T @ coef_t, T @ cov_t @ T.T


def fit_direction(targets, x, s, n, degree, u_delta, weighting="gls"):
    """One direction: coefficients (in t), covariance, scaling; 'gls' = the paper's model, 'ols' = ordinary
    least squares with its own residual variance."""
    m = len(targets)
    if degree + 1 > m:
        raise InvalidInputError(f"a degree-{degree} polynomial needs at least {degree + 1} targets, got {m}")
    mid, half = 0.5 * (targets.max() + targets.min()), 0.5 * (targets.max() - targets.min())
    t = (targets - mid) / half
    X = np.vander(t, degree + 1, increasing=True)
    if weighting == "ols":
        coef, *_ = np.linalg.lstsq(X, x, rcond=None)
        dof = m - degree - 1
        res = x - X @ coef
        sigma2 = float(res @ res / dof) if dof > 0 else np.nan
        cov = sigma2 * np.linalg.inv(X.T @ X)
        return coef, cov, mid, half
    u2 = (s ** 2) / n  # eq. 10: type A uncertainty of the mean
    if np.all(u2 > 0):
        # U(x) = D + u^2(delta) 1 1^T (eq. 8-9). The polynomial has a constant term (1 = X e0), so
        # x = X (beta + delta e0) + eps: the GLS estimate is the weighted least-squares one under D and
        # Cov = Cov_WLS + u^2(delta) e0 e0^T exactly. Computed this way it stays accurate for any u(delta)
        # (the dense U is ill-conditioned once u(delta) >> u(P_i)).
        sw = 1.0 / np.sqrt(u2)
        Xw = X * sw[:, None]
        coef, *_ = np.linalg.lstsq(Xw, x * sw, rcond=None)
        cov = np.linalg.inv(Xw.T @ Xw)
        cov[0, 0] += u_delta ** 2
        return coef, cov, mid, half
    U = np.diag(u2) + u_delta ** 2 * np.ones((m, m))  # zero scatter at a target: the dense form
    try:
        L = np.linalg.cholesky(U)
    except np.linalg.LinAlgError:
        raise InvalidInputError("the covariance U(x) is singular (zero scatter at a target and u(delta) = 0): "
                                "give the instrument's uncertainty (--instrument-u or --mpe)") from None
    Xw = np.linalg.solve(L, X)
    xw = np.linalg.solve(L, x)
    coef, *_ = np.linalg.lstsq(Xw, xw, rcond=None)
    cov = np.linalg.inv(Xw.T @ Xw)
    return coef, cov, mid, half


#: significance level of the lack-of-fit test
LACK_OF_FIT_LEVEL = 0.05
def lack_of_fit(x, s, n, value, n_coef, level=LACK_OF_FIT_LEVEL) -> dict:
    """Lack-of-fit test of the model ``value`` at the targets against the mean deviations ``x``: the weighted
    chi-square chi2 = sum_i ((x_i - x(P_i)) / u(x_i))^2 with u(x_i) = s_i / sqrt(n), the paper's type A
    uncertainty of the mean (eq. 10), on nu = m - n_coef degrees of freedom. The common instrument error
    u^2(delta) 1 1^T of eq. 8-9 drops out (the polynomial has a constant term, so the GLS residuals are orthogonal
    to 1 under D^-1): chi2 is r^T U(x)^-1 r for any u(delta). Its limit and p-value come from its null
    distribution (:func:`lack_of_fit_null`, simulated with equal scatter at m equally spaced targets): the
    chi-square quantile would reject a correct cubic in 21-40 % of 5-run tests, F(nu, n - 1) in 0.3-0.7 %; this
    rejects 4.9-5.1 % with equal scatter, 4.4-5.7 % with unequal scatter or irregular targets (5 runs or more;
    docs/positioning.md). p_value: the share of the null sample at or above chi2. Returns chi2, dof, chi2_per_dof, p_value, critical (of chi2 / nu), reference (its
    distribution), rejected, tested (False: no degree of freedom, a target without scatter or a single run) and
    max_abs_residual (input unit)."""
    x, s, value = (np.asarray(a, dtype=float) for a in (x, s, value))
    r = x - value
    dof = int(len(x) - n_coef)
    out = {"chi2": float("nan"), "dof": dof, "chi2_per_dof": float("nan"), "p_value": float("nan"),
           "critical": float("nan"), "level": float(level), "rejected": False, "tested": False,
           "max_abs_residual": float(np.max(np.abs(r))) if r.size else 0.0, "reason": "", "reference": ""}
    if dof < 1:
        out["reason"] = f"as many coefficients ({n_coef}) as targets ({len(x)}): no degree of freedom left"
        return out
    if n < 2 or not np.all(np.isfinite(s)):
        out["reason"] = "one run per direction: no scatter to test the model against"
        return out
    u = s / np.sqrt(n)
    if not np.all(u > 0):
        out["reason"] = "zero scatter at a target"
        return out
    chi2 = float(np.sum((r / u) ** 2))
    crit, p_value = null_limit(lack_of_fit_null(len(x), int(n), int(n_coef)), chi2, level)
    crit /= dof
    out.update(chi2=chi2, chi2_per_dof=chi2 / dof, p_value=p_value, critical=crit,
               reference=f"its simulated null distribution ({len(x)} targets, {int(n)} runs)",
               rejected=bool(chi2 / dof > crit), tested=True, max_abs_residual=float(np.max(np.abs(r))))
    return out


def evaluate_band(poly: dict, P, k=2.0):
    """Model value and expanded uncertainty U(P) = k sqrt(x(P)^T Cov x(P)) at positions P."""
    P = np.atleast_1d(np.asarray(P, dtype=float))
    t = (P - poly["mid"]) / poly["half"]
    X = np.vander(t, poly["degree"] + 1, increasing=True)
    value = X @ poly["coef_t"]
    var = np.einsum("ij,jk,ik->i", X, poly["cov_t"], X)
    return value, k * np.sqrt(np.maximum(var, 0.0))


def _model(data: PositioningData, degree, u_delta, weighting, k):
    if data.runs < 2:
        raise InvalidInputError("the polynomial model needs repeated runs: u(P_i) (paper eq. 10) is the scatter of the "
                                "approaches to each target, and this test has one run per direction")
    fig, per = figures(data)
    poly, residuals = {}, []
    for d in data.directions:
        x, s, arr = per[f"mean_{d}"], per[f"s_{d}"], getattr(data, d)
        coef_t, cov_t, mid, half = fit_direction(data.targets, x, s, arr.shape[1], degree, u_delta, weighting)
        coef_p, cov_p = _to_position_basis(coef_t, cov_t, mid, half)
        entry = {"coefficients": coef_p, "covariance": cov_p, "degree": degree, "coef_t": coef_t, "cov_t": cov_t,
                 "mid": mid, "half": half, "k": k}
        value, U = evaluate_band(entry, data.targets, k)
        entry["U_at_targets"] = U
        entry["lack_of_fit"] = lack_of_fit(x, s, arr.shape[1], value, degree + 1)
        residuals.append(x - value)
        poly[d] = entry
    return fig, per, poly, np.concatenate(residuals)


@register("positioning.gls_polynomial", kind="closed form", validator=validate,
          summary="The paper's model: polynomial through the mean deviations by GLS, U(x) = diag(u^2) + u^2(delta) 11^T",
          reference="Kureková et al., positioning paper, eq. 2 and 5-10")
def gls_polynomial(data, *, degree=3, instrument_u=None, mpe=None, k=2.0):
    """Per direction, the polynomial (degree 3 by default, eq. 2) through the mean deviations with
    generalised least squares under U(x) = diag(u^2(P_i)) + u^2(delta) 1 1^T (eq. 8-9), u(P_i) by type A
    (eq. 10) and u(delta) from ``instrument_u`` or ``mpe`` (rectangular: MPE / sqrt 3). Coefficients
    and covariance in increasing powers of the position; U(P) = k sqrt(x^T Cov x) anywhere on the travel if the
    polynomial holds: ``polynomial[d]["lack_of_fit"]`` (:func:`lack_of_fit`) says whether the means reject it."""
    degree = int(check_positive("degree", degree, "positioning.gls_polynomial", allow_zero=True))
    ud = instrument_uncertainty(instrument_u, mpe)
    fig, per, poly, res = _model(data, degree, ud, "gls", float(k))
    return PositioningFit(figures=fig, per_target=per, polynomial=poly, residuals=res, converged=True,
                          message=f"GLS degree {degree}, u(delta) = {ud:g}", extra={"u_delta": ud})


@register("positioning.ols_polynomial", kind="closed form", validator=validate,
          summary="Polynomial through the mean deviations by ordinary least squares (baseline for the GLS model)",
          reference="positioning paper eq. 2 with ordinary least squares (comparison)")
def ols_polynomial(data, *, degree=3, k=2.0):
    """The same polynomial by ordinary least squares, its covariance from the residual variance (ignores
    the instrument's common error and the per-target scatter)."""
    degree = int(check_positive("degree", degree, "positioning.ols_polynomial", allow_zero=True))
    fig, per, poly, res = _model(data, degree, 0.0, "ols", float(k))
    return PositioningFit(figures=fig, per_target=per, polynomial=poly, residuals=res, converged=True,
                          message=f"OLS degree {degree}")
