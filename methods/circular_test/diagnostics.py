"""Diagnostics of a circular test: the machine's error sources from the two runs, with standard
uncertainties, by least squares on the exact geometry of the error model (the trace patterns of
ISO 230-4 annex / Kakino et al. 1987, ref. 6 of the circle/ellipse paper).

The model moves the commanded point R u(theta), u = (cos theta, sin theta), of a run in direction d
(+1 CCW, -1 CW) about the nominal centre by the displacement D(theta) = sum_j beta_j G_j(theta) of its
sources (R = nominal radius; X, Y the nominal machine coordinates):

* centre offset (o_x, o_y): (o_x, o_y)                                            (nuisance)
* mean scale s: s R u (with the probe length, the common radius)                   (nuisance)
* scale mismatch s_x - s_y: (R / 2) (cos theta, -sin theta)
* squareness alpha (the Y axis leaning towards +X: the angle between +X and +Y is 90 deg - alpha): R (sin theta, 0)
* servo mismatch l_x - l_y (lag lengths l = tau v; in ms with the feed v): (d / 2) (sin theta, cos theta)
* backlash b_x: (d / 2) sign(sin theta) (1, 0);  b_y: -(d / 2) sign(cos theta) (0, 1)
* reversal spike h_x: d sign(sin theta) exp(-phi_x / phi_tau) (1, 0), phi_x the angle travelled since the
  X reversal (theta = 0, 180 deg) if that came at or after the run's first point (within
  ``START_TOLERANCE`` of its first sampling step: a run that starts at a reversal), else no spike; h_y
  likewise at the Y reversals; the decay angle phi_tau (0.1-10 deg: a slower decay is a backlash over
  the arc) is a parameter of the fit. At a reversal (|sin theta| or |cos theta| <= ``REVERSAL_ZONE``, or a
  run's first or last point within ``START_TOLERANCE`` of a step of one) the sign is 0: the axis is midway.
* cyclic error of pitch p: (a_x sin(2 pi X / p) + b_x cos(2 pi X / p), a_y sin(2 pi Y / p) + ...);
  amplitude = mean of the X and Y amplitudes
* and a radius difference between the runs, (d / 2) delta_rho along the radius            (nuisance).

Each measured point q is compared with the model path at the same polar angle about the nominal
centre: theta is solved from angle(R u(theta) + D(theta)) = angle(q) (fixed-point iteration to
roundoff), and the residual is |q| - |R u(theta) + D(theta)| - d delta_rho / 2. No small-angle
linearisation: a noise-free run of the model's sources is fitted to roundoff (tested from 90 to 360 deg).
The fit is Gauss-Newton with the analytic Jacobian (log phi_tau included; a backtracking line search by
Armijo's condition and quadratic interpolation, Nocedal & Wright, Numerical Optimization, 2nd ed., sec. 3.5,
eq. 3.58), from the first-order solution at the best phi_tau of a grid. ``_model['converged']`` is True only when
the fit ended before ``MAX_ITERATIONS`` at a point whose Gauss-Newton step is at most ``STATIONARY_U`` standard
uncertainties (or roundoff): a first-order optimum (:func:`_stationarity`); else False, with the reason in
``_model['message']`` (the estimates are then those of the last iterate). Not modelled: the common servo lag
l = (l_x + l_y) / 2, a displacement along the path only. It turns the CCW pattern by -l / R and the CW
pattern by +l / R, which reads as a servo mismatch of -2 l (s_x - s_y) and a scale mismatch of
2 l (l_x - l_y) / R^2 (second order: 0.002 um and 0.02 um/m for l = 33 um, 2 ms at 1000 mm/min, 30 um/m
and 8 um at R = 150 mm), and moves the steps at the reversals by l / R along the path.

Uncertainties: the covariance sigma^2 (J^T J)^+ of the full model at the solution (every source and
nuisance, phi_tau included), sigma^2 = RSS / (N - rank), N counting independent points: a run with repeated
samples is refused (:func:`methods.circular_test.evaluation.refuse_repeated`; each sample twice would divide
every u by sqrt 2). They assume independent residuals and are
optimistic where vibration or unmodelled errors leave correlated residuals. Every source stays in the
model whatever is reported, so a source the arc cannot separate does not leak into the others: its
confounding is in their uncertainties. A source is withheld (value None, with the reason) when:
(a) it is a backlash or reversal spike of an axis that does not reverse inside the arc (X reverses at 0
and 180 deg, Y at 90 and 270 deg); its estimate would rest on the runs' centre difference alone;
(b) its signature keeps less than ``IDENTIFIABLE_MIN`` of its norm after projection onto the span of all
the other columns (the inverse square root of its variance-inflation factor), or none (an exact
combination of them over the angles measured).
Over 400 random arcs of 90-360 deg with every source (the common lag included) and 0.5 um noise,
|estimate - truth| <= 1.96 u held for 94.9 % of the 3027 reported estimates (each source 93.9-96.1 %).
"""
from __future__ import annotations

import math

import numpy as np

from methods._errors import InvalidInputError
from methods.circular_test.evaluation import refuse_repeated

REVERSAL_ZONE = 1e-9  # |sin| or |cos| below which an axis is at its reversal: the sign of its motion is 0

SPIKE_DECAY_GRID_DEG = np.geomspace(0.1, 10.0, 13)  # a slower decay is a backlash over the arc
SPIKE_DECAY_BOUNDS_DEG = (SPIKE_DECAY_GRID_DEG[0], SPIKE_DECAY_GRID_DEG[-1])  # the fit's bounds on the decay angle
IDENTIFIABLE_MIN = 0.05   # fraction of a signature's norm left after projecting out the others
NUISANCE = ("center_x", "center_y", "mean_scale", "radius_difference")
REVERSAL_TERMS = {"backlash_x": "x", "reversal_spike_x": "x", "backlash_y": "y", "reversal_spike_y": "y"}
SOURCES = ("scale_mismatch", "squareness", "servo_mismatch", "backlash_x", "backlash_y", "reversal_spike_x",
           "reversal_spike_y")
CYCLIC = ("cyc_xs", "cyc_xc", "cyc_ys", "cyc_yc")
THETA_ITERATIONS = 50
MAX_ITERATIONS = 30
HALVINGS = 8
STEP_TOLERANCE = 1e-15  # of R: a Gauss-Newton step that moves the model by less has converged
RELATIVE_DECREASE = 1e-12  # a decrease of the sum of squares below this fraction of it is rounding: the fit stops
SUFFICIENT_DECREASE = 0.25  # Armijo's c1 of the line search (_fit): a full step must give half the decrease promised
STATIONARY_U = 1e-3  # converged: the Gauss-Newton step at the returned point is at most this many standard uncertainties
GRID_REVERSAL_ZONE = 1e-3  # rad: points this close to a reversal are left out of the start's grid
START_TOLERANCE = 0.1  # a reversal this fraction of the first sampling step before a run's first point is at it
NEAR_REVERSAL_SIGMAS = 3.0  # a sample whose commanded angle is this many sigma / R from a reversal is at it


def _has_reversal(theta, axis) -> bool:
    """Does the arc contain a reversal of ``axis`` (x: sin(theta) changes sign; y: cos(theta) does)?"""
    v = np.sin(theta) if axis == "x" else np.cos(theta)
    return bool(np.any(v > 0.05) and np.any(v < -0.05))


class _Model:
    """The runs (points about the nominal centre, direction, run boundaries) and the model's fields."""

    def __init__(self, q, d, first, R, center, pitch, names):
        self.q, self.d, self.first, self.R, self.center, self.pitch = q, d, first, R, center, pitch
        self.names = names                     # linear parameters, in order
        self.half_d, self.minus_half_d, self.minus_d = 0.5 * d, -0.5 * d, -d   # the fields' factors (exact)
        self.r = np.hypot(q[:, 0], q[:, 1])
        phi = np.arctan2(q[:, 1], q[:, 0])
        # unwrapped along each run (the run's own order), so theta is continuous within a run
        self.phi = np.concatenate([np.unwrap(phi[a:b]) for a, b in zip(first, list(first[1:]) + [len(q)])])
        self.run_of = np.repeat(np.arange(len(first)), np.diff(list(first) + [len(q)]))
        step = np.abs(self.phi[np.minimum(first + 1, len(q) - 1)] - self.phi[first])
        self.start_tol = (START_TOLERANCE * step)[self.run_of]
        # a run that starts or ends at a reversal angle (within START_TOLERANCE of a step): at that point the
        # axis is at its reversal (the sign of its motion 0), whatever side of it a fit's angle puts it on
        ends = np.zeros(len(q), bool)
        ends[first] = True
        ends[np.r_[first[1:] - 1, len(q) - 1]] = True
        self.at_reversal_x = ends & (np.abs(np.sin(self.phi)) < self.start_tol)
        self.at_reversal_y = ends & (np.abs(np.cos(self.phi)) < self.start_tol)

    def spike_decay(self, theta, at):
        """(exp(-phi / phi_tau) factor's phi: angle since the last reversal at ``at`` + k pi, or inf if
        that reversal came before the run's first point). Kept for the last ``theta`` array (the fit asks for the
        same angles' decays in the fields and the Jacobian)."""
        memo = self.__dict__.get("_decay")
        if memo is None or memo[0] is not theta:
            memo = self._decay = (theta, {})
        if at not in memo[1]:
            memo[1][at] = self._spike_decay(theta, at)
        return memo[1][at]

    def _spike_decay(self, theta, at):
        d = self.d
        theta0 = theta[self.first][self.run_of]
        tol = self.start_tol
        since = np.mod(d * (theta - at), np.pi)
        swept = d * (theta - theta0)
        return np.where(since <= swept + tol, since, np.inf)

    def fields(self, theta, phi_tau, derivative=False):
        """{name: G_j as its (x, y) components} (and {name: dG_j / dtheta} with ``derivative``)."""
        G, dG = self._fields(theta, phi_tau, derivative)[:2]
        return (G, dG) if derivative else G

    def _fields(self, theta, phi_tau, derivative):
        """(G, dG or None, cos theta, sin theta, the zero array of G's zero components, the one array of its unit
        ones): the fields of the model's parameters only, their derivatives only when asked (vectorised, called at
        every iteration of :meth:`theta`)."""
        R, d = self.R, self.d
        want = {n for n in self.names if n != "radius_difference"}
        c, s = np.cos(theta), np.sin(theta)
        zero, one = self._constant(c.shape)
        G, dG = {}, ({} if derivative else None)
        Rc, Rs = R * c, R * s
        G["center_x"], G["center_y"] = (one, zero), (zero, one)
        G["mean_scale"] = (Rc, Rs)
        G["scale_mismatch"] = (0.5 * R * c, -0.5 * R * s)
        G["squareness"] = (Rs, zero)
        G["servo_mismatch"] = (self.half_d * s, self.half_d * c)
        if derivative:
            dG["center_x"] = dG["center_y"] = (zero, zero)
            dG["mean_scale"] = (-R * s, R * c)
            dG["scale_mismatch"] = (-0.5 * R * s, -0.5 * R * c)
            dG["squareness"] = (R * c, zero)
            dG["servo_mismatch"] = (self.half_d * c, self.minus_half_d * s)
        if want & {"backlash_x", "reversal_spike_x"}:
            sx = np.where((np.abs(s) <= REVERSAL_ZONE) | self.at_reversal_x, 0.0, np.sign(s))  # 0 at a reversal
            G["backlash_x"] = (self.half_d * sx, zero)
            if "reversal_spike_x" in want:
                ex = np.exp(-self.spike_decay(theta, 0.0) / phi_tau)
                G["reversal_spike_x"] = (d * sx * ex, zero)
            if derivative:
                dG["backlash_x"] = (zero, zero)
                if "reversal_spike_x" in want:
                    dG["reversal_spike_x"] = (-sx * ex / phi_tau, zero)
        if want & {"backlash_y", "reversal_spike_y"}:
            sy = np.where((np.abs(c) <= REVERSAL_ZONE) | self.at_reversal_y, 0.0, np.sign(c))
            G["backlash_y"] = (zero, self.minus_half_d * sy)
            if "reversal_spike_y" in want:
                ey = np.exp(-self.spike_decay(theta, np.pi / 2) / phi_tau)
                G["reversal_spike_y"] = (zero, self.minus_d * sy * ey)
            if derivative:
                dG["backlash_y"] = (zero, zero)
                if "reversal_spike_y" in want:
                    dG["reversal_spike_y"] = (zero, sy * ey / phi_tau)
        if self.pitch and want & set(CYCLIC):
            k = 2 * np.pi / self.pitch
            X, Y = self.center[0] + Rc, self.center[1] + Rs
            sin_x, cos_x, sin_y, cos_y = np.sin(k * X), np.cos(k * X), np.sin(k * Y), np.cos(k * Y)
            G["cyc_xs"], G["cyc_xc"] = (sin_x, zero), (cos_x, zero)
            G["cyc_ys"], G["cyc_yc"] = (zero, sin_y), (zero, cos_y)
            if derivative:
                dG["cyc_xs"], dG["cyc_xc"] = (-k * R * s * cos_x, zero), (k * R * s * sin_x, zero)
                dG["cyc_ys"], dG["cyc_yc"] = (zero, k * R * c * cos_y), (zero, -k * R * c * sin_y)
        G = {n: G[n] for n in self.names if n != "radius_difference"}
        if derivative:
            dG = {n: dG[n] for n in G}
        return G, dG, c, s, zero, one

    def _constant(self, shape):
        """The zero and one arrays of the fields (shared by their calls: never written to)."""
        memo = self.__dict__.get("_zero_one")
        if memo is None or memo[0].shape != shape:
            memo = self._zero_one = (np.zeros(shape), np.ones(shape))
        return memo

    def path(self, theta, beta, phi_tau, derivative=False):
        """Model point(s) R u(theta) + D(theta) as (x, y) (and d/dtheta, and the fields). Each coordinate is summed
        on its own (the same operations, in the same order, as on (N, 2) rows, without building them). A unit
        component of a field adds beta_j itself; a zero one adds nothing, and is skipped with a finite beta_j when no
        angle is 0 (then no sum is -0, which adding +0 would turn into +0)."""
        G, dG, c, s, zero, one = self._fields(theta, phi_tau, derivative)
        px, py = self.R * c, self.R * s
        sums = [(px, py, G)]
        if derivative:
            sums.append((self.R * -s, self.R * c, dG))
        skip = not np.any(theta == 0.0)
        out = []
        for x, y, F in sums:
            for j, n in enumerate(self.names):
                b = beta[j]
                if n not in F or not b:
                    continue
                fin = skip and math.isfinite(b)
                gx, gy = F[n]
                if gx is not zero or not fin:
                    x = x + (b if gx is one else b * gx)
                if gy is not zero or not fin:
                    y = y + (b if gy is one else b * gy)
            out.append((x, y))
        return (*out, G) if derivative else out[0]

    def theta(self, beta, phi_tau):
        """The commanded angle of each point: angle(R u(theta) + D(theta)) = the measured angle."""
        warm = getattr(self, "_theta", None)  # the last solution: a warm start (the fit moves it little)
        theta = self.phi.copy() if warm is None else warm.copy()
        for _ in range(THETA_ITERATIONS):
            px, py = self.path(theta, beta, phi_tau)
            err = np.mod(np.arctan2(py, px) - self.phi + np.pi, 2 * np.pi) - np.pi
            theta = theta - err
            if np.max(np.abs(err)) <= 4 * np.finfo(float).eps * (1 + np.max(np.abs(theta))):
                break
        self._theta = theta
        return theta

    def residual(self, beta, phi_tau):
        theta = self.theta(beta, phi_tau)
        px, py = self.path(theta, beta, phi_tau)
        return self.r - np.hypot(px, py) - self._radial(beta), theta

    def _radial(self, beta):
        if "radius_difference" in self.names:
            return 0.5 * self.d * beta[self.names.index("radius_difference")]
        return 0.0

    def jacobian(self, beta, phi_tau, theta, log_tau=False):
        """d(model radius at the measured angle)/d beta_j (N, p): G_j . n - (p_theta . n) (G_j . t) / (p_theta . t)
        with n, t the unit radial and tangential directions of the model point (theta moves with beta); with
        ``log_tau`` a last column for log phi_tau (the spikes' G_j phi / phi_tau, times their amplitudes)."""
        (px, py), (ptx, pty), G = self.path(theta, beta, phi_tau, derivative=True)
        rn = np.hypot(px, py)
        nx, ny = px / rn, py / rn
        tx, ty = -ny, nx
        ratio = (ptx * nx + pty * ny) / (ptx * tx + pty * ty)
        out = np.empty((len(px), len(self.names) + bool(log_tau)))
        for j, name in enumerate(self.names):
            if name == "radius_difference":
                out[:, j] = 0.5 * self.d
                continue
            gx, gy = G[name]
            out[:, j] = (gx * nx + gy * ny) - ratio * (gx * tx + gy * ty)
        if log_tau:
            gx, gy = np.zeros_like(px), np.zeros_like(py)
            for name, at in (("reversal_spike_x", 0.0), ("reversal_spike_y", np.pi / 2)):
                if name in G:
                    since = self.spike_decay(theta, at)
                    w = np.where(np.isfinite(since), since / phi_tau, 0.0)
                    b = beta[self.names.index(name)]
                    gx += b * G[name][0] * w
                    gy += b * G[name][1] * w
            out[:, -1] = (gx * nx + gy * ny) - ratio * (gx * tx + gy * ty)
        return out

    def spike_first_order(self, theta, phi_tau):
        """The first-order columns of the X and Y reversal spikes at angles theta (N, 2)."""
        c, s = np.cos(theta), np.sin(theta)
        sx = np.where((np.abs(s) <= REVERSAL_ZONE) | self.at_reversal_x, 0.0, np.sign(s))
        sy = np.where((np.abs(c) <= REVERSAL_ZONE) | self.at_reversal_y, 0.0, np.sign(c))
        ex = np.exp(-self.spike_decay(theta, 0.0) / phi_tau)
        ey = np.exp(-self.spike_decay(theta, np.pi / 2) / phi_tau)
        return np.column_stack([self.d * sx * ex * c, -self.d * sy * ey * s])

    def first_order(self, theta, phi_tau):
        """The first-order (small-deviation) columns at angles theta: G_j . u."""
        G = self.fields(theta, phi_tau)
        ux, uy = np.cos(theta), np.sin(theta)
        return np.column_stack([0.5 * self.d if n == "radius_difference" else G[n][0] * ux + G[n][1] * uy
                                for n in self.names])


def _without_spikes(model):
    """The model without its reversal-spike terms (the same points and fields)."""
    plain = _Model.__new__(_Model)
    plain.__dict__.update(model.__dict__)
    plain.names = [n for n in model.names if not n.startswith("reversal_spike")]
    return plain


def _near_reversal(model):
    """(mask of the samples at a reversal within the noise, the commanded angles of the exact fit without spikes).

    A sample inside a run whose commanded angle lies within ``NEAR_REVERSAL_SIGMAS`` sigma / R of an axis reversal,
    sigma the robust standard deviation (1.4826 x the median absolute deviation) of that fit's radial residuals, may
    have been taken on either side of it: the noise along the path (taken as the radial noise's) decides the side the
    fit reads, while the data show the step taken or not. Fitted, its residual of the full backlash step was read as
    a one-sample spike (2.8 um inward, decay at the 0.1 deg bound, for a sample 0.18 um along the path from the
    reversal in 0.2 um noise). A run's first and last samples stay (``START_TOLERANCE`` handles them)."""
    _, _, res, theta, _, _ = _fit(_without_spikes(model), False)
    sigma = 1.4826 * float(np.median(np.abs(res - np.median(res))))
    near = np.minimum(np.abs(np.sin(theta)), np.abs(np.cos(theta))) <= NEAR_REVERSAL_SIGMAS * sigma / model.R
    near[model.first] = False
    near[np.r_[model.first[1:] - 1, len(near) - 1]] = False
    return near, theta


def _fit(model, spikes, plain_theta=None):
    """Least squares of the exact model: (beta, phi_tau, residuals, theta, J with the log phi_tau column, status:
    converged, iterations, gauss_newton_step_u, message).

    Gauss-Newton with the analytic Jacobian (log phi_tau included, held at its bound when the step would leave
    it) and a backtracking line search (``line_search``), from the first-order solution at the best phi_tau of a
    grid (and a bounded 1-D search about it). With spikes in the model, the grid is searched at the commanded
    angles of the exact fit without spikes (points next to a reversal are then on the right side of it), and
    again at those of the fit with them; the better fit is kept. The step used to be halved only until the sum
    of squares dropped: where the Gauss-Newton model overshoots along a flat, curved direction (the decay angle
    of spikes small against the noise) the full step was taken for any decrease and the fit zigzagged about the
    minimum up to the iteration limit (2 runs of 100,000 points: 30 iterations, 0.006 u from the minimum)."""
    from scipy.optimize import minimize_scalar  # imported on first use (light import)

    dr0 = model.r - model.R
    lo, hi = np.log(np.radians(SPIKE_DECAY_BOUNDS_DEG))
    cache = {}

    spike_cols = [j for j, n in enumerate(model.names) if n.startswith("reversal_spike")]
    spike_axes = [0 if model.names[j].endswith("_x") else 1 for j in spike_cols]
    base = {}

    def linear(phi_tau, theta):
        # points within GRID_REVERSAL_ZONE of a reversal are left out: which side of it a start's angles put
        # them on is uncertain, and a point on the wrong side would decide the grid alone
        if base.get("theta") is not theta:   # the columns but the spikes' depend on theta only
            keep = (np.abs(np.sin(theta)) > GRID_REVERSAL_ZONE) & (np.abs(np.cos(theta)) > GRID_REVERSAL_ZONE)
            base.update(theta=theta, keep=keep, X=model.first_order(theta, phi_tau)[keep], y=dr0[keep])
        keep, X, y = base["keep"], base["X"].copy(), base["y"]
        if spike_cols:
            X[:, spike_cols] = model.spike_first_order(theta, phi_tau)[keep][:, spike_axes]
        scale = np.linalg.norm(X, axis=0)
        scale[scale == 0] = 1.0
        coef, *_ = np.linalg.lstsq(X / scale, y, rcond=None)
        coef = coef / scale
        return float(np.sum((y - X @ coef) ** 2)), coef

    def start(theta):
        if not spikes:
            return np.radians(5.0), linear(np.radians(5.0), theta)[1]
        grid = np.radians(SPIKE_DECAY_GRID_DEG)
        rss = [linear(p, theta)[0] for p in grid]
        k = int(np.argmin(rss))
        a, b = np.log(grid[max(k - 1, 0)]), np.log(grid[min(k + 1, len(grid) - 1)])
        opt = minimize_scalar(lambda lp: linear(np.exp(lp), theta)[0], bounds=(a, b), method="bounded",
                              options={"xatol": 1e-4})
        phi_tau = float(np.exp(opt.x)) if opt.fun <= rss[k] else float(grid[k])
        return phi_tau, linear(phi_tau, theta)[1]

    def fun(x, phi_tau):
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = model.residual(x[:len(model.names)], np.exp(x[-1]) if spikes else phi_tau)
        return cache[key]

    def jac(x, phi_tau):
        theta = fun(x, phi_tau)[1]
        b = x[:len(model.names)]
        return -model.jacobian(b, np.exp(x[-1]) if spikes else phi_tau, theta, log_tau=spikes)

    def gn_step(J, res, x):
        """The Gauss-Newton step (least squares of the scaled Jacobian); with log phi_tau at a bound and the step
        leaving it, the step of the other parameters with it held there (the bound is active)."""
        sc = np.linalg.norm(J, axis=0)
        sc[sc == 0] = 1.0
        step = -np.linalg.lstsq(J / sc, res, rcond=None)[0] / sc
        if spikes and ((x[-1] <= lo and step[-1] < 0) or (x[-1] >= hi and step[-1] > 0)):
            step = np.append(-np.linalg.lstsq(J[:, :-1] / sc[:-1], res, rcond=None)[0] / sc[:-1], 0.0)
        return step

    def line_search(x, step, rss, D, phi_tau):
        """Backtracking on phi(t) = |res(x + t step)|^2 from t = 1 (or the bound of log phi_tau, if the step
        reaches it first): accepted at Armijo's sufficient decrease phi(t) <= phi(0) + c1 t phi'(0), phi'(0) = -2 D,
        c1 = SUFFICIENT_DECREASE (< 1/2: a step the Gauss-Newton model predicts well is always taken, Nocedal &
        Wright, Numerical Optimization, 2nd ed., thm 3.6); else the next t is the minimiser of the quadratic
        through phi(0), phi'(0) and phi(t) (ibid. eq. 3.58), at least t / 10 (Dennis & Schnabel, alg. A6.3.1).
        A step that overshoots (a flat, curved direction: the spike decay of small spikes in noise) is so cut to
        the minimum along it, where halving until the sum of squares drops zigzagged about it. A promised
        decrease D at rounding level (<= RELATIVE_DECREASE of phi(0)), or a trial without a finite phi: halving
        until phi drops. Returns
        (x, res, rss) of the step taken, or None when no trial lowered phi."""
        t = 1.0
        if spikes and not lo <= x[-1] + step[-1] <= hi:
            t = (np.clip(x[-1] + step[-1], lo, hi) - x[-1]) / step[-1]
        best = None
        for _ in range(HALVINGS):
            xn = x + t * step
            if spikes:
                xn[-1] = np.clip(xn[-1], lo, hi)
            rn = fun(xn, phi_tau)[0]
            rss_n = float(rn @ rn)
            if D <= RELATIVE_DECREASE * rss or not np.isfinite(rss_n):   # rounding (any decrease), or no number
                if rss_n <= rss:
                    return xn, rn, rss_n
                t *= 0.5
                continue
            if rss_n <= rss - 2 * SUFFICIENT_DECREASE * t * D:
                return xn, rn, rss_n
            if rss_n < rss and (best is None or rss_n < best[2]):
                best = xn, rn, rss_n
            t = max(D * t * t / (rss_n - rss + 2 * D * t), 0.1 * t)
        return best

    def gauss_newton(phi_tau, beta):
        x = np.concatenate([beta, [np.clip(np.log(phi_tau), lo, hi)]]) if spikes else beta
        res = fun(x, phi_tau)[0]
        rss = float(res @ res)
        stop = f"stopped at the iteration limit ({MAX_ITERATIONS})"
        for it in range(MAX_ITERATIONS):
            J = jac(x, phi_tau)
            step = gn_step(J, res, x)
            Jstep = J @ step
            if np.max(np.abs(Jstep)) <= STEP_TOLERANCE * model.R:   # the model moves by roundoff: converged
                stop = "the Gauss-Newton step moves the model by roundoff"
                break
            taken = line_search(x, step, rss, float(Jstep @ Jstep), phi_tau)
            if taken is None:
                stop = f"no step lowered the sum of squares ({HALVINGS} trials)"
                break
            done = taken[2] >= rss * (1 - RELATIVE_DECREASE)
            x, res, rss = taken
            if done:
                stop = f"the sum of squares decreased by less than {RELATIVE_DECREASE:g} of itself"
                break
        return rss, x, it + 1, stop

    theta_start = model.phi
    if spikes:   # the angles of the fit without spikes (``plain_theta``, if given): a start
        theta_start = _fit(_without_spikes(model), False)[3] if plain_theta is None else plain_theta
    phi_tau, beta = start(theta_start)
    rss, x, iterations, stop = gauss_newton(phi_tau, beta)
    if spikes:
        phi_tau2, beta2 = start(fun(x, phi_tau)[1])
        rss2, x2, iterations2, stop2 = gauss_newton(phi_tau2, beta2)
        if rss2 < rss:
            rss, x, iterations, stop = rss2, x2, iterations2, stop2
    res, theta = fun(x, phi_tau)
    J = -jac(x, phi_tau)  # d model / d x
    at_bound = None
    if spikes and x[-1] in (lo, hi):
        at_bound = -1 if x[-1] == lo else 1
    status = _stationarity(J, res, model.R, at_bound)
    check = status.pop("check")
    if stop.startswith("stopped at the iteration limit"):   # never converged at the limit, whatever the check says
        status["converged"] = False
        status["message"] = f"NOT converged: {stop}; {check}"
    else:
        status["message"] = (f"{'converged' if status['converged'] else 'NOT converged'}: {check}; Gauss-Newton stopped "
                             f"after {iterations} iterations: {stop}")
    status["iterations"] = iterations
    phi_tau = float(np.exp(x[-1])) if spikes else phi_tau
    return x[:len(model.names)], phi_tau, res, theta, J, status


def _stationarity(J, res, R, at_bound=None) -> dict:
    """Is the returned point a first-order optimum of the sum of squares? (the ``converged`` flag's check)

    J = d model / d x at the point, res = data - model. The Gauss-Newton step there, delta = (J^T J)^+ J^T res,
    promises the decrease D = |J delta|^2; with the covariance C = sigma^2 (J^T J)^+ of the estimates,
    |delta_j| <= u_j sqrt(D) / sigma for every parameter j (Cauchy-Schwarz in the metric of C^-1). Converged:
    D <= (STATIONARY_U sigma)^2 (no estimate is more than STATIONARY_U of its standard uncertainty from where
    that step leads), or J delta moves the model by at most STEP_TOLERANCE R at every point (roundoff: exact
    data). ``at_bound`` (-1 lower, +1 upper): log phi_tau, the last column, sits at that bound; if the step
    pushes it further out (the Karush-Kuhn-Tucker sign) the test is on the other columns with it held."""
    def step(A):   # (J delta, delta scaled by the columns' norms: its signs)
        sc = np.linalg.norm(A, axis=0)
        sc[sc == 0] = 1.0
        delta = np.linalg.lstsq(A / sc, res, rcond=None)[0]
        return (A / sc) @ delta, delta
    move, delta = step(J)
    held = ""
    if at_bound is not None and delta[-1] * at_bound > 0:   # the step would leave the bounds: the bound is active
        move = step(J[:, :-1])[0]
        held = "; the spike decay held at its bound, where the step would leave it"
    D = float(move @ move)
    rss = float(res @ res)
    sigma2 = rss / max(len(res) - J.shape[1], 1)
    in_u = float(np.sqrt(D / sigma2)) if sigma2 > 0 else (0.0 if D == 0 else float("inf"))
    roundoff = bool(np.max(np.abs(move), initial=0.0) <= STEP_TOLERANCE * R)
    ok = bool(D <= (STATIONARY_U ** 2) * sigma2 or roundoff)
    if roundoff:
        what = f"the Gauss-Newton step at the returned point moves the model by roundoff (<= {STEP_TOLERANCE:g} R)"
    else:
        what = (f"the Gauss-Newton step at the returned point is {in_u:.1e} standard uncertainties "
                f"({'<=' if ok else '>'} {STATIONARY_U:g})")
    return {"converged": ok, "gauss_newton_step_u": in_u, "check": what + held}


def _off_reversals(cw, ccw, center):
    """The runs without their samples whose measured angle about ``center`` is an axis reversal (0, 90, 180,
    270 deg to ``REVERSAL_ZONE``: a round angle grid, as ballbar exports resampled to whole steps have) inside the
    run, and how many were left out. At such a sample the sign of the axis' motion is undefined: the model puts it
    midway (half the backlash) where the data show the step taken or not, and the reversal spike fitted that one
    residual as a spike of about the full backlash (decay at its 0.1 deg bound, half the 0.2 deg sample step:
    -2.9 um, beyond 2 u, for a clean 3 um step; or "NOT converged"). A run's first and last samples stay."""
    kept, dropped = [], 0
    for pts in (cw, ccw):
        q = pts - center
        phi = np.unwrap(np.arctan2(q[:, 1], q[:, 0]))
        off = np.minimum(np.abs(np.sin(phi)), np.abs(np.cos(phi))) <= REVERSAL_ZONE
        off[[0, -1]] = False
        dropped += int(off.sum())
        kept.append(pts[~off])
    return kept[0], kept[1], dropped


def diagnose(cw, ccw, nominal_radius: float, nominal_center, *, feed_mm_min: float | None = None,
             cyclic_pitch: float | None = None, partial: bool | None = None) -> dict:
    """Estimates of the error sources with standard uncertainties: name -> {value, unit, u} (or value and u
    None with a ``note`` saying why the source is withheld); ``_model`` holds the nuisances and the fit.

    ``nominal_center`` in machine coordinates (needed for the cyclic error's phase); ``feed_mm_min``
    turns the servo mismatch into a time (ms; else the difference of the axes' lag lengths in um);
    ``cyclic_pitch`` (mm) enables the cyclic-error estimate. Each run's points in their recorded order."""
    if nominal_center is None:
        raise InvalidInputError("diagnostics need the nominal centre (--nominal-center X Y)")
    for v, n in ((feed_mm_min, "feed"), (cyclic_pitch, "cyclic pitch")):
        if v is not None and not (np.isfinite(v) and v > 0):
            raise InvalidInputError(f"the {n} must be a positive number, got {v!r}")
    if not (np.isfinite(nominal_radius) and nominal_radius > 0):
        raise InvalidInputError(f"the nominal radius must be a positive number, got {nominal_radius!r}")
    if not np.all(np.isfinite(np.asarray(nominal_center, dtype=float))):
        raise InvalidInputError(f"the nominal centre must be two finite numbers, got {nominal_center!r}")
    cw, ccw = np.asarray(cw, float), np.asarray(ccw, float)
    for pts, name in ((cw, "CW"), (ccw, "CCW")):   # sigma^2 = RSS / (N - rank) counts independent points only
        if pts.ndim == 2 and pts.shape[1:] == (2,):
            refuse_repeated(pts, name)
    R = float(nominal_radius)
    center = np.asarray(nominal_center, dtype=float)
    cw, ccw, at_reversal = (*_off_reversals(cw, ccw, center),)
    pts = np.vstack([cw, ccw])
    d = np.concatenate([-np.ones(len(cw)), np.ones(len(ccw))])
    q = pts - center
    theta = np.arctan2(q[:, 1], q[:, 0])
    if partial is None:
        a = np.sort(np.degrees(theta))
        partial = max(np.diff(a).max(initial=0.0), 360.0 - (a[-1] - a[0])) > 30.0
    names = ["center_x", "center_y", "mean_scale", "radius_difference", *SOURCES] + (list(CYCLIC) if cyclic_pitch else [])
    withheld = {}
    for term, axis in REVERSAL_TERMS.items():
        if not _has_reversal(theta, axis):
            withheld[term] = f"not identifiable from this arc: it contains no reversal of the {axis.upper()} axis"
    model = _Model(q, d, np.array([0, len(cw)]), R, center, cyclic_pitch, names)
    # a spike field that is zero on every point (no reversal at or after a run's start) is left out
    G = model.fields(model.phi, np.radians(5.0))
    model.names = names = [n for n in names if n == "radius_difference" or np.any(G[n])]
    spikes = any(n.startswith("reversal_spike") for n in names)
    if len(pts) <= len(names) + spikes:
        raise InvalidInputError("too few points for the diagnostics' model")
    near, plain_theta = _near_reversal(model) if spikes else (np.zeros(len(q), bool), None)
    if near.any():   # at a reversal within the noise: left out, as samples exactly at one are
        at_reversal += int(near.sum())
        q, d = q[~near], d[~near]
        model = _Model(q, d, np.array([0, len(cw) - int(near[:len(cw)].sum())]), R, center, cyclic_pitch, names)
        plain_theta = None
    beta, phi_tau, res, theta, J, status = _fit(model, spikes, plain_theta)

    # covariance of the full model (every source, the nuisances and phi_tau), by SVD of the scaled Jacobian
    scale = np.linalg.norm(J, axis=0)
    scale[scale == 0] = 1.0
    U, S, Vt = np.linalg.svd(J / scale, full_matrices=False)
    rank = int(np.sum(S > S[0] * max(J.shape) * np.finfo(float).eps * 16))
    dof = len(res) - rank
    if dof <= 0:
        raise InvalidInputError("too few points for the diagnostics' model")
    rss = float(np.sum(res ** 2))
    sigma2 = rss / dof
    Vr = Vt[:rank].T / S[:rank]
    inv_scaled = Vr @ Vr.T                                   # (Js^T Js)^+
    cov = sigma2 * inv_scaled / np.outer(scale, scale)
    null = np.linalg.norm(Vt[rank:], axis=0) if rank < len(S) else np.zeros(J.shape[1])
    frac = 1.0 / np.sqrt(np.maximum(np.diag(inv_scaled), 1e-300))  # norm left after projecting out the others
    for j, n in enumerate(names):
        if n in NUISANCE or n in withheld:
            continue
        if null[j] > 1e-6 or frac[j] < IDENTIFIABLE_MIN:
            withheld[n] = ("not identifiable from this arc: its signature is (nearly) a combination of the "
                           "others over the angles measured")
    for n in SOURCES + (CYCLIC if cyclic_pitch else ()):
        if n not in names and n not in withheld:
            withheld[n] = "not identifiable from this arc: no reversal of its axis at or after the runs' start"
    u = np.sqrt(np.maximum(np.diag(cov), 0.0))
    idx = {n: i for i, n in enumerate(names)}
    v_feed = feed_mm_min / 60.0 if feed_mm_min else None

    def item(name, scale_, unit):
        if name in withheld:
            return {"value": None, "unit": unit, "u": None, "note": withheld[name]}
        i = idx[name]
        return {"value": float(beta[i] * scale_), "unit": unit, "u": float(u[i] * abs(scale_))}

    out = {"squareness": item("squareness", 1e6, "urad"),
           "scale_mismatch": item("scale_mismatch", 1e6, "um/m"),
           "servo_mismatch": item("servo_mismatch", 1e3 / v_feed, "ms") if v_feed else item("servo_mismatch", 1e3, "um"),
           "backlash_x": item("backlash_x", 1e3, "um"), "backlash_y": item("backlash_y", 1e3, "um"),
           "reversal_spike_x": item("reversal_spike_x", 1e3, "um"),
           "reversal_spike_y": item("reversal_spike_y", 1e3, "um")}
    cyc_withheld = [n for n in CYCLIC if n in withheld]
    if cyclic_pitch and cyc_withheld:
        out["cyclic_error"] = {"value": None, "unit": "um", "u": None, "note": withheld[cyc_withheld[0]]}
    elif cyclic_pitch:
        amps, grads = [], []
        for a, b in (("cyc_xs", "cyc_xc"), ("cyc_ys", "cyc_yc")):
            va, vb = beta[idx[a]], beta[idx[b]]
            amp = float(np.hypot(va, vb))
            g = np.zeros(J.shape[1])
            if amp > 0:
                g[idx[a]], g[idx[b]] = va / amp, vb / amp
            amps.append(amp)
            grads.append(g)
        g = 0.5 * (grads[0] + grads[1])
        out["cyclic_error"] = {"value": 1e3 * 0.5 * (amps[0] + amps[1]), "unit": "um",
                               "u": 1e3 * float(np.sqrt(max(g @ cov @ g, 0.0)))}
    else:
        out["cyclic_error"] = {"value": None, "unit": "um", "u": None,
                               "note": "not estimated: give the ball-screw pitch (--cyclic-pitch)"}
    ms = beta[idx["mean_scale"]] * R
    dr = beta[idx["radius_difference"]]
    out["_model"] = {"centre_offset_um": [float(beta[idx["center_x"]] * 1e3), float(beta[idx["center_y"]] * 1e3)],
                     "radius_offset_um": {"cw": float((ms - 0.5 * dr) * 1e3), "ccw": float((ms + 0.5 * dr) * 1e3)},
                     "spike_decay_deg": float(np.degrees(phi_tau)),
                     "residual_rms_um": float(np.sqrt(rss / len(res)) * 1e3), "points": int(len(res)),
                     "left_out_at_reversal": at_reversal,
                     "partial_arc": bool(partial), "not_identifiable": sorted(withheld),
                     "converged": status["converged"], "iterations": status["iterations"],
                     "gauss_newton_step_u": status["gauss_newton_step_u"], "message": status["message"]}
    return out
