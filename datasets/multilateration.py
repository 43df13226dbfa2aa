"""Simulated LaserTRACER measurements of the MCV 754 QUICK (multilateration paper, Holub et al., Machines
2022, 10, 833) with known truth: its measured data and the Trac-Cal reference software are not public.

Machine: 3-axis WXYZT chain, travels 750 x 500 x 550 mm (table 1), Z home at the top (z in [-550, 0]: the frame
in which the paper's station heights, z = -340 to -508 mm, lie inside the travel). 18 component errors and 3
squareness errors (:mod:`methods.multilateration.kinematics`), linearised as in eq. 2-4.
Stations: the six Trac-Cal positions of table 5. Several 4-subsets of them are nearly coplanar (LT1-LT4 lie
within 1.3 mm of a plane, which leaves the point step ill-posed), so 4 stations means LT1, LT2, LT4, LT5 unless
chosen otherwise. Instrument: U(k = 2) = 0.2 um +
0.3 um/m x length (table 2), Gaussian with sigma = U / 2, independent per length.
"""
from __future__ import annotations

import numpy as np

from methods.multilateration.data import MultilaterationData
from methods.multilateration.kinematics import COMPONENTS, MCV754_TRAVEL, ErrorModel, volumetric_errors

#: Trac-Cal station positions of table 5 [mm]
TABLE5_STATIONS = np.array([[-154.799400, 125.978800, -471.460100],
                            [-143.324800, 328.559000, -471.386500],
                            [862.105400, 291.242700, -340.460000],
                            [833.382200, 103.158700, -340.446600],
                            [891.308200, 152.634600, -507.868500],
                            [885.581100, 154.917200, -507.865700]])
#: dead-path offsets L_k [mm] (not published; plausible values of a few cm)
DEAD_PATHS = np.array([41.237, 38.912, 55.604, 47.381, 36.058, 52.749])
#: tool (reflector) offsets [mm]: none, and two non-parallel ones so that all rotations are observable
TOOL_OFFSETS = ((0.0, 0.0, 0.0), (100.0, 0.0, -100.0), (0.0, 100.0, -100.0))
#: LaserTRACER uncertainty, table 2: U(k=2) = 0.2 um + 0.3 um/m x L
U_CONST_MM, U_PER_M_MM = 0.2e-3, 0.3e-3


def instrument_sigma(length_mm):
    """Standard uncertainty (mm) of one length: (0.2 um + 0.3 um/m x L) / 2."""
    return (U_CONST_MM + U_PER_M_MM * np.asarray(length_mm) / 1000.0) / 2.0


def mcv754_errors(degree: int = 3) -> ErrorModel:
    """A plausible error state of a machine of this size: 10-25 um positioning, 5-12 um straightness, 15-45 urad
    angular and 40-65 urad squareness errors over the travels (coefficients of (u / travel)^j). The largest
    volumetric error is 66 um (the paper reports 64 um for its MCV 754). Fixed numbers, so that every run
    sees the same machine."""
    base = {  # mm for E[XYZ]*, rad for E[ABC]*, coefficients of u^1, u^2, u^3 (straightness from u^2)
        "EXX": [0.024, -0.008, 0.006], "EYX": [0.012, -0.008], "EZX": [-0.01, 0.006],
        "EAX": [3e-5, -1.2e-5, 6e-6], "EBX": [-4.4e-5, 1.6e-5, -8e-6], "ECX": [3.6e-5, -1e-5, 4e-6],
        "EXY": [0.008, -0.006], "EYY": [-0.018, 0.01, -0.004], "EZY": [-0.008, 0.004],
        "EAY": [-2.4e-5, 1e-5, -4e-6], "EBY": [1.8e-5, -8e-6, 4e-6], "ECY": [2.8e-5, -1.2e-5, 6e-6],
        "EXZ": [0.01, -0.004], "EYZ": [-0.006, 0.004], "EZZ": [0.02, -0.012, 0.004],
        "EAZ": [-2e-5, 8e-6, -4e-6], "EBZ": [3.2e-5, -1.4e-5, 6e-6], "ECZ": [-1.6e-5, 6e-6, -2e-6],
    }
    coefs = {}
    for n in COMPONENTS:
        c = base[n]
        straight = n[1] in "XYZ" and n[1] != n[2]
        m = degree - (2 if straight else 1) + 1
        coefs[n] = np.array((c + [0.0] * m)[:m], float)
    return ErrorModel(degree=degree, travel=MCV754_TRAVEL, coefficients=coefs,
                      squareness={"C0Y": 50e-6, "B0Z": -64e-6, "A0Z": 42e-6})


def axis_grid(shape=(5, 4, 4), travel=MCV754_TRAVEL) -> np.ndarray:
    """Axis positions on a regular grid over x in [0, 750], y in [0, 500], z in [-550, 0]."""
    xs = np.linspace(0.0, travel[0], shape[0])
    ys = np.linspace(0.0, travel[1], shape[1])
    zs = np.linspace(-travel[2], 0.0, shape[2])
    X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
    return np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])


#: the default 4-station (RRB) choice from table 5: in general position (third singular value 111 mm)
FOUR_STATIONS = (1, 2, 4, 5)


def simulate(*, stations=6, grid=(5, 4, 4), offsets=TOOL_OFFSETS, errors: ErrorModel | None | str = "default",
             noise: float = 1.0, rng: np.random.Generator | None = None, degree: int = 3):
    """One simulated LaserTRACER campaign: every station measures every grid position with every tool offset.

    ``stations``: 6 (table 5), 4 (:data:`FOUR_STATIONS`) or a tuple of table-5 station numbers (1-6); ``errors``: "default" (:func:`mcv754_errors`), None (a perfect
    machine) or an :class:`ErrorModel`; ``noise``: multiple of the instrument's uncertainty (0 = exact lengths).
    Returns ``(MultilaterationData, truth)``; truth has stations (K, 4), axes, offsets, nominal, actual and
    volumetric_errors per point (N, 3), the ErrorModel and sigma (N, K).
    """
    chosen = {6: (1, 2, 3, 4, 5, 6), 4: FOUR_STATIONS}.get(stations, stations) if not isinstance(stations, tuple) \
        else stations
    if not isinstance(chosen, tuple) or not set(chosen) <= {1, 2, 3, 4, 5, 6} or len(set(chosen)) < 3:
        raise ValueError("stations must be 4, 6 or a tuple of at least three table-5 station numbers 1-6")
    pick = np.array(chosen) - 1
    rng = rng if rng is not None else np.random.default_rng(0)
    model = mcv754_errors(degree) if isinstance(errors, str) and errors == "default" else errors
    ax = axis_grid(grid)
    off = np.asarray(offsets, float)
    axes = np.repeat(ax, len(off), axis=0)
    offs = np.tile(off, (len(ax), 1))
    nominal = axes + offs
    if np.unique(nominal, axis=0).shape[0] != nominal.shape[0]:
        raise ValueError("two (position, tool offset) pairs give the same nominal point; change the grid or offsets")
    vol = volumetric_errors(model, axes, offs) if model is not None else np.zeros_like(nominal)
    actual = nominal + vol
    S = np.column_stack([TABLE5_STATIONS[pick], DEAD_PATHS[pick]])
    dist = np.linalg.norm(actual[:, None, :] - S[None, :, :3], axis=2)
    sigma = instrument_sigma(dist)
    lengths = dist - S[None, :, 3] + noise * sigma * rng.standard_normal(dist.shape)
    data = MultilaterationData(tuple(f"LT{k}" for k in chosen), nominal, lengths, offsets=offs)
    truth = {"stations": S, "axes": axes, "offsets": offs, "nominal": nominal, "actual": actual,
             "volumetric_errors": vol, "model": model, "sigma": sigma, "noise": float(noise)}
    return data, truth


def write_example(folder, *, stations=6, noise: float = 1.0, seed: int = 0) -> tuple:
    """Write ``measurements.csv`` and ``stations.csv`` (the true stations) of one simulated campaign to
    ``folder``; returns their paths. For trying ``python -m methods multilaterate``."""
    from pathlib import Path
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    data, truth = simulate(stations=stations, noise=noise, rng=np.random.default_rng(seed))
    meas, st = folder / "measurements.csv", folder / "stations.csv"
    data.to_frame().to_csv(meas, index=False, float_format="%.9f")
    data.with_stations(truth["stations"]).stations_frame().to_csv(st, index=False, float_format="%.9f")
    return meas, st
