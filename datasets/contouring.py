"""Synthetic 2D contouring tests like the magnification paper's figures 3-5 (Ibaraki & Matsubara 2009).

Each example returns (reference polyline (M, 2), measured trajectory (N, 2)). The measured trajectories
come from a second-order servo per axis (natural frequency ``wn``, damping ``zeta``) following the
reference at constant feed: corner rounding (undershoot) followed by a small overshoot, as the paper
measured with a cross grid encoder (about 60 um and 3 um at a square corner)."""
from __future__ import annotations

import numpy as np


def arc(center, radius, start, end, step_deg=0.5):
    """Points of an arc (radians), a fine polyline."""
    n = max(int(abs(np.degrees(end - start)) / step_deg), 2)
    t = np.linspace(start, end, n + 1)
    return np.column_stack([center[0] + radius * np.cos(t), center[1] + radius * np.sin(t)])


def resample(poly: np.ndarray, spacing: float) -> np.ndarray:
    """Points every ``spacing`` along a polyline (the commanded positions at constant feed)."""
    seg = np.hypot(*np.diff(poly, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    q = np.arange(0.0, s[-1], spacing)
    return np.column_stack([np.interp(q, s, poly[:, 0]), np.interp(q, s, poly[:, 1])])


def servo(commanded: np.ndarray, dt: float, wn: float = 60.0, zeta: float = 0.7) -> np.ndarray:
    """Each axis through a second-order system wn^2 / (s^2 + 2 zeta wn s + wn^2), starting at rest on the path."""
    from scipy.signal import lsim  # scipy.signal takes ~1 s to import: loaded when a contouring example is made
    t = np.arange(len(commanded)) * dt
    out = np.empty_like(commanded)
    for j in range(2):
        u = commanded[:, j] - commanded[0, j]
        _, y, _ = lsim(([wn ** 2], [1.0, 2 * zeta * wn, wn ** 2]), u, t)
        out[:, j] = y + commanded[0, j]
    return out


def square_corner(feed_mm_s=20.0, dt=0.0005, wn=120.0, zeta=0.55, leg=20.0, convex=True):
    """A square corner (fig. 3): along +x, then a 90 deg turn (left turn: 'convex' seen from the right)."""
    ref = np.array([[0.0, 0.0], [leg, 0.0], [leg, leg if convex else -leg]])
    cmd = resample(ref, feed_mm_s * dt)
    return ref, servo(cmd, dt, wn, zeta)


def segments_and_arcs(feed_mm_s=50.0, dt=0.001, wn=70.0, zeta=0.55):
    """Segments joined at sharp corners, and arcs (fig. 4)."""
    ref = np.vstack([[[0.0, 0.0], [30.0, 0.0]], arc((30.0, 10.0), 10.0, -np.pi / 2, 0.0)[1:], [[40.0, 30.0]],
                     [[20.0, 40.0]], arc((10.0, 40.0), 10.0, 0.0, np.pi / 2)[1:], [[0.0, 50.0]], [[0.0, 20.0]]])
    cmd = resample(ref, feed_mm_s * dt)
    return ref, servo(cmd, dt, wn, zeta)


def free_form(feed_mm_s=20.0, dt=0.001, wn=120.0, zeta=0.7, segment=0.1):
    """A free-form curve programmed as 0.1 mm segments (fig. 5); the machine follows the smooth curve."""
    x = np.linspace(0.0, 40.0, 4001)
    smooth = np.column_stack([x, 5.0 * np.sin(x / 6.0) + 2.0 * np.sin(x / 2.3)])
    ref = resample(smooth, segment)
    ref = np.vstack([ref, smooth[-1]])
    cmd = resample(smooth, feed_mm_s * dt)
    return ref, servo(cmd, dt, wn, zeta)


def circle_glitches(radius=50.0, glitch=0.004, width_deg=3.0, n=3600, noise=0.0002, seed=0):
    """A circle with quadrant glitches (stick motion at the axis reversals): the reference is a fine
    polyline of the circle."""
    rng = np.random.default_rng(seed)
    ref = arc((0.0, 0.0), radius, 0.0, 2 * np.pi, step_deg=0.25)
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    since = np.mod(t, np.pi / 2)
    r = radius + glitch * np.exp(-np.degrees(since) / width_deg) + rng.normal(0.0, noise, n)
    return ref, np.column_stack([r * np.cos(t), r * np.sin(t)])


def corner_path(side: str, turn: str, error=0.06, leg=10.0, n=2001):
    """A square corner of the reference and a measured path that passes it on one side with a smooth
    error bump of ``error`` (mm) at the corner: ``side`` 'inside' (cutting the corner) or 'outside'
    (overshooting), ``turn`` 'left' (the inside is on the left) or 'right'. The same path seen from the
    other side of the corner is the concave case: inside-left = convex corner cut, outside-left = the path
    outside the convex corner, i.e. inside the concave one."""
    sgn = 1.0 if turn == "left" else -1.0
    ref = np.array([[0.0, 0.0], [leg, 0.0], [leg, sgn * leg]])
    s = np.linspace(-leg, leg, n)  # arc length from the corner
    on = np.where(s[:, None] < 0, np.column_stack([leg + s, 0 * s]), np.column_stack([leg + 0 * s, sgn * s]))
    bump = error * np.exp(-(s / (10 * error)) ** 2)
    inward = np.array([-1.0, sgn]) / np.sqrt(2.0)  # towards the inside of the corner
    direction = inward if side == "inside" else -inward
    return ref, on + bump[:, None] * direction + 0.1 * error * np.column_stack([np.zeros(n), np.zeros(n)])


EXAMPLES = {"corner_inside_convex": lambda: corner_path("inside", "left"),
            "corner_outside_convex": lambda: corner_path("outside", "left"),
            "corner_inside_concave": lambda: corner_path("outside", "right"),
            "corner_outside_concave": lambda: corner_path("inside", "right"),
            "square_corner_servo": lambda: square_corner(convex=True),
            "segments_and_arcs": segments_and_arcs,
            "free_form_0.1mm": lambda: free_form(wn=40.0),
            "circle_quadrant_glitches": circle_glitches}
