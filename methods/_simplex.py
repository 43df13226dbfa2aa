"""Nelder–Mead driver shared by the simplex methods (programs FCG, FEA, FEG of the circle/ellipse
paper): the initial simplex from a first vertex s1S and a step vector lambda (its table 2), with the
scipy or NLopt implementation."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from methods._lazy import lazy_module

nlopt = lazy_module("nlopt")


BACKENDS = ("scipy", "nlopt")


def initial_simplex(first_vertex: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """Vertices s1 and s1 + lambda_j e_j, j = 1..n (the paper's simplex from s1S and lambda)."""
    return np.vstack([first_vertex, first_vertex + np.diag(steps)])


@dataclass
class SimplexRun:
    x: np.ndarray
    converged: bool
    message: str
    iterations: int | None
    nfev: int
    history: list = field(default_factory=list)


def nelder_mead(objective, x0, steps, *, backend: str, xatol: float, fatol: float, max_fev: int) -> SimplexRun:
    """Minimise ``objective`` from the simplex (x0, x0 + steps_j e_j).

    scipy stops when the simplex is smaller than ``xatol`` and its values differ by at most ``fatol``;
    NLopt stops on ``xatol`` alone (its ftol means 'one step changed f by less than this', which halts
    Nelder–Mead on a single small improvement). NLopt does not count iterations (``iterations`` None);
    its ``history`` is the best value after each evaluation, scipy's the best value per iteration."""
    x0 = np.asarray(x0, dtype=np.float64)
    steps = np.asarray(steps, dtype=np.float64)
    if backend == "scipy":
        history = []

        def callback(intermediate_result):
            history.append(float(intermediate_result.fun))

        from scipy.optimize import minimize  # imported on first use (light import)

        res = minimize(objective, x0, method="Nelder-Mead", callback=callback,
                       options={"initial_simplex": initial_simplex(x0, steps), "xatol": xatol, "fatol": fatol,
                                "maxfev": max_fev, "maxiter": max_fev})
        return SimplexRun(np.asarray(res.x), bool(res.success), str(res.message), int(res.nit), int(res.nfev), history)

    best = {"f": np.inf, "x": x0.copy()}
    history = []

    def nl_objective(p, grad):
        f = float(objective(p))
        if f < best["f"]:
            best["f"], best["x"] = f, np.array(p, dtype=float)
        history.append(best["f"])
        return f

    opt = nlopt.opt(nlopt.LN_NELDERMEAD, len(x0))
    opt.set_min_objective(nl_objective)
    opt.set_initial_step(steps)
    opt.set_xtol_abs(xatol)
    opt.set_maxeval(max_fev)
    messages = {nlopt.SUCCESS: "success", nlopt.STOPVAL_REACHED: "stopval reached", nlopt.FTOL_REACHED: "ftol reached",
                nlopt.XTOL_REACHED: "xtol reached", nlopt.MAXEVAL_REACHED: "maximum number of evaluations reached",
                nlopt.MAXTIME_REACHED: "maximum time reached"}
    try:
        x = opt.optimize(x0)
        code = opt.last_optimize_result()
        converged = code in (nlopt.SUCCESS, nlopt.FTOL_REACHED, nlopt.XTOL_REACHED)
        message = f"nlopt: {messages.get(code, f'result code {code}')}"
    except (nlopt.RoundoffLimited, RuntimeError, ValueError) as exc:
        x = best["x"]  # where it stopped; converged=False says it is not an optimum
        converged, message = False, f"nlopt failed: {type(exc).__name__}: {exc}"
    return SimplexRun(np.asarray(x), converged, message, None, len(history), history)
