"""ISO 230-2 evaluation of positioning (positioning paper sec. 2-3; ISO 230-2:1997/2006/2014, k = 2),
with the 1988 edition's +-3s variant and VDI/DGQ 3441 as options."""
from __future__ import annotations

import numpy as np

from methods._errors import InvalidInputError
from methods._registry import register
from methods.positioning.results import PositioningFit
from methods._validation import check_choice
from methods.positioning.data import PositioningData, validate
from methods.positioning.nulls import lack_of_fit_null, null_limit

STANDARDS = ("iso230-2:2014", "iso230-2:1988", "vdi3441")


def figures(data: PositioningData, standard: str = "iso230-2:2014") -> tuple[dict, dict]:
    """(axis figures, per-target arrays). ISO 230-2 with k = 2 (1997-2014) or k = 3 (1988):
    x_i = mean unidirectional deviation, s_i its estimator of the standard uncertainty, B_i = x_i up -
    x_i down, R_i up = 2k s_i up, R_i = max(k s_up + k s_down + |B_i|, R_i up, R_i down),
    E up = max - min of x_i up, E = max - min over both, M = max - min of (x_up + x_down)/2,
    A up = max(x_up + k s_up) - min(x_up - k s_up), A over both directions."""
    k = 3.0 if standard == "iso230-2:1988" else 2.0
    if data.runs == 1:
        return _single_run(data, standard, k)
    if len(data.directions) == 1:
        return _unidirectional(data, standard, k)
    xu, xd = data.up.mean(axis=1), data.down.mean(axis=1)
    su, sd = data.up.std(axis=1, ddof=1), data.down.std(axis=1, ddof=1)
    B_i = xu - xd
    Ru_i, Rd_i = 2 * k * su, 2 * k * sd
    R_i = np.maximum(k * su + k * sd + np.abs(B_i), np.maximum(Ru_i, Rd_i))
    xm = 0.5 * (xu + xd)
    per = {"targets": data.targets, "mean_up": xu, "mean_down": xd, "s_up": su, "s_down": sd, "B_i": B_i,
           "R_i_up": Ru_i, "R_i_down": Rd_i, "R_i": R_i, "mean_bidirectional": xm}
    fig = {"A_up": float(np.max(xu + k * su) - np.min(xu - k * su)),
           "A_down": float(np.max(xd + k * sd) - np.min(xd - k * sd)),
           "A": float(max(np.max(xu + k * su), np.max(xd + k * sd)) - min(np.min(xu - k * su), np.min(xd - k * sd))),
           "E_up": float(np.ptp(xu)), "E_down": float(np.ptp(xd)),
           "E": float(max(xu.max(), xd.max()) - min(xu.min(), xd.min())),
           "M": float(np.ptp(xm)), "R_up": float(Ru_i.max()), "R_down": float(Rd_i.max()), "R": float(R_i.max()),
           "B": float(np.max(np.abs(B_i))), "B_mean": float(np.mean(B_i)), "k": k, "standard": standard,
           "targets": len(data.targets), "runs": data.runs, "directions": "bidirectional"}
    if standard == "vdi3441":
        # VDI/DGQ 3441: scatter Ps_i = 6 s_i (s pooled over both directions), reversal span U_i = |B_i|,
        # Pa = range of the bidirectional means, P = max(x_i + (U_i + Ps_i)/2) - min(x_i - (U_i + Ps_i)/2)
        pooled = np.sqrt(0.5 * (su ** 2 + sd ** 2))
        Ps_i, U_i = 6 * pooled, np.abs(B_i)
        half = 0.5 * (U_i + Ps_i)
        fig.update(Ps=float(Ps_i.max()), U=float(U_i.max()), Pa=float(np.ptp(xm)),
                   P=float(np.max(xm + half) - np.min(xm - half)))
        per.update(Ps_i=Ps_i, U_i=U_i)
        for key in ("R_i", "R_i_up", "R_i_down"):      # ISO 230-2's repeatability at a target: not a VDI figure
            del per[key]
    return fig, per


#: significance level of the test of a reversal that varies along the travel (:func:`reversal_variation`)
REVERSAL_LEVEL = 0.05


def reversal_variation(data: PositioningData, level: float = REVERSAL_LEVEL) -> dict | None:
    """Does the reversal B_i = x_i up - x_i down vary along the travel more than the scatter of the means explains?
    A compensation table of the mean bidirectional deviation with one backlash (-B mean, ISO 230-2's mean reversal
    value) leaves (B_i - B mean) / 2 in each direction, of opposite sign.

    The test works on the paired differences d_ij = x_ij up - x_ij down of run j (ISO 230-2's test cycle approaches
    every target up and down in each run): B_i = mean_j d_ij, and s^2(d_i) / n estimates var(B_i) free of what a
    run shares between its two approaches (the thermal drift of a laser test: s_up, s_down hold it, B_i does not).
    Statistic chi2 = sum_i (B_i - B_w)^2 / (s^2(d_i) / n), B_w the mean weighted by n / s^2(d_i), on m - 1 degrees
    of freedom: each term is standardised by its own target's scatter (Welch 1951, Biometrika 38, 330: the
    weighted sum of squares of his ANOVA for unequal variances), so its distribution hardly depends on how the
    scatter varies along the travel. Its limit comes from its simulated null distribution, the lack-of-fit test's
    with one coefficient (:func:`methods.positioning.nulls.lack_of_fit_null`: fixed seed, cached per m and n), not
    from Welch's F approximation, which needs more runs per target than a positioning test has (simulated level
    8.7 % for 11 targets x 5 runs, 30 % for 21 x 3) nor from F(m - 1, 2m(n - 1)) of the pooled scatter (12-16 %
    with the scatter varying along the travel, and blind to a variation under run-to-run drift). Simulated level
    (docs/positioning.md): 4.6-5.6 % for 5 runs with equal scatter, s.d. 0.3-3 um along the travel, one target with
    5x or 10x the scatter, 2 um of run-to-run drift. A file whose up and down runs are numbered differently
    (``runs_numbered_alike`` False) is paired by the order of the run numbers; if those pairs are not one cycle's,
    a drift between them is common to every target, drops out of B_i - B_w and only widens s(d_i): the test keeps
    its level and loses power (``pairing`` says which).

    Returns B_i's least and largest value, B mean (unweighted, ISO's), ``left`` = max |B_i - B mean| / 2 (what each
    direction keeps, input unit), chi2, dof, chi2_per_dof, critical (of chi2 / dof), p_value, level, significant,
    pairing, tested and reason (a target whose differences do not scatter, e.g. quantised readings, cannot be
    weighted: not tested); None for a unidirectional or one-run test, or when no difference scatters anywhere."""
    if len(data.directions) != 2 or data.runs < 2 or len(data.targets) < 2:
        return None
    n, m = data.runs, len(data.targets)
    d = data.up - data.down
    B_i = d.mean(axis=1)
    var_b = d.var(axis=1, ddof=1) / n
    if not np.any(var_b > 0):
        return None
    pairing = ("by run number" if getattr(data, "runs_numbered_alike", True) else
               "by the order of the run numbers (the file numbers its up and down runs differently)")
    out = {"B_i_min": float(B_i.min()), "B_i_max": float(B_i.max()), "B_mean": float(B_i.mean()),
           "left": float(np.max(np.abs(B_i - B_i.mean())) / 2), "dof": m - 1, "level": float(level),
           "pairing": pairing, "chi2": float("nan"), "chi2_per_dof": float("nan"), "critical": float("nan"),
           "p_value": float("nan"), "significant": False, "tested": False, "reason": ""}
    flat = np.flatnonzero(~(var_b > 0))
    if flat.size:
        out["reason"] = (f"x_up - x_down is the same in every run at target {data.targets[flat[0]]:g} "
                         f"({data.unit or 'input unit'}){' and ' + str(flat.size - 1) + ' more' if flat.size > 1 else ''}: "
                         "no scatter to weigh it by (quantised readings?)")
        return out
    w = 1.0 / var_b
    chi2 = float(np.sum(w * (B_i - np.sum(w * B_i) / np.sum(w)) ** 2))
    crit, p = null_limit(lack_of_fit_null(m, n, 1), chi2, level)
    out.update(chi2=chi2, chi2_per_dof=chi2 / (m - 1), critical=crit / (m - 1), p_value=p,
               significant=bool(chi2 > crit), tested=True)
    return out


def _unidirectional(data: PositioningData, standard: str, k: float) -> tuple[dict, dict]:
    """ISO 230-2 unidirectional figures of the one direction measured: A, E, R of that direction (and
    the same values under the axis keys A, E, R); M and B need both directions and are absent. A file that names
    no direction is 'unidirectional (direction not given)' (its figures under the keys of 'up')."""
    if standard == "vdi3441":
        raise InvalidInputError("VDI/DGQ 3441 needs both approach directions; this test has one")
    d = data.directions[0]
    arr = getattr(data, d)
    x, s = arr.mean(axis=1), arr.std(axis=1, ddof=1)
    R_i = 2 * k * s
    per = {"targets": data.targets, f"mean_{d}": x, f"s_{d}": s, f"R_i_{d}": R_i}
    A, E, R = float(np.max(x + k * s) - np.min(x - k * s)), float(np.ptp(x)), float(R_i.max())
    label = d if getattr(data, "direction_given", True) else "direction not given"
    fig = {f"A_{d}": A, f"E_{d}": E, f"R_{d}": R, "A": A, "E": E, "R": R, "k": k, "standard": standard,
           "targets": len(data.targets), "runs": data.runs, "directions": f"unidirectional ({label})"}
    return fig, per


#: what one run per direction cannot give: the estimator s_i needs at least two approaches (ISO 230-2 sec. 2.15)
SINGLE_RUN_WITHOUT = "A and R need the estimator s of repeated approaches (ISO 230-2: at least two per target)"


def _single_run(data: PositioningData, standard: str, k: float) -> tuple[dict, dict]:
    """One run per direction, ISO 230-2's test of linear axes over 2000 mm: the mean deviations are that run's
    deviations, so E (per direction and bidirectional), M, B_i, B and B mean follow by their definitions; s, R and A
    need repeated approaches and are absent (:data:`SINGLE_RUN_WITHOUT`)."""
    if standard == "vdi3441":
        raise InvalidInputError("VDI/DGQ 3441 needs the scatter of repeated runs; this test has one run per direction")
    per = {"targets": data.targets}
    fig = {"k": k, "standard": standard, "targets": len(data.targets), "runs": 1, "not_evaluated": SINGLE_RUN_WITHOUT}
    for d in data.directions:
        x = getattr(data, d)[:, 0]
        per[f"mean_{d}"] = x
        fig[f"E_{d}"] = float(np.ptp(x))
    if len(data.directions) == 2:
        xu, xd = per["mean_up"], per["mean_down"]
        per.update(B_i=xu - xd, mean_bidirectional=0.5 * (xu + xd))
        fig.update(E=float(max(xu.max(), xd.max()) - min(xu.min(), xd.min())), M=float(np.ptp(per["mean_bidirectional"])),
                   B=float(np.max(np.abs(per["B_i"]))), B_mean=float(np.mean(per["B_i"])), directions="bidirectional")
    else:
        d = data.directions[0]
        label = d if getattr(data, "direction_given", True) else "direction not given"
        fig.update(E=fig[f"E_{d}"], directions=f"unidirectional ({label})")
    return fig, per


#: ISO 230-2 (1997-2014 editions) sec. 5.3.2-5.3.4 as we read them: linear axes up to 2000 mm need at least five
#: target positions per metre and five overall, each approached five times in each direction; longer axes are
#: tested by one approach in each direction to targets 250 mm apart on average
TARGETS_PER_METRE, MIN_TARGETS, MIN_RUNS, LONG_AXIS_MM, LONG_AXIS_INTERVAL_MM = 5, 5, 5, 2000.0, 250.0


def conformity(data: PositioningData) -> list[str]:
    """What a test lacks to be an ISO 230-2 test (an empty list when it has the standard's targets and runs):
    the figures are still computed by the standard's formulas, but a 2-run s (1 degree of freedom) times
    k = 2 is not the standard's R, nor 2 targets its E. Travel = last - first target (mm)."""
    P = np.asarray(data.targets, float)
    travel = float(P[-1] - P[0])
    lacks = []
    if travel <= LONG_AXIS_MM:
        need = max(MIN_TARGETS, int(np.ceil(TARGETS_PER_METRE * travel / 1000.0 - 1e-9)))
        if P.size < need:
            lacks.append(f"{P.size} targets on a {travel:g} mm travel ({need} needed: at least {TARGETS_PER_METRE} "
                         f"per metre and {MIN_TARGETS} overall)")
        if data.runs < MIN_RUNS:
            lacks.append(f"{data.runs} runs per direction ({MIN_RUNS} needed)")
    else:
        need = int(np.ceil(travel / LONG_AXIS_INTERVAL_MM - 1e-9)) + 1
        if P.size < need:
            lacks.append(f"{P.size} targets on a {travel:g} mm travel ({need} needed: an axis over "
                         f"{LONG_AXIS_MM:g} mm has targets {LONG_AXIS_INTERVAL_MM:g} mm apart on average)")
    return lacks


@register("positioning.iso230_2", kind="closed form", validator=validate,
          summary="ISO 230-2 positioning figures: A, E, M, R, B per direction (k = 2; 1988 and VDI 3441 options)",
          reference="ISO 230-2:2014 (1997) sec. 2-3; positioning paper (Kureková et al.) sec. 2-3")
def iso230_2(data, *, standard="iso230-2:2014"):
    """The standard's point-wise evaluation at the target positions (no model between them)."""
    check_choice("standard", standard, STANDARDS, "positioning.iso230_2")
    fig, per = figures(data, standard)
    return PositioningFit(figures=fig, per_target=per, converged=True, message=f"{standard} figures")
