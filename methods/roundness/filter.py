"""The Gaussian profile filter of ISO 16610-21:2011 for closed profiles (roundness), and the harmonic
spectrum of a closed profile.

ISO 16610-21 clause 5.2 gives the weighting function of a closed profile as the periodic Gaussian, and
clause 5.3.1 its transmission characteristic for the long-wave component (the filtered profile): a
harmonic of k undulations per revolution (UPR) is passed with the factor

    a(k) = exp(-pi (alpha k / lambda_c)^2),   alpha = sqrt(ln 2 / pi)            (ISO 16610-21 clause 5.3.1)

so that exactly 50 % of the amplitude passes at the cut-off k = lambda_c (clause 3 of ISO 16610-21 and
ISO 16610-20 define the cut-off by that 50 % transmission). Because the profile is closed, its Fourier
series has integer harmonics only and the filter is exact in the frequency domain: the discrete Fourier
transform of equally spaced samples, each harmonic multiplied by a(k), and the inverse transform.

Unequally spaced angles: a weighted convolution with the periodic Gaussian weighting function of
clause 5.2, s(x) = sum_m exp(-pi ((x + 2 pi m) / (alpha lambda))^2) / (alpha lambda), lambda = 2 pi / lambda_c
rad, by the trapezoidal rule on the measured angles and normalised by the sum of the weights:

    w(theta_i) = sum_j s(theta_i - theta_j) z_j D_j / sum_j s(theta_i - theta_j) D_j,  D_j = (theta_j+1 - theta_j-1)/2

Every output is a convex combination of the data (no overshoot, however the points cluster or the noise
is), a constant passes exactly, and the transmission approaches a(k) as the spacing shrinks (trapezoid
error O((h / (alpha lambda))^2)); the tests measure it against the equal-spacing FFT path. (Resampling by
a periodic cubic spline was tried first and rejected: on noisy data at random angles the spline through
nearly coincident points overshoots by orders of magnitude more than the noise.)

Both sums are evaluated in O(N log N + K log K) through the Fourier series of s, whose coefficients are
a(k) / (2 pi): sum_j s(theta - theta_j) c_j = (1 / 2 pi) sum_|k|<=K a(k) e^{ik theta} sum_j c_j e^{-ik theta_j}, one
type-1 and one type-2 non-uniform FFT (FINUFFT: Barnett, Magland & af Klinteberg, SIAM J. Sci. Comput. 41
(2019) C479-C504) at the requested tolerance NUFFT_TOL, with K the smallest harmonic where a(K) < 1e-17.
Error bound: each sum is off by at most NUFFT_TOL x sum_j |c_j| / (2 pi) x sum_k a(k) (FINUFFT's relative
accuracy on each Fourier coefficient) plus the truncated tail below 1e-17 x sum_j |c_j|; the normalised output
is off from the direct convolution by about 1e-12 x max|z| (tests/test_roundness.py measures it). The
direct O(N^2) convolution (:func:`convolution_filter`) is kept as the reference.

Sampling (ISO 12181-2:2011, the specification operator: about 7 points per cut-off wavelength, i.e. at
least 7 lambda_c points per revolution): with N >= 7 lambda_c the Nyquist harmonic N/2 >= 3.5 lambda_c is
passed with a(3.5 lambda_c) = 2e-4 at most, so everything the filter passes lies below the Nyquist harmonic
and is carried by the samples; a direct discrete convolution with the sampled periodic Gaussian has the
transmission sum_m a(k + m N), off from a(k) by about a(N - k), i.e. by up to 2e-4 near N/2 at N = 7 lambda_c.
Below 7 lambda_c, harmonics that the filter still passes noticeably lie beyond the Nyquist harmonic and
the data cannot carry them: :func:`check_sampling` warns.
"""
from __future__ import annotations

import math
import warnings

import numpy as np

from methods._errors import InvalidInputError

ALPHA = math.sqrt(math.log(2.0) / math.pi)
#: The cut-offs of ISO 12181-2 / ISO 16610-21 in UPR (any positive value is accepted too).
STANDARD_CUTOFFS_UPR = (15, 50, 150, 500, 1500)
#: ISO 12181-2's sampling recommendation: points per revolution >= this factor x the cut-off in UPR.
POINTS_PER_CUTOFF = 7
#: requested relative accuracy of the non-uniform FFTs of the unequal-spacing filter
NUFFT_TOL = 1e-13
#: Angles count as equally spaced when each lies within this fraction of a step 2 pi / N from an equal grid
#: (an eccentricity e of the instrument's spindle about the LSCI centre displaces them by e / R rad).
EQUAL_SPACING_TOL = 1e-3
#: A profile is open when its largest angular step exceeds this many median steps and ISO 12181-2's spacing
#: for the cut-off (:func:`check_closed`).
GAP_MEDIAN_STEPS = 25


class UndersampledWarning(UserWarning):
    """Fewer points per revolution than ISO 12181-2 recommends for the cut-off."""


def parse_cutoff(cutoff_upr, where: str = "roundness") -> float | None:
    """``None``/``'none'``/``0``-free check: ``None`` or ``'none'`` means no filter; else a positive finite
    number of UPR (15, 50, 150, 500, 1500 are the standard's; any positive value is allowed)."""
    if cutoff_upr is None or (isinstance(cutoff_upr, str) and cutoff_upr.strip().lower() in ("none", "off", "")):
        return None
    try:
        value = float(cutoff_upr)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{where}: cut-off {cutoff_upr!r} is not a number of UPR; give e.g. 50, or 'none'") from None
    if not math.isfinite(value) or value <= 0:
        raise InvalidInputError(f"{where}: the cut-off must be a positive number of UPR (e.g. 15, 50, 150, 500, 1500) "
                                f"or 'none', got {cutoff_upr!r}")
    return value


def transmission(k, cutoff_upr: float) -> np.ndarray:
    """ISO 16610-21 clause 5.3.1: a(k) = exp(-pi (alpha k / lambda_c)^2), k in UPR."""
    k = np.asarray(k, dtype=float)
    return np.exp(-np.pi * (ALPHA * k / cutoff_upr) ** 2)


def check_sampling(n_points: int, cutoff_upr: float | None) -> str | None:
    """Warn (and return the message) when N < 7 lambda_c (ISO 12181-2's sampling recommendation)."""
    if cutoff_upr is None or n_points >= POINTS_PER_CUTOFF * cutoff_upr:
        return None
    msg = (f"{n_points} points per revolution are fewer than {POINTS_PER_CUTOFF} x the {cutoff_upr:g} UPR cut-off "
           f"(= {math.ceil(POINTS_PER_CUTOFF * cutoff_upr)}): the profile is under-sampled for this filter "
           f"(ISO 12181-2); use a lower cut-off (<= {n_points / POINTS_PER_CUTOFF:.3g} UPR) or more points")
    warnings.warn(msg, UndersampledWarning, stacklevel=3)
    return msg


def order_by_angle(angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(order, unwrapped angles): the profile's points sorted by polar angle, angles increasing from the
    first one within [theta_0, theta_0 + 2 pi). Two points at the same angle are refused."""
    a = np.mod(angles, 2 * np.pi)
    order = np.argsort(a, kind="stable")
    a = a[order]
    steps = np.diff(np.concatenate([a, [a[0] + 2 * np.pi]]))
    if np.min(steps) <= 1e-12:
        j = int(np.argmin(steps))
        i, k = sorted((int(order[j]) + 1, int(order[(j + 1) % len(order)]) + 1))   # 1-based, in the input's order
        raise InvalidInputError(f"roundness: two points lie at the same polar angle (points {i} and {k} in the "
                                "order given); a closed profile needs one point per angle (drop a repeated closing "
                                "point, or keep one revolution of a trace recorded over more)")
    return order, a


def check_closed(sorted_angles: np.ndarray, cutoff_upr: float | None) -> None:
    """Refuse an open profile (an arc, or a revolution with a part missing): ISO 12181-1:2011 defines the
    roundness parameters on the closed roundness profile, the whole circumference of the section, and the
    ISO 16610-21 clause 5 filter is the closed-profile (periodic) one, which would join the two ends of an arc
    across the gap as if they were neighbours.

    The largest angular step between neighbouring points (the wrap-around one included) is a gap when it
    exceeds both
      * GAP_MEDIAN_STEPS x the median step: more than the spacing's own irregularity (uniformly random
        angles, the most irregular closed sampling, have a largest step of about ln(N) / ln(2) median steps,
        10 to 17 for 1e3 to 1e5 points), and
      * the step ISO 12181-2 asks of the sampling for the cut-off, 2 pi / (7 lambda_c), at most 2 pi / 7
        (7 points per revolution); unfiltered: no such term (the median rule alone),
    so the check refuses what is missing, never a sparse but spread-out sampling the standard allows."""
    n = sorted_angles.size
    steps = np.diff(np.concatenate([sorted_angles, [sorted_angles[0] + 2 * np.pi]]))
    i = int(np.argmax(steps))
    gap, median = float(steps[i]), float(np.median(steps))
    limit = GAP_MEDIAN_STEPS * median
    spec = ""
    if cutoff_upr is not None:
        spacing = 2 * np.pi / (POINTS_PER_CUTOFF * max(cutoff_upr, 1.0))
        spec = f" and than the {math.degrees(spacing):.3g}° spacing ISO 12181-2 allows at a {cutoff_upr:g} UPR cut-off"
        limit = max(limit, spacing)
    if gap <= limit:
        return
    start = math.degrees(np.mod(sorted_angles[i], 2 * np.pi))
    end = math.degrees(np.mod(sorted_angles[(i + 1) % n], 2 * np.pi))
    raise InvalidInputError(
        f"roundness: the profile is open: no point between {start:.1f}° and {end:.1f}° (a gap of {math.degrees(gap):.3g}°, "
        f"wider than {GAP_MEDIAN_STEPS} x the median spacing of {math.degrees(median):.3g}°{spec}); ISO 12181 roundness "
        "is defined on the closed profile: measure the whole circumference, or fit a circle to the arc "
        "(fitbench fit circle.minimum_zone FILE) for its centre, radius and form error")


def equal_grid_origin(sorted_angles: np.ndarray, tol: float = EQUAL_SPACING_TOL) -> float | None:
    """theta_0 when the sorted angles are theta_0 + 2 pi j / N to within ``tol`` steps each (theta_0: the
    mean offset), else None. Treating them as the grid moves harmonic k by at most k tol 2 pi / N rad, i.e. by
    at most pi tol rad at the Nyquist harmonic."""
    n = sorted_angles.size
    h = 2 * np.pi / n
    offsets = sorted_angles - h * np.arange(n)
    origin = float(np.mean(offsets))
    return origin if float(np.max(np.abs(offsets - origin))) <= tol * h else None


def equally_spaced(sorted_angles: np.ndarray, tol: float = EQUAL_SPACING_TOL) -> bool:
    """True when the sorted angles lie on an equal grid of N steps (see :func:`equal_grid_origin`)."""
    return equal_grid_origin(sorted_angles, tol) is not None


def fft_filter(values: np.ndarray, cutoff_upr: float) -> np.ndarray:
    """The closed-profile Gaussian filter of N equally spaced samples (one revolution): each harmonic k of
    the DFT multiplied by a(k) (ISO 16610-21 clause 5.3.1). Exact for every harmonic 0..N/2."""
    n = values.size
    spec = np.fft.rfft(values)
    spec *= transmission(np.arange(spec.size), cutoff_upr)
    return np.fft.irfft(spec, n)


def periodic_gaussian_weights(x: np.ndarray, cutoff_upr: float) -> np.ndarray:
    """The closed-profile weighting function s(x) of ISO 16610-21 clause 5.2 (x in rad, any shape):
    the Gaussian of width alpha lambda, lambda = 2 pi / lambda_c, summed over its 2 pi images."""
    width = ALPHA * 2 * np.pi / cutoff_upr
    x = np.mod(np.asarray(x, dtype=float) + np.pi, 2 * np.pi) - np.pi
    images = math.ceil(6 * ALPHA / cutoff_upr + 0.5)   # images beyond this weigh < exp(-36 pi) relative
    out = np.zeros_like(x)
    for m in range(-images, images + 1):
        out += np.exp(-np.pi * ((x + 2 * np.pi * m) / width) ** 2)
    return out / width


def convolution_filter(sorted_angles: np.ndarray, values: np.ndarray, cutoff_upr: float,
                       block_elements: int = 4_000_000) -> np.ndarray:
    """The normalised trapezoidal convolution of the module docstring (any spacing), in row blocks."""
    n = sorted_angles.size
    ext = np.concatenate([[sorted_angles[-1] - 2 * np.pi], sorted_angles, [sorted_angles[0] + 2 * np.pi]])
    quad = 0.5 * (ext[2:] - ext[:-2])
    out = np.empty(n)
    rows = max(1, block_elements // n)
    for i in range(0, n, rows):
        s = periodic_gaussian_weights(sorted_angles[i:i + rows, None] - sorted_angles[None, :], cutoff_upr) * quad
        out[i:i + rows] = (s @ values) / s.sum(axis=1)
    return out


def nufft_filter(sorted_angles: np.ndarray, values: np.ndarray, cutoff_upr: float) -> np.ndarray:
    """The normalised trapezoidal convolution of the module docstring by two non-uniform FFTs per sum
    (O(N log N + K log K), error bound in the module docstring)."""
    import finufft

    n = sorted_angles.size
    ext = np.concatenate([[sorted_angles[-1] - 2 * np.pi], sorted_angles, [sorted_angles[0] + 2 * np.pi]])
    quad = 0.5 * (ext[2:] - ext[:-2])
    # a(k) < 1e-17 beyond K: exp(-pi (alpha K / lambda_c)^2) = 1e-17
    K = int(math.ceil(cutoff_upr / ALPHA * math.sqrt(17 * math.log(10) / math.pi)))
    K = min(K, 4 * n)
    modes = 2 * K + 1
    x = np.ascontiguousarray(np.mod(sorted_angles, 2 * np.pi) - np.pi)  # finufft's [-pi, pi); the shift cancels
    weights = np.stack([values * quad, quad]).astype(np.complex128)
    coef = finufft.nufft1d1(x, weights, modes, eps=NUFFT_TOL, isign=-1)   # sum_j c_j e^{-ik x_j}, k = -K..K
    coef *= (transmission(np.arange(-K, K + 1), cutoff_upr) / (2 * np.pi))[None, :]
    back = finufft.nufft1d2(x, np.ascontiguousarray(coef), eps=NUFFT_TOL, isign=1)
    return back[0].real / back[1].real


def resample_equal(sorted_angles: np.ndarray, values: np.ndarray, n: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(grid, values on it): periodic linear interpolation of a closed profile onto ``n`` (default N)
    equally spaced angles starting at the first measured angle."""
    n = n or sorted_angles.size
    grid = sorted_angles[0] + 2 * np.pi * np.arange(n) / n
    return grid, np.interp(grid, sorted_angles, values, period=2 * np.pi)


def gaussian_filter(sorted_angles: np.ndarray, values: np.ndarray, cutoff_upr: float | None) -> tuple[np.ndarray, str]:
    """(filtered values at the measured angles, path): the ISO 16610-21 closed-profile filter of a profile
    given at increasing angles within one revolution. ``cutoff_upr=None`` returns the values unchanged."""
    if cutoff_upr is None:
        return values.copy(), "none (unfiltered)"
    if equally_spaced(sorted_angles):
        return fft_filter(values, cutoff_upr), "FFT on equally spaced angles"
    return (nufft_filter(sorted_angles, values, cutoff_upr),
            "convolution with the periodic Gaussian weighting function by non-uniform FFT (unequal spacing)")


def harmonic_spectrum(sorted_angles: np.ndarray, values: np.ndarray) -> dict:
    """Amplitudes A_k and phases phi_k (rad) of values(theta) = A_0 + sum_k A_k cos(k theta + phi_k) for
    k = 0..floor(N/2) UPR, with theta the measured polar angle (origin of the phases: the +x axis).
    Equally spaced angles: the DFT; otherwise the DFT of the periodic linear interpolation onto N equal angles
    (an approximation: linear interpolation attenuates harmonic k by about sinc^2(k / N))."""
    n = sorted_angles.size
    grid0 = equal_grid_origin(sorted_angles)
    if grid0 is not None:
        on_grid = values
    else:
        grid, on_grid = resample_equal(sorted_angles, values)
        grid0 = grid[0]
    c = np.fft.rfft(on_grid) / n
    k = np.arange(c.size)
    c = c * np.exp(-1j * k * grid0)          # phases referred to theta = 0, not to the first sample
    amp = 2 * np.abs(c)
    amp[0] = np.abs(c[0].real)
    if n % 2 == 0:
        amp[-1] = np.abs(c[-1])               # the Nyquist harmonic appears once in the DFT
    return {"upr": k, "amplitude": amp, "phase": np.angle(c)}


def dominant_lobes(spectrum: dict, count: int = 5) -> list[dict]:
    """The ``count`` largest harmonics with k >= 2 (k = 1 is the centring, ~0 about the LSCI centre)."""
    k, amp, ph = spectrum["upr"], spectrum["amplitude"], spectrum["phase"]
    idx = np.flatnonzero(k >= 2)
    top = idx[np.argsort(-amp[idx], kind="stable")][:count]
    return [{"upr": int(k[i]), "amplitude": float(amp[i]), "phase": float(ph[i])} for i in top]
