"""ISO 12181 roundness: the ISO 16610-21 closed-profile Gaussian filter, RON parameters about the four
reference circles, the harmonic spectrum, bad input, the CLI."""
from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

import methods
from methods import InvalidInputError
from methods.roundness import filter as rfilter
from methods.roundness import evaluate, transmission

ALPHA = math.sqrt(math.log(2) / math.pi)


def lobed(n, lobes, *, center=(1200.0, 650.0), radius=299.0, theta0=0.0, angles=None):
    """Points r(theta) = R + sum A_k cos(k theta + phi_k) about ``center`` at ``angles`` (default: n equal)."""
    t = theta0 + 2 * np.pi * np.arange(n) / n if angles is None else angles
    r = radius + sum(a * np.cos(k * t + ph) for k, a, ph in lobes)
    return np.column_stack([center[0] + r * np.cos(t), center[1] + r * np.sin(t)]), t, r


def direct_periodic_convolution(values, cutoff):
    """Independent reference: w_i = h sum_j s(theta_i - theta_j) z_j with the periodic Gaussian weighting
    function s(x) = sum_m exp(-pi ((x + 2 pi m) / (alpha lambda))^2) / (alpha lambda), lambda = 2 pi / cutoff
    (ISO 16610-21 clause 5.2), O(N^2)."""
    n = values.size
    h = 2 * np.pi / n
    lam = 2 * np.pi / cutoff
    x = (np.arange(n)[:, None] - np.arange(n)[None, :]) * h
    s = sum(np.exp(-np.pi * ((x + 2 * np.pi * m) / (ALPHA * lam)) ** 2) for m in range(-3, 4)) / (ALPHA * lam)
    return h * s @ values


# ------------------------------------------------------------------ the filter

def test_transmission_formula_half_at_cutoff():
    for c in rfilter.STANDARD_CUTOFFS_UPR:
        assert transmission(c, c) == pytest.approx(0.5, abs=1e-15)
    assert ALPHA == pytest.approx(0.4697, abs=1e-4)


@pytest.mark.parametrize("n,cutoff", [(360, 15.0), (1024, 50.0), (1001, 50.0)])
def test_measured_transmission_equals_formula_every_harmonic(n, cutoff):
    """Each cosine of k = 1..N/2 UPR through the filter comes out scaled by a(k) (measured amplitude by
    projection), to 1e-6 absolute; at the cut-off 0.5 +- 0.005."""
    t = 2 * np.pi * np.arange(n) / n + 0.3
    measured = []
    for k in range(1, n // 2 + 1):
        z = np.cos(k * t + 0.7)
        out, path = rfilter.gaussian_filter(t, z, cutoff)
        assert path.startswith("FFT")
        measured.append((out @ z) / (z @ z))   # projection on the input harmonic
        assert np.max(np.abs(out - measured[-1] * z)) < 1e-12  # nothing but the same harmonic comes out
    measured = np.array(measured)
    k = np.arange(1, n // 2 + 1)
    assert np.max(np.abs(measured - transmission(k, cutoff))) < 1e-6
    kc = int(cutoff)
    assert measured[kc - 1] == pytest.approx(0.5, abs=0.005)


@pytest.mark.parametrize("cutoff", [15.0, 50.0])
def test_fft_filter_equals_direct_periodic_convolution(cutoff):
    """With N >= 20 lambda_c the sampled weighting function aliases by a(N/2) < 1e-30: the direct O(N^2)
    convolution and the FFT path agree to rounding (1e-12 of the profile's size) on random data."""
    n = 1000
    z = np.random.default_rng(7).normal(size=n)
    t = 2 * np.pi * np.arange(n) / n
    ref = direct_periodic_convolution(z, cutoff)
    out, _ = rfilter.gaussian_filter(t, z, cutoff)
    assert np.max(np.abs(out - ref)) < 1e-12 * np.max(np.abs(z))


def test_unequal_spacing_path_agrees_with_equal_spacing_and_exact():
    """Jittered angles (+-0.3 steps) go through the convolution (non-uniform FFT); the filtered values at those angles
    match the exact filtered profile sum a(k) A_k cos(k theta + phi_k) (what the FFT path gives on equal
    angles, to 1e-12) to 1e-4 of the largest lobe: the trapezoid error (h / (alpha lambda))^2 / 12 ~ 7e-5
    with h_max = 1.6 steps at 50 UPR, partly cancelling over the jitter."""
    n, cutoff = 3600, 50.0
    lobes = [(2, 1.0, 0.1), (3, 0.5, 1.0), (15, 0.3, 2.0), (50, 0.2, 0.5), (120, 0.05, 1.5)]
    rng = np.random.default_rng(3)
    h = 2 * np.pi / n
    t_j = np.sort(np.mod(2 * np.pi * np.arange(n) / n + rng.uniform(-0.3, 0.3, n) * h, 2 * np.pi))
    t_e = 2 * np.pi * np.arange(n) / n

    def profile(t):
        return sum(a * np.cos(k * t + ph) for k, a, ph in lobes)

    def exact(t):
        return sum(transmission(k, cutoff) * a * np.cos(k * t + ph) for k, a, ph in lobes)

    out_e, path_e = rfilter.gaussian_filter(t_e, profile(t_e), cutoff)
    out_j, path_j = rfilter.gaussian_filter(t_j, profile(t_j), cutoff)
    assert path_e.startswith("FFT") and path_j.startswith("convolution")
    assert np.max(np.abs(out_e - exact(t_e))) < 1e-12
    err = np.max(np.abs(out_j - exact(t_j)))
    assert err < 1e-4
    # on equal angles the convolution path is the FFT path (N = 3600 >= 20 x 50 UPR: aliasing < 1e-30)
    assert np.max(np.abs(rfilter.convolution_filter(t_e, profile(t_e), cutoff) - out_e)) < 1e-12
    # the spectrum of the jittered profile (linear resampling) recovers the filtered lobes within sinc^2
    spec = rfilter.harmonic_spectrum(t_j, out_j)
    for k, a, ph in lobes[:3]:
        assert spec["amplitude"][k] == pytest.approx(transmission(k, cutoff) * a, rel=1e-3)


def test_unequal_spacing_noisy_random_angles_stays_within_data():
    """Random angles with points nearly coinciding and white noise: every filtered value is a convex
    combination of the data (a spline resampling overshot 130 x the noise here)."""
    rng = np.random.default_rng(11)
    t = np.sort(rng.uniform(0, 2 * np.pi, 2000))
    z = 4e-4 * rng.standard_normal(t.size)
    for cutoff in (15.0, 150.0):
        out, path = rfilter.gaussian_filter(t, z, cutoff)
        assert path.startswith("convolution") and "non-uniform FFT" in path
        assert z.min() <= out.min() and out.max() <= z.max()
        assert np.std(out) < np.std(z)


@pytest.mark.parametrize("layout", ["jitter 6 %", "random angles"])
def test_unequal_spacing_by_nufft_equals_the_direct_convolution(layout):
    """The O(N log N) path (two non-uniform FFTs per sum) against the O(N^2) reference convolution of the
    same trapezoidal sums: within the stated bound, 1e-12 of the largest value, at every standard cut-off."""
    rng = np.random.default_rng(5)
    n = 3000
    h = 2 * np.pi / n
    t = (np.sort(np.mod(h * np.arange(n) + rng.uniform(-0.06, 0.06, n) * h, 2 * np.pi)) if layout == "jitter 6 %"
         else np.sort(rng.uniform(0, 2 * np.pi, n)))
    z = 3.0 + np.sin(3 * t) + 0.2 * np.cos(70 * t) + 1e-3 * rng.standard_normal(n)
    for cutoff in (15.0, 50.0, 150.0, 500.0):
        direct = rfilter.convolution_filter(t, z, cutoff)
        fast = rfilter.nufft_filter(t, z, cutoff)
        assert np.max(np.abs(fast - direct)) < 1e-12 * np.max(np.abs(z))


def test_a_long_jittered_trace_takes_the_fast_path():
    """36,000 points with ~6 % angle jitter (what a rotary encoder gives) were filtered by the O(N^2)
    convolution (80-113 s); they now take the non-uniform FFT path, and a constant passes exactly."""
    n = 36_000
    rng = np.random.default_rng(8)
    t = np.sort(np.mod(2 * np.pi * np.arange(n) / n + rng.uniform(-0.06, 0.06, n) * 2 * np.pi / n, 2 * np.pi))
    assert not rfilter.equally_spaced(t)
    out, path = rfilter.gaussian_filter(t, np.full(n, 0.25), 50.0)
    assert "non-uniform FFT" in path
    assert np.max(np.abs(out - 0.25)) < 1e-13


def test_undersampled_warns():
    t = 2 * np.pi * np.arange(300) / 300
    with pytest.warns(rfilter.UndersampledWarning, match="fewer than 7 x the 50 UPR"):
        msg = rfilter.check_sampling(300, 50.0)
    assert "350" in msg
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert rfilter.check_sampling(350, 50.0) is None
        assert rfilter.check_sampling(10, None) is None
    pts, _, _ = lobed(300, [(3, 0.001, 0.0)])
    with pytest.warns(rfilter.UndersampledWarning):
        res = methods.fit("roundness.iso12181", pts, cutoff_upr=50)
    assert res.warnings and "under-sampled" in res.message
    del t


# ------------------------------------------------------------------ RON parameters

@pytest.mark.parametrize("k", [2, 3, 5, 12])
@pytest.mark.parametrize("cutoff", [None, 15.0, 50.0])
def test_pure_lobed_profile_gives_two_amplitude_times_transmission(k, cutoff):
    """r = R + A cos k theta (k >= 2), N a multiple of 2k: every reference circle is centred on the profile's
    centre by symmetry, the samples hit the extremes, so RONt = 2 A a(k) for all four. The pipeline is exact
    here (the LSCI centre of a k >= 2 lobed profile on equal angles is its centre, so the deviations are the
    harmonic itself); what remains is the circle solvers' centre accuracy: a centre off by e changes RONt by
    <= 2 e, and the tolerance 1e-9 x A (0.001 um for A = 1 um) allows e ~ 1e-12 x R.

    The one exception is MICI of the 2-lobe profile: its two valleys are flatter than the inscribed circle, and
    on samples h apart a centre moved by e < 2 A a(2) h along the major axis raises the smallest radius by
    e^2 / (2 R) > 0 (the continuous profile would lower it by e^2 / (8 A a(2))). The discrete MICI is then
    that displaced centre (the inscribed radius gains ~1e-14 mm, RONt grows by e): we check its radius and
    bound RONt by 2 A a(2) (1 + 2 h)."""
    n, A = 3600, 1e-3
    pts, _, _ = lobed(n, [(k, A, 0.0)])
    res = methods.fit("roundness.iso12181", pts, cutoff_upr=cutoff)
    a_k = 1.0 if cutoff is None else float(transmission(k, cutoff))
    # (the zone solvers do not always certify these symmetric profiles, whose many tied extremes defeat their
    # contact checks; their centres are right all the same, which is what the values below check)
    for kind, ref in res.references.items():
        if kind == "mici" and k == 2:
            h = 2 * np.pi / n
            assert ref["radius"] == pytest.approx(299.0 - A * a_k, abs=1e-12)
            assert 2 * A * a_k - 1e-12 <= ref["RONt"] <= 2 * A * a_k * (1 + 2 * h)
            continue
        assert ref["RONt"] == pytest.approx(2 * A * a_k, abs=1e-9 * A + 1e-12), kind
    assert res.references["mzci"]["RONp"] == pytest.approx(A * a_k, abs=1e-9 * A)
    assert res.references["mici"]["RONv"] == 0.0 and res.references["mcci"]["RONp"] == 0.0


def test_small_deviation_limit_with_eccentric_sampling():
    """A 3-lobe profile whose angles are equal about a point 5 um away from its centre (an eccentric set-up):
    the deviations about the fitted centre are the harmonic only to first order in e/R, so RONt matches
    2 A a(k) to a tolerance of the order of e^2/R + A e/R (about 1e-6 relative here)."""
    A, e, R = 2e-3, 5e-3, 10.0
    t = 2 * np.pi * np.arange(3600) / 3600
    r = R + A * np.cos(3 * t)
    pts = np.column_stack([r * np.cos(t), r * np.sin(t)]) + [e, 0.0]
    res = methods.fit("roundness.iso12181", pts, cutoff_upr=50)
    expect = 2 * A * transmission(3, 50.0)
    assert res.references["lsci"]["RONt"] == pytest.approx(expect, rel=1e-4)


def test_invariants_on_noisy_profile():
    rng = np.random.default_rng(11)
    n = 2000
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    r = 25.0 + 3e-3 * np.cos(2 * t + 0.4) + 1e-3 * np.cos(7 * t) + 4e-4 * rng.standard_normal(n)
    pts = np.column_stack([-40 + r * np.cos(t), 17 + r * np.sin(t)])
    for cutoff in (None, 15, 50, 150):
        res = methods.fit("roundness.iso12181", pts, cutoff_upr=cutoff)
        refs = res.references
        assert res.converged == all(r["converged"] for r in refs.values())
        for kind, ref in refs.items():
            assert ref["RONp"] + ref["RONv"] == pytest.approx(ref["RONt"], abs=1e-15 * 25)
            assert ref["RONp"] >= 0 and ref["RONv"] >= 0
        # RONq about LSCI = RMS of the residuals about the least-squares circle of the filtered profile
        lsq = methods.fit("circle.gauss_newton", res.points)
        assert refs["lsci"]["RONq"] == pytest.approx(np.sqrt(np.mean(lsq.residuals ** 2)), rel=1e-9)
        # MZCI's RONt is the smallest of the four (it minimises max - min over centres) whenever
        # circle.minimum_zone certifies its zone; when it does not, the result says so
        if refs["mzci"]["converged"]:
            assert all(refs["mzci"]["RONt"] <= refs[k]["RONt"] + 1e-12 for k in refs)
        else:
            assert not res.converged and "mzci:" in res.message
        assert res.form_error == refs["mzci"]["RONt"]


def test_unfiltered_mzci_equals_minimum_zone_exactly():
    rng = np.random.default_rng(5)
    pts, _, _ = lobed(720, [(3, 2e-3, 0.2), (9, 5e-4, 1.0)])
    pts = pts + rng.normal(0, 2e-4, pts.shape)
    res = methods.fit("roundness.iso12181", pts, cutoff_upr=None)
    mz = methods.fit("circle.minimum_zone", pts)
    assert res.references["mzci"]["RONt"] == mz.form_error
    assert res.references["mzci"]["center"] == mz.center
    assert res.filter_path.startswith("none")


def test_filtering_never_adds_peak_to_valley_for_smooth_lobes():
    pts, _, _ = lobed(3600, [(2, 1e-3, 0.0), (40, 1e-3, 0.3), (300, 1e-3, 1.0)])
    ront = [methods.fit("roundness.iso12181", pts, cutoff_upr=c, reference="mzci").form_error
            for c in (15, 50, 150, 500, None)]
    assert all(np.diff(ront) > 0)


# ------------------------------------------------------------------ spectrum

def test_harmonic_amplitudes_recovered():
    lobes = [(2, 1.5e-3, 0.3), (3, 2e-3, -1.1), (7, 4e-4, 2.5), (15, 1e-4, 0.0), (90, 3e-5, -2.0)]
    pts, _, _ = lobed(1800, lobes, theta0=0.01)
    res = methods.fit("roundness.iso12181", pts, cutoff_upr=None)
    spec = res.spectrum
    for k, a, ph in lobes:
        assert spec["amplitude"][k] == pytest.approx(a, rel=1e-9)
        assert np.angle(np.exp(1j * (spec["phase"][k] - ph))) == pytest.approx(0.0, abs=1e-6)
    others = np.delete(spec["amplitude"], [0] + [k for k, _, _ in lobes])
    assert others.max() < 1e-9 * 2e-3
    assert [d["upr"] for d in res.dominant_lobes[:3]] == [3, 2, 7]
    filt = methods.fit("roundness.iso12181", pts, cutoff_upr=50)
    for k, a, _ in lobes:
        assert filt.spectrum["amplitude"][k] == pytest.approx(a * transmission(k, 50.0), rel=1e-9, abs=1e-15)


# ------------------------------------------------------------------ bad input

@pytest.mark.parametrize("pts,cut,match", [
    (np.ones((5, 2)) * np.arange(5)[:, None] * [1, 2], 50, "at least 8 points"),
    (None, 0, "positive number of UPR"),
    (None, -15, "positive number of UPR"),
    (None, float("nan"), "positive number of UPR"),
    (None, "fifty", "not a number of UPR"),
    ("nan", 50, "NaN or inf"),
])
def test_bad_input_one_line(pts, cut, match):
    good, _, _ = lobed(400, [(3, 1e-3, 0.0)])
    if pts is None:
        pts = good
    elif isinstance(pts, str):
        pts = good.copy()
        pts[4, 1] = np.nan
    with pytest.raises(InvalidInputError, match=match) as info:
        methods.fit("roundness.iso12181", pts, cutoff_upr=cut)
    assert "\n" not in str(info.value)


def test_bad_reference_and_repeated_point():
    good, _, _ = lobed(400, [(3, 1e-3, 0.0)])
    with pytest.raises(InvalidInputError, match="reference"):
        methods.fit("roundness.iso12181", good, reference="lsq")
    with pytest.raises(InvalidInputError, match="same polar angle"):
        methods.fit("roundness.iso12181", np.vstack([good, good[:1]]))


def _arc(n, keep, *, start=0.0, lobes=((3, 1.5e-3, 0.4), (17, 3e-4, 1.0))):
    """The ``keep`` of ``n`` equal angles from ``start`` (rad) of a lobed profile: a revolution with a part missing."""
    pts, t, _ = lobed(n, list(lobes), center=(30.0, -5.0), radius=12.5)
    idx = (np.arange(keep) + int(round(start / (2 * np.pi) * n))) % n
    return pts[idx]


@pytest.mark.parametrize("keep_deg,start_deg,cutoff", [(270, 0, 50), (270, 0, None), (270, 135, 1), (270, 135, 150),
                                                     (180, 0, 15), (355, 40, 15), (355, 40, None)])
def test_open_profile_is_refused(cutoff, keep_deg, start_deg):
    """A 3600-point revolution with 5° to 180° missing, the gap at the wrap or in the middle: ISO 12181
    defines roundness on the closed profile; the periodic filter joined the ends (a 270° arc read its 1.5 um
    3-lobe as 1.27 um, all four circles 'ok'). One line naming the gap and what to do. (A 5° gap at a 1 UPR
    cut-off is within the 51° spacing ISO 12181-2 allows there: evaluated.)"""
    pts = _arc(3600, keep_deg * 10, start=np.radians(start_deg))
    with pytest.raises(InvalidInputError, match="profile is open") as info:
        methods.fit("roundness.iso12181", pts, cutoff_upr=cutoff)
    msg = str(info.value)
    assert "\n" not in msg and "measure the whole circumference" in msg
    assert f"a gap of {360 - keep_deg + 0.1:.3g}°" in msg


@pytest.mark.parametrize("layout", ["equal", "jitter 30 %", "random angles", "3 points dropped"])
@pytest.mark.parametrize("cutoff", [None, 15, 50, 150])
def test_closed_profiles_with_irregular_spacing_are_not_refused(layout, cutoff):
    """What is closed passes the gap check: equal, jittered and uniformly random angles (largest step ~11
    median steps at 2000 points), a few consecutive points missing (an outlier removal)."""
    n = 2000
    rng = np.random.default_rng(21)
    h = 2 * np.pi / n
    t = {"equal": h * np.arange(n), "jitter 30 %": np.sort(np.mod(h * np.arange(n) + rng.uniform(-0.3, 0.3, n) * h, 2 * np.pi)),
         "random angles": np.sort(rng.uniform(0, 2 * np.pi, n)),
         "3 points dropped": np.delete(h * np.arange(n), [700, 701, 702])}[layout]
    pts, _, _ = lobed(t.size, [(3, 1e-3, 0.0), (7, 2e-4, 1.0)], angles=t)
    res = methods.fit("roundness.iso12181", pts, cutoff_upr=cutoff, reference="lsci")
    assert res.references["lsci"]["RONt"] > 0


def test_sparse_published_profile_at_the_standards_spacing_is_not_refused():
    """The published 25-point profile at 3 UPR: its largest step (20.3°) exceeds ISO 12181-2's 17.1° but is
    1.4 median steps: a sparse closed sampling, evaluated (the roundness study's row)."""
    import datasets
    pts = datasets.load("roundness_set1", drop_repeated_closing_point=True).points
    assert methods.fit("roundness.iso12181", pts, cutoff_upr=3).references["mzci"]["RONt"] > 0


def test_cli_open_profile_one_line_exit_2(tmp_path, capsys):
    from fitbench.cli.commands import main
    f = tmp_path / "threeq.csv"
    np.savetxt(f, _arc(3600, 2700), delimiter=",", header="x,y", comments="")
    assert main(["roundness", str(f), "--cutoff", "50"]) == 2
    cap = capsys.readouterr()
    err = cap.err.strip()
    assert err.startswith("fitbench: error: roundness: the profile is open") and "\n" not in err
    assert "Traceback" not in err and "RONt" not in cap.out


def test_evaluate_pure_function_matches_registered():
    pts, _, _ = lobed(500, [(4, 1e-3, 0.0)])
    ev = evaluate(pts, cutoff_upr=15, reference="lsci")
    res = methods.fit("roundness.iso12181", pts, cutoff_upr=15, reference="lsci")
    assert ev["references"]["lsci"]["RONt"] == res.form_error
    d = res.to_dict(residuals=False)
    assert d["references"]["lsci"]["RONt"] == res.form_error and "points" not in d
    json.dumps(d)


# ------------------------------------------------------------------ CLI

def _write_profile(tmp_path, unit_scale=1.0):
    pts, _, _ = lobed(720, [(3, 2e-3, 0.2), (5, 1e-3, 1.0)], center=(30.0, -5.0), radius=12.5)
    f = tmp_path / f"profile_{unit_scale:g}.csv"
    np.savetxt(f, pts * unit_scale, delimiter=",", header="x,y", comments="")
    return f


def test_cli_table_json_units_and_plot(tmp_path, capsys):
    from fitbench.cli.commands import main
    f = _write_profile(tmp_path)
    png = tmp_path / "r.png"
    assert main(["roundness", str(f), "--cutoff", "15", "--plot", str(png)]) in (0, 1)
    out = capsys.readouterr().out
    assert "RONt [µm]" in out and "minimum zone circles (MZCI)" in out and "15 UPR Gaussian" in out
    assert png.stat().st_size > 10_000
    # the same profile in µm gives the same JSON (lengths in mm) as in mm
    f_um = _write_profile(tmp_path, 1e3)
    main(["roundness", str(f), "--cutoff", "15", "--reference", "lsci", "--json"])
    d_mm = json.loads(capsys.readouterr().out)
    main(["roundness", str(f_um), "--unit", "µm", "--cutoff", "15", "--reference", "lsci", "--json"])
    d_um = json.loads(capsys.readouterr().out)
    assert d_mm["units"]["lengths"] == "mm" and d_um["input_unit"] == "µm"
    assert d_um["references"]["lsci"]["RONt"] == pytest.approx(d_mm["references"]["lsci"]["RONt"], rel=1e-9)
    # lobes 3 and 5 (phases 0.2, 1.0) filtered: RONt about LSCI = the peak-to-valley of the exact filtered
    # profile, to the sampling of 720 points (max - min of samples misses the extremes by <= A (k h)^2 / 8 ~ 1e-3)
    t = np.linspace(0, 2 * np.pi, 200000)
    exact = 2e-3 * transmission(3, 15.0) * np.cos(3 * t + 0.2) + 1e-3 * transmission(5, 15.0) * np.cos(5 * t + 1.0)
    assert d_mm["references"]["lsci"]["RONt"] == pytest.approx(np.ptp(exact), rel=1e-3)


@pytest.mark.parametrize("argv,match", [(["--cutoff", "0"], "positive number of UPR"),
                                        (["--cutoff", "abc"], "not a number of UPR"),
                                        (["--reference", "lsq"], "invalid choice")])
def test_cli_bad_input_one_line_exit_2(tmp_path, capsys, argv, match):
    from fitbench.cli.commands import main
    f = _write_profile(tmp_path)
    assert main(["roundness", str(f), *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert match in err and "\n" not in err and err.startswith("fitbench: error:")


def test_cli_undersampled_warns_on_stderr(capsys):
    from fitbench.cli.commands import main
    main(["roundness", "roundness_set1", "--cutoff", "15"])
    cap = capsys.readouterr()
    assert "fitbench: warning: 25 points per revolution" in cap.err


def test_ranking_table_counts_are_integer_counts_not_percentages():
    """The report's ranking table of the reference circles: the counts of rows carry no '%' and print as
    integers; only the mean excess is in %."""
    import pandas as pd

    from experiments.render.report_tables import html_table, latex_fragments
    from experiments.studies.roundness import ranking_shown
    ranks = pd.DataFrame({"reference": ["lsci", "mzci"], "rows": [12, 12], "smallest": [0, 12],
                          "largest": [12, 0], "mean_excess_over_mzci_pct": [6.5, 0.0]})
    shown = ranking_shown(ranks)
    tex = "".join(latex_fragments(shown, caption="c", label="t", unit="", digits=3))
    html = html_table(shown, caption="c", unit="", digits=3)
    assert tex.count(r"{[}\%{]}") == 1 and html.count("[%]") == 1        # the mean excess only
    assert "& 12 & 0 & 12 &" in tex.replace("  ", " ") and "12.0" not in tex and ">12.0<" not in html
