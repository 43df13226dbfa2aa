"""The 3-axis kinematic chain WXYZT of the multilateration paper (Holub et al., Machines 2022, 10, 833,
eq. 1-4), linearised, and the identification of its 21 geometric errors from volumetric errors.

The 18 component errors are named as in ISO 230-1 (table 3 of the paper): for axis U in {X, Y, Z}
``EXU, EYU, EZU`` (positioning and straightness, the paper's delta_xu, delta_yu, delta_zu, in mm) and
``EAU, EBU, ECU`` (roll/pitch/yaw about x, y, z, the paper's epsilon_xu..epsilon_zu, in rad), each a smooth
function of that axis' own position. The three squareness errors are ``C0Y`` (S_xy, Y to X), ``B0Z``
(S_xz, Z to X) and ``A0Z`` (S_yz, Z to Y). Table 4 of the paper pairs the ISO names and symbols
differently (B0Z / S_xy); here each name goes with the plane it acts in.

Linearised chain (dual-number units dropped, eq. 2-4; the signs follow from a small rotation
``eps x v`` of everything an axis carries, which the text of the paper lost):

    dx = EXX + EXY + EXZ - y (ECX + C0Y) + z (EBX + EBY - B0Z) - yp (ECX + ECY + ECZ) + zp (EBX + EBY + EBZ)
    dy = EYX + EYY + EYZ - z (EAX + EAY + A0Z) + xp (ECX + ECY + ECZ) - zp (EAX + EAY + EAZ)
    dz = EZX + EZY + EZZ + y EAX + yp (EAX + EAY + EAZ) - xp (EBX + EBY + EBZ)

where (x, y, z) are the axis positions and (xp, yp, zp) the tool (reflector) offset; the nominal tool
point is (x + xp, y + yp, z + zp) and the volumetric error is actual - nominal.

Each component error is a polynomial in the relative position u / travel, zero at the axis origin (the
reference position): positioning and angular errors of degree 1..d, straightness errors of degree 2..d
(ISO 230-1 measures straightness from a reference line; its slope is a squareness or the orientation of
the axis). With ``rigid=True`` the identification adds a rigid-body motion (3 translations, 3 small
rotations) of the measured volume, which multilateration with self-calibrated stations cannot observe.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from methods._errors import InvalidInputError

AXES = "XYZ"
COMPONENTS = [f"E{d}{a}" for a in AXES for d in "XYZABC"]  # EXX, EYX, EZX, EAX, EBX, ECX, EXY, ...
SQUARENESS = ["C0Y", "B0Z", "A0Z"]
NAMES = COMPONENTS + SQUARENESS
PAPER_SYMBOL = {**{f"E{d}{a}": f"{'delta' if d in 'XYZ' else 'epsilon'}_{'xyz'['XYZABC'.index(d) % 3]}{a.lower()}"
                   for a in AXES for d in "XYZABC"}, "C0Y": "S_xy", "B0Z": "S_xz", "A0Z": "S_yz"}
RIGID = ["TX", "TY", "TZ", "RX", "RY", "RZ"]
#: travels of the MCV 754 QUICK (table 1 of the paper: measurement ranges 750 x 500 x 550 mm)
MCV754_TRAVEL = (750.0, 500.0, 550.0)


def _min_degree(name: str) -> int:
    d, a = name[1], name[2]
    return 2 if d in "XYZ" and d != a else 1  # straightness: no linear term


@dataclass
class ErrorModel:
    """Polynomial coefficients of the 18 component errors (``coefficients[name][j]`` multiplies
    (u / travel)^(j + first degree)) and the 3 squareness errors (rad), plus an optional rigid-body
    motion ``rigid`` = (TX, TY, TZ [mm], RX, RY, RZ [rad])."""

    degree: int
    travel: tuple = MCV754_TRAVEL
    coefficients: dict = field(default_factory=dict)
    squareness: dict = field(default_factory=dict)
    rigid: np.ndarray = field(default_factory=lambda: np.zeros(6))

    def vector(self, rigid: bool = False) -> np.ndarray:
        """All parameters in the order of :func:`parameter_names`."""
        v = [np.asarray(self.coefficients.get(n, np.zeros(self.degree - _min_degree(n) + 1)), float) for n in COMPONENTS]
        v.append(np.array([self.squareness.get(n, 0.0) for n in SQUARENESS], float))
        if rigid:
            v.append(np.asarray(self.rigid, float))
        return np.concatenate(v)

    @classmethod
    def from_vector(cls, vector, degree: int, travel=MCV754_TRAVEL, rigid: bool = False) -> "ErrorModel":
        vector = np.asarray(vector, float)
        coefs, k = {}, 0
        for n in COMPONENTS:
            m = degree - _min_degree(n) + 1
            coefs[n] = vector[k:k + m].copy()
            k += m
        sq = {n: float(vector[k + i]) for i, n in enumerate(SQUARENESS)}
        k += 3
        rb = vector[k:k + 6].copy() if rigid else np.zeros(6)
        return cls(degree=degree, travel=tuple(travel), coefficients=coefs, squareness=sq, rigid=rb)

    def component(self, name: str, position) -> np.ndarray:
        """The component error ``name`` (e.g. 'EBX') at the given positions of its axis."""
        axis = AXES.index(name[2])
        u = np.asarray(position, float) / self.travel[axis]
        c = np.asarray(self.coefficients.get(name, []), float)
        p0 = _min_degree(name)
        return sum(c[j] * u ** (j + p0) for j in range(c.size)) if c.size else np.zeros_like(u)


def parameter_names(degree: int, rigid: bool = False) -> list[str]:
    """Names of the model's parameters: 'EBX^2' is the coefficient of (x / travel)^2 in EBX."""
    out = [f"{n}^{j}" for n in COMPONENTS for j in range(_min_degree(n), degree + 1)]
    return out + SQUARENESS + (RIGID if rigid else [])


def design_matrix(axes, offsets, degree: int, travel=MCV754_TRAVEL, rigid: bool = False) -> np.ndarray:
    """G (3N x P) with volumetric errors [dx_1, dy_1, dz_1, dx_2, ...] = G @ parameters (eq. 2-4)."""
    axes = np.asarray(axes, float)
    offsets = np.broadcast_to(np.asarray(offsets, float), axes.shape)
    n = axes.shape[0]
    x, y, z = axes.T
    xp, yp, zp = offsets.T
    # coefficient of each component error in (dx, dy, dz): shape (3, N) per error name
    one, zero = np.ones(n), np.zeros(n)
    mult = {}
    for a in AXES:
        mult[f"EX{a}"] = (one, zero, zero)
        mult[f"EY{a}"] = (zero, one, zero)
        mult[f"EZ{a}"] = (zero, zero, one)
        mult[f"EA{a}"] = (zero, -zp, yp)
        mult[f"EB{a}"] = (zp, zero, -xp)
        mult[f"EC{a}"] = (-yp, xp, zero)
    # errors of the axes below the one carrying the motion act on the positions it carries
    mult["ECX"] = (-y - yp, xp, zero)
    mult["EAX"] = (zero, -z - zp, y + yp)
    mult["EBX"] = (z + zp, zero, -xp)
    mult["EBY"] = (z + zp, zero, -xp)
    mult["EAY"] = (zero, -z - zp, yp)
    cols = []
    for name in COMPONENTS:
        u = axes[:, AXES.index(name[2])] / travel[AXES.index(name[2])]
        m = np.stack(mult[name])  # (3, N)
        for j in range(_min_degree(name), degree + 1):
            cols.append((m * u ** j).T.reshape(-1))
    cols.append(np.stack((-y, zero, zero)).T.reshape(-1))   # C0Y
    cols.append(np.stack((-z, zero, zero)).T.reshape(-1))   # B0Z
    cols.append(np.stack((zero, -z, zero)).T.reshape(-1))   # A0Z
    if rigid:
        X = axes + offsets
        for i in range(3):  # translations
            t = np.zeros((n, 3))
            t[:, i] = 1.0
            cols.append(t.reshape(-1))
        for i in range(3):  # small rotations: omega x X
            w = np.zeros(3)
            w[i] = 1.0
            cols.append(np.cross(w, X).reshape(-1))
    return np.column_stack(cols)


def volumetric_errors(model: ErrorModel, axes, offsets=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Volumetric errors (N, 3) = actual - nominal tool positions of the linearised chain."""
    rigid = bool(np.any(model.rigid))
    G = design_matrix(axes, offsets, model.degree, model.travel, rigid=rigid)
    return (G @ model.vector(rigid=rigid)).reshape(-1, 3)


@dataclass
class Identification:
    """Identified error model with ``covariance`` of ``vector`` (order of ``names``) and the residual
    RMS of the fit (mm); ``model`` evaluates the identified component errors."""

    model: ErrorModel
    names: list
    vector: np.ndarray
    covariance: np.ndarray
    residual_rms: float
    dof: int

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.diag(self.covariance))

    def as_table(self) -> list[dict]:
        return [{"parameter": n, "value": float(v), "u": float(s)} for n, v, s in zip(self.names, self.vector, self.std)]


def identify(axes, offsets, errors, *, degree: int = 3, travel=MCV754_TRAVEL, rigid: bool = True,
             covariance=None) -> Identification:
    """Least squares of the linearised chain (eq. 2-4) on volumetric errors (N, 3) at axis positions
    ``axes`` with tool ``offsets``. ``covariance`` (N, 3, 3) of the errors gives generalised least squares
    and uncertainties from it; without it the uncertainties scale with the residual variance."""
    axes = np.asarray(axes, float)
    errors = np.asarray(errors, float)
    if axes.ndim != 2 or axes.shape[1] != 3 or errors.shape != axes.shape:
        raise InvalidInputError(f"identify: axes and errors must both be (N, 3) arrays, got {axes.shape} and {errors.shape}")
    if not (np.all(np.isfinite(axes)) and np.all(np.isfinite(errors))):
        raise InvalidInputError("identify: axis positions and volumetric errors must be finite")
    G = design_matrix(axes, offsets, degree, travel, rigid=rigid)
    names = parameter_names(degree, rigid)
    e = errors.reshape(-1)
    if covariance is not None:
        C = np.asarray(covariance, float)
        Linv = np.linalg.inv(np.linalg.cholesky(C))            # (N, 3, 3) whitening blocks
        Gw = np.einsum("nij,njp->nip", Linv, G.reshape(-1, 3, G.shape[1])).reshape(G.shape)
        ew = np.einsum("nij,nj->ni", Linv, errors).reshape(-1)
    else:
        Gw, ew = G, e
    scale = np.linalg.norm(Gw, axis=0)
    scale[scale == 0] = 1.0
    U, s, Vt = np.linalg.svd(Gw / scale, full_matrices=False)
    rank = int(np.sum(s > s[0] * 1e-10))
    if rank < G.shape[1]:
        null = Vt[-1]
        worst = [names[i] for i in np.argsort(-np.abs(null))[:4]]
        raise InvalidInputError(f"identify: the {G.shape[1]} parameters are not identifiable from these positions "
                                f"(rank {rank}); e.g. {', '.join(worst)} are confounded. Measure with tool offsets in "
                                f"x, y and z and at least {degree + 1} positions per axis")
    coef = Vt.T @ ((U.T @ ew) / s)
    vector = coef / scale
    res = ew - Gw @ vector
    dof = Gw.shape[0] - Gw.shape[1]
    cov = (Vt.T / s ** 2) @ Vt / np.outer(scale, scale)
    sigma2 = 1.0 if covariance is not None else (float(res @ res) / dof if dof > 0 else float("nan"))
    model = ErrorModel.from_vector(vector, degree, travel, rigid=rigid)
    return Identification(model=model, names=names, vector=vector, covariance=cov * sigma2,
                          residual_rms=float(np.sqrt(np.mean((e - G @ vector) ** 2))), dof=dof)
