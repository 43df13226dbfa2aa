"""Synthetic circular tests (ISO 230-4) of an NC machine with known error sources.

The commanded path is a circle of nominal radius R about the nominal centre, run at feed F (mm/min)
clockwise or counter-clockwise from a start angle, sampled at f_s (Hz), with optional run-in and
run-out arcs (not part of the evaluated trace). A partial arc (``arc_deg`` < 360) also has a sample at
exactly its start and its end angle, as ballbar software records the nominal arc. Each error source moves the actual axis positions:

* ``scale_x``, ``scale_y`` (dimensionless, e.g. 30e-6 = 30 um/m): dx = s_x (x - x_c), dy = s_y (y - y_c);
* ``squareness`` (rad): dx = alpha (y - y_c), the X axis leans towards Y;
* ``lag_x``, ``lag_y`` (s): servo following errors, dx = -tau_x vx, dy = -tau_y vy; their difference is
  the servo mismatch (a 45 deg ellipse whose inclination flips with the direction);
* ``backlash_x``, ``backlash_y`` (mm): lost motion, the axis lags by b/2 against its motion:
  dx = -(b_x / 2) sign(vx);
* ``spike_x``, ``spike_y`` (mm) with ``spike_tau`` (s): reversal spikes, after each reversal of an axis a
  transient lag dx = -h sign(vx) exp(-dt / tau) (stick-slip; an outward bump at the quadrant point);
* ``cyclic_amplitude`` (mm) with ``cyclic_pitch`` (mm): ball-screw cyclic error on both axes,
  dx = A sin(2 pi x / p), dy = A sin(2 pi y / p), in absolute machine coordinates;
* ``straightness_y`` (mm): the X axis' straightness in Y, dy = S ((x - x_c) / R)^2;
* ``vibration_y`` (mm) with ``vibration_hz``: dy = A sin(2 pi f t) (the paper saw 4 Hz on Y);
* ``drift_x``, ``drift_y`` (mm/s): slow thermal drift of the axes during the run, dx = drift_x t;
* ``noise`` (mm): Gaussian, per coordinate;
* ``offset_x``, ``offset_y`` (mm): the instrument's centre away from the nominal centre (set-up).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

#: |sin| or |cos| of the commanded angle below which an axis is at its reversal (velocity sign 0: backlash
#: and spike midway); a partial arc that starts or ends at a reversal angle hits it to roundoff
REVERSAL_ZONE = 1e-9


@dataclass
class MachineErrors:
    scale_x: float = 0.0
    scale_y: float = 0.0
    squareness: float = 0.0
    lag_x: float = 0.0
    lag_y: float = 0.0
    backlash_x: float = 0.0
    backlash_y: float = 0.0
    spike_x: float = 0.0
    spike_y: float = 0.0
    spike_tau: float = 0.05
    cyclic_amplitude: float = 0.0
    cyclic_pitch: float = 10.0
    straightness_y: float = 0.0
    vibration_y: float = 0.0
    vibration_hz: float = 4.0
    drift_x: float = 0.0
    drift_y: float = 0.0
    noise: float = 0.0
    offset_x: float = 0.0
    offset_y: float = 0.0

    @property
    def servo_mismatch(self) -> float:
        """lag_x - lag_y (s)."""
        return self.lag_x - self.lag_y


@dataclass
class TestConditions:
    """What ISO 230-4 asks to record with a circular test."""

    __test__ = False  # not a pytest test class

    nominal_radius: float = 298.997
    nominal_center: tuple = (1200.0, 650.0)
    feed_mm_min: float = 1000.0
    sampling_hz: float = 30.0
    start_angle_deg: float = 239.0
    run_in_deg: float = 0.0
    run_out_deg: float = 0.0
    arc_deg: float = 360.0          # ISO 230-4 partial arcs (e.g. 220 deg in a vertical plane)
    plane: str = "X/Y"
    machine: str = "synthetic"
    extra: dict = field(default_factory=dict)


def _since_reversal(theta, theta0, d, omega, at):
    """Exact time since the axis last reversed: X reverses where theta = k pi (at = 0), Y where
    theta = pi/2 + k pi (at = pi/2); inf if that reversal came before the motion started."""
    phi = np.mod(d * (theta - at), np.pi)  # angle travelled since the last reversal
    swept = d * (theta - theta0)
    return np.where(phi <= swept, phi / omega, np.inf)


def trace(direction: str, cond: TestConditions, err: MachineErrors, rng: np.random.Generator | None = None):
    """One run: returns (points (N, 2) of the evaluated full circle, dict with time, commanded points,
    nominal angles and the run-in/run-out parts). ``direction`` is 'cw' or 'ccw'."""
    if direction not in ("cw", "ccw"):
        raise ValueError(f"direction must be 'cw' or 'ccw', got {direction!r}")
    d = 1.0 if direction == "ccw" else -1.0
    R = cond.nominal_radius
    xc, yc = cond.nominal_center
    v = cond.feed_mm_min / 60.0
    omega = v / R
    run_in, run_out = np.radians(cond.run_in_deg), np.radians(cond.run_out_deg)
    arc = np.radians(cond.arc_deg)
    total_angle = arc + run_in + run_out
    dt = 1.0 / cond.sampling_hz
    t = np.arange(0.0, total_angle / omega, dt)
    if cond.arc_deg < 360:  # a partial arc is recorded from exactly its start to exactly its end angle
        t = np.union1d(t, [run_in / omega, (run_in + arc) / omega])
    theta = np.radians(cond.start_angle_deg) - d * run_in + d * omega * t
    x = xc + R * np.cos(theta)
    y = yc + R * np.sin(theta)
    vx = -d * omega * R * np.sin(theta)
    vy = d * omega * R * np.cos(theta)
    vx[np.abs(vx) <= REVERSAL_ZONE * omega * R] = 0.0  # at a reversal (to roundoff): the velocity's sign is 0
    vy[np.abs(vy) <= REVERSAL_ZONE * omega * R] = 0.0
    dx = err.scale_x * (x - xc) + err.squareness * (y - yc) - err.lag_x * vx - 0.5 * err.backlash_x * np.sign(vx)
    dy = err.scale_y * (y - yc) - err.lag_y * vy - 0.5 * err.backlash_y * np.sign(vy)
    if err.spike_x:
        dx -= err.spike_x * np.sign(vx) * np.exp(-_since_reversal(theta, theta[0], d, omega, 0.0) / err.spike_tau)
    if err.spike_y:
        dy -= err.spike_y * np.sign(vy) * np.exp(-_since_reversal(theta, theta[0], d, omega, np.pi / 2) / err.spike_tau)
    if err.cyclic_amplitude:
        dx += err.cyclic_amplitude * np.sin(2 * np.pi * x / err.cyclic_pitch)
        dy += err.cyclic_amplitude * np.sin(2 * np.pi * y / err.cyclic_pitch)
    if err.straightness_y:
        dy += err.straightness_y * ((x - xc) / R) ** 2
    if err.vibration_y:
        dy += err.vibration_y * np.sin(2 * np.pi * err.vibration_hz * t)
    if err.drift_x or err.drift_y:
        dx = dx + err.drift_x * t
        dy = dy + err.drift_y * t
    if err.noise:
        if rng is None:
            raise ValueError("noise needs an explicit numpy Generator (rng)")
        dx = dx + rng.normal(0.0, err.noise, t.shape)
        dy = dy + rng.normal(0.0, err.noise, t.shape)
    pts = np.column_stack([x + dx + err.offset_x, y + dy + err.offset_y])
    swept = d * (theta - theta[0])
    end = (swept < run_in + arc) if cond.arc_deg >= 360 else (swept <= run_in + arc + 1e-12)
    evaluated = (swept >= run_in - 1e-12) & end
    info = {"t": t[evaluated], "commanded": np.column_stack([x, y])[evaluated], "theta": theta[evaluated],
            "direction": direction, "run_in": pts[swept < run_in - 1e-12],
            "run_out": pts[(swept >= run_in - 1e-12) & ~end]}
    return pts[evaluated], info


def circular_test(cond: TestConditions | None = None, err: MachineErrors | None = None, seed: int | None = 0):
    """Both runs of a test: (cw points, ccw points, truth dict)."""
    cond = cond or TestConditions()
    err = err or MachineErrors()
    ss = np.random.SeedSequence(seed)
    rng_cw, rng_ccw = (np.random.default_rng(s) for s in ss.spawn(2))
    cw, info_cw = trace("cw", cond, err, rng_cw)
    ccw, info_ccw = trace("ccw", cond, err, rng_ccw)
    truth = {"conditions": asdict(cond), "errors": asdict(err), "servo_mismatch_s": err.servo_mismatch,
             "info": {"cw": info_cw, "ccw": info_ccw}}
    return cw, ccw, truth


def lola_hbg130(seed: int = 2004) -> tuple[TestConditions, MachineErrors]:
    """A scenario like the circle/ellipse paper's test of the LOLA HBG 130 (sec. 3.3): R = 298.997 mm,
    1000 mm/min, 30 Hz, start 239 deg, centre (1200, 650) mm. Its errors are chosen so that the paths are
    the ellipse of tables 3-5 (a - b = 22.1 um, major axis at 32.04 deg, the same in both directions,
    hence scale mismatch and squareness rather than servo mismatch), the mean radius and centre of
    tables 1-2 (299.0132 mm: +16.2 um of mean scale; (-11.84, 9.81) um from the nominal centre), larger deviations at the Y reversals S2 and S4 (spikes), the
    4 Hz Y vibration, and 0.5 um noise. The paper's measured data are not published: these numbers are
    what its tables imply, not a measurement."""
    R = 298.997
    a_minus_b = 0.0221  # mm, tables 3-5
    gamma = np.radians(32.04)  # major-axis direction
    mean_scale = (299.0132 - R) / R
    # radial deviation R(s_mean + ds/2 cos 2theta + alpha/2 sin 2theta) = (a-b)/2 cos 2(theta - gamma)
    ds = a_minus_b * np.cos(2 * gamma) / R
    alpha = a_minus_b * np.sin(2 * gamma) / R
    cond = TestConditions(nominal_radius=R, nominal_center=(1200.0, 650.0), feed_mm_min=1000.0, sampling_hz=30.0,
                          start_angle_deg=239.0, run_in_deg=10.0, run_out_deg=10.0, machine="LOLA HBG 130 (synthetic)",
                          extra={"temperature_C": 20.0, "axes_not_under_test": "Z-200 mm, W-700 mm"})
    err = MachineErrors(scale_x=mean_scale + ds / 2, scale_y=mean_scale - ds / 2, squareness=alpha,
                        spike_y=0.004, spike_tau=0.3, vibration_y=0.0008, vibration_hz=4.0, noise=0.0005,
                        offset_x=-0.01184, offset_y=0.00981)  # the centre of tables 1-2
    return cond, err
