"""Simulated null distributions of the positioning model's tests (the lack-of-fit chi2 of
:func:`methods.positioning.model.lack_of_fit`, and with one coefficient the reversal's variation along the travel of
:func:`methods.positioning.iso230_2.reversal_variation`): their limits and p-values. Below both modules, which use
it."""
from __future__ import annotations

import functools

import numpy as np

#: simulated tests giving the lack-of-fit statistic's null distribution (fixed seed: every run prints the same
#: limit; the 95 % point's Monte Carlo standard error is about 0.5 %)
LACK_OF_FIT_SIMULATIONS = 100_000


@functools.lru_cache(maxsize=8)
def lack_of_fit_null(m: int, n: int, n_coef: int, simulations: int = LACK_OF_FIT_SIMULATIONS) -> np.ndarray:
    """The null distribution (sorted) of :func:`lack_of_fit`'s chi2 for ``m`` equally spaced targets, ``n`` runs and
    ``n_coef`` coefficients, by simulation of the paper's model (eq. 8-10) with the same scatter at every target
    (ISO 230-2's one repeatability): x_i = p(P_i) + sigma/sqrt(n) g_i, s_i^2 = sigma^2 chi2_(n-1)/(n-1), each term
    weighted by its own estimated s_i. chi2 does not depend on sigma, p or u(delta): with equal scatter its
    distribution depends on m, n and n_coef alone. Neither chi2(nu) (u(x_i) known) nor F(nu, n - 1) (one common
    estimated variance) is it: the weights come from n runs each, and the fit follows the targets whose s_i came
    out small (11 targets, 5 runs, cubic: 95 % point of chi2/nu 3.42 where F(7, 4) gives 6.09 and chi2(7)/7 2.01)."""
    rng = np.random.default_rng(np.random.SeedSequence(230_2, spawn_key=(m, n, n_coef)))
    X = np.polynomial.chebyshev.chebvander(np.linspace(-1.0, 1.0, m), n_coef - 1)   # the polynomials' span
    XX = (X[:, :, None] * X[:, None, :]).reshape(m, n_coef * n_coef)
    out = []
    chunk = max(1, 2_000_000 // m)
    for start in range(0, simulations, chunk):
        k = min(chunk, simulations - start)
        g = rng.standard_normal((k, m))
        w = (n - 1) / rng.chisquare(n - 1, (k, m))              # sigma^2 / s_i^2
        A = (w @ XX).reshape(k, n_coef, n_coef)
        y = (w * g) @ X
        beta = np.linalg.solve(A, y[..., None])[..., 0]
        out.append(np.maximum(np.einsum("ij,ij->i", w * g, g) - np.einsum("ij,ij->i", y, beta), 0.0))
    return np.sort(np.concatenate(out))


def null_limit(null: np.ndarray, chi2: float, level: float) -> tuple[float, float]:
    """(limit, p_value) of ``chi2`` against a sorted simulated null sample: the (1 - level) quantile (linear
    between order statistics) and the share of the sample at or above chi2, (count + 1) / (size + 1)."""
    h = (null.size - 1) * (1.0 - level)
    lo = int(h)
    crit = float(null[lo] + (h - lo) * (null[min(lo + 1, null.size - 1)] - null[lo]))
    above = null.size - int(np.searchsorted(null, chi2, side="left"))
    return crit, (above + 1) / (null.size + 1)
