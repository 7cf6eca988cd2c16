"""Spike-train analysis (mjtouch.analysis) and figures against analytic cases.

Random trains use fixed seeds; every statistical tolerance is a stated number
of standard deviations of the estimator, computed from the process."""

import io
import math
import sys

import numpy as np
import pytest

from mjtouch import analysis
from mjtouch.analysis import figures


def bin_times(times_s, dt_s, nstep, t0_s=0.0):
    """Counts per step of spike times, with the convention of the plugin's
    spikes block: row k counts spikes in (t0 + (k - 1) dt, t0 + k dt]."""
    k = np.ceil((np.asarray(times_s) - t0_s) / dt_s).astype(int)
    return np.bincount(k, minlength=nstep)[:nstep].astype(float)


def poisson_counts(rng, rate_hz, dt_s, shape):
    return rng.poisson(rate_hz * dt_s, size=shape).astype(float)


# --- spike times, raster, rates -----------------------------------------------------------


def test_raster_recovers_spike_times_to_half_a_step(rng):
    dt, nstep = 1e-3, 2000
    trains = [np.sort(rng.uniform(0.0, (nstep - 1) * dt, size=n)) for n in (0, 7, 150)]
    counts = np.stack([bin_times(t, dt, nstep) for t in trains], axis=1)
    got = analysis.raster(counts, dt)
    assert len(got) == 3
    for want, have in zip(trains, got):
        assert have.size == want.size
        # each spike is placed at its step's middle: within dt/2 (+ round-off)
        assert np.all(np.abs(np.sort(have) - want) <= dt / 2 + 1e-12)


def test_spike_times_offset_by_t0():
    dt, t0 = 2.5e-4, 1.25
    counts = np.zeros(40)
    counts[[3, 17]] = [2, 1]
    times = analysis.spike_times(counts, dt, t0)
    expect = t0 + (np.array([3, 3, 17]) - 0.5) * dt
    np.testing.assert_allclose(times, expect, rtol=0, atol=1e-15)


def test_receptor_rates_of_poisson_trains(rng):
    dt, nstep = 1e-3, 50_000
    rates = np.array([5.0, 40.0, 200.0])
    counts = np.stack([poisson_counts(rng, r, dt, nstep) for r in rates], axis=1)
    got = analysis.receptor_rates_hz(counts, dt)
    T = nstep * dt
    # a Poisson count over T has sd sqrt(rate T): 5 sd
    assert np.all(np.abs(got - rates) <= 5 * np.sqrt(rates * T) / T)
    # and it is exactly count / duration
    np.testing.assert_array_equal(got, counts.sum(axis=0) / T)


def test_psth_of_a_rate_step(rng):
    dt, nrec = 1e-3, 200
    rate = np.where(np.arange(1000) < 500, 20.0, 80.0)  # Hz, step at 0.5 s
    counts = rng.poisson(rate[:, None] * dt, size=(1000, nrec)).astype(float)
    bin_s = 0.05
    starts, psth = analysis.psth(counts, dt, bin_s)
    assert starts.size == 20
    np.testing.assert_allclose(np.diff(starts), bin_s, rtol=1e-12)
    expect = np.where(starts + dt < 0.5, 20.0, 80.0)
    # bin count ~ Poisson(rate * bin * nrec): 5 sd
    sd = np.sqrt(expect * bin_s * nrec) / (bin_s * nrec)
    assert np.all(np.abs(psth - expect) <= 5 * sd)
    # spikes are conserved
    assert psth.sum() * bin_s * nrec == pytest.approx(counts.sum(), rel=1e-12)
    # trials x steps x receptors pools like receptors
    trials = counts.T.reshape(4, 50, 1000).transpose(0, 2, 1)
    np.testing.assert_allclose(analysis.psth(trials, dt, bin_s)[1], psth, rtol=1e-12)


def test_smoothed_rate_of_a_single_spike_is_the_kernel():
    dt, tau = 1e-4, 0.02
    counts = np.zeros(3000)
    counts[100] = 1
    r = analysis.smoothed_rate(counts, dt, tau)
    t_end = np.arange(3000) * dt  # step ends
    t_spike = (100 - 0.5) * dt
    expect = np.where(t_end >= t_spike, np.exp(-(t_end - t_spike) / tau) / tau, 0.0)
    np.testing.assert_allclose(r, expect, rtol=1e-9, atol=1e-12)


def test_smoothed_rate_mean_equals_rate_of_a_regular_train():
    # A spike every N steps: in steady state the mean of the exponentially
    # smoothed rate over a period is (1 / (N dt)) x (x / (2 sinh(x / 2))),
    # x = dt / tau (each spike's discrete kernel sums to that factor / dt).
    dt, tau, N = 1e-4, 0.05, 137
    counts = np.zeros(200 * N)
    counts[::N] = 1
    r = analysis.smoothed_rate(counts, dt, tau)
    x = dt / tau
    expect = 1 / (N * dt) * x / (2 * math.sinh(x / 2))
    assert r[-N:].mean() == pytest.approx(expect, rel=1e-9)


# --- vector strength ---------------------------------------------------------------------


def test_vector_strength_of_a_phase_locked_train_is_one():
    f, phase0 = 250.0, 0.3  # phase in cycles
    times = (np.arange(500) + phase0) / f
    vs = analysis.vector_strength(times, f)
    assert vs.vs == pytest.approx(1.0, abs=1e-12)
    assert vs.phase_rad == pytest.approx(2 * np.pi * phase0, abs=1e-9)
    assert vs.n == 500
    assert vs.rayleigh_z == pytest.approx(500.0, rel=1e-12)
    assert vs.p_value < 1e-200


def test_vector_strength_of_uniform_phases_is_near_zero(rng):
    n, f = 5000, 100.0
    times = rng.uniform(0, 50.0, size=n)  # 5000 cycles: phases uniform
    vs = analysis.vector_strength(times, f)
    # Rayleigh: P(n vs^2 > z) ~ exp(-z) for uniform phases; z = ln(1e6)
    # bounds vs with probability 1 - 1e-6
    assert vs.vs < math.sqrt(math.log(1e6) / n)
    assert vs.p_value > 1e-6


def test_vector_strength_with_gaussian_jitter():
    # Spike times jittered by N(0, s^2) about a locked phase: the population
    # vector strength is exp(-(2 pi f s)^2 / 2). The estimator's sd along
    # the mean direction is sqrt(((1 + R^4) / 2 - R^2) / n).
    rng = np.random.default_rng(1)
    f, s, n = 200.0, 0.8e-3, 20_000
    times = np.arange(n) / f + rng.normal(0, s, size=n)
    R = math.exp(-0.5 * (2 * math.pi * f * s) ** 2)
    sd = math.sqrt(((1 + R**4) / 2 - R**2) / n)
    assert analysis.vector_strength(times, f).vs == pytest.approx(R, abs=5 * sd)


def test_rayleigh_p_value_is_calibrated():
    # Under uniform phases the p-value is uniform: P(p < 0.1) = 0.1.
    rng = np.random.default_rng(2)
    trials, n = 1000, 40
    p = np.array(
        [analysis.vector_strength(rng.uniform(0, 1, n), 13.0).p_value for _ in range(trials)]
    )
    # binomial(1000, 0.1): sd 0.0095; 5 sd
    assert abs((p < 0.1).mean() - 0.1) < 5 * math.sqrt(0.1 * 0.9 / trials)
    # for large n Zar's formula tends to exp(-Z)
    assert analysis.rayleigh_p(10**6, 2e-3) == pytest.approx(math.exp(-4.0), rel=1e-3)


def test_vector_strength_weights_equal_repeated_spikes(rng):
    times = rng.uniform(0, 1, 30)
    w = rng.integers(1, 4, 30)
    a = analysis.vector_strength(times, 37.0, weights=w)
    b = analysis.vector_strength(np.repeat(times, w), 37.0)
    assert a.vs == pytest.approx(b.vs, rel=1e-12) and a.n == b.n == w.sum()


def test_vector_strength_from_counts_is_bounded_by_step_quantisation():
    # A train locked to 317 Hz binned at 1e-4 s: each spike moves by at most
    # dt/2, i.e. a phase of pi f dt, so vs >= cos(pi f dt).
    f, dt = 317.0, 1e-4
    times = (np.arange(300) + 0.37) / f
    counts = bin_times(times, dt, int(times[-1] / dt) + 3)
    vs = analysis.vector_strength_counts(counts, dt, f)
    assert vs.n == 300
    assert math.cos(math.pi * f * dt) - 1e-12 <= vs.vs < 1.0


def test_spikes_per_cycle_of_a_locked_train():
    f, dt = 250.0, 1e-4
    times = (np.arange(100) + 0.6) / f
    counts = bin_times(times, dt, int(round(100 / f / dt)) + 1)
    per = analysis.spikes_per_cycle(counts, dt, f, origin_s=0.1 / f)
    assert per.size == 99  # cycles wholly inside the train
    assert np.all(per == 1)
    # two spikes in one cycle, none in the next
    counts2 = counts.copy()
    k = np.nonzero(counts2)[0]
    counts2[k[10]] = 0
    counts2[k[11]] = 2
    per2 = analysis.spikes_per_cycle(counts2, dt, f, origin_s=0.1 / f)
    assert per2.sum() == per.sum() and per2.max() == 2 and per2.min() == 0


# --- spectra ------------------------------------------------------------------------------


def test_spike_spectrum_of_poisson_trains_is_flat_at_twice_the_rate(rng):
    dt, lam, nrec, nstep = 1e-3, 30.0, 20, 20_000
    counts = poisson_counts(rng, lam, dt, (nstep, nrec))
    f, p = analysis.spike_spectrum(counts, dt, segment_s=1.0)
    band = (f >= 5) & (f <= 400)
    # One-sided PSD of a Poisson process: 2 lam. Each Welch bin is ~chi^2
    # with relative sd 1 per periodogram; averaging R trains x K disjoint
    # segments x M bins gives 1 / sqrt(R K M); 6x covers the Hann window's
    # correlation between neighbouring bins and overlapping segments (<= 2x)
    # with 3 sd to spare.
    K, M = nstep * dt / 1.0, band.sum()
    tol = 6 / math.sqrt(nrec * K * M)
    assert p[band].mean() == pytest.approx(2 * lam, rel=tol)


def test_spike_spectrum_of_a_regular_train_has_lines_at_its_harmonics():
    dt = 1e-4
    counts = np.zeros(20_000)
    counts[::40] = 1  # every 4 ms: 250 Hz
    f, p = analysis.spike_spectrum(counts, dt)
    peaks = analysis.spectral_peaks(f, p, n=4, fmin_hz=50.0, fmax_hz=1100.0)
    df = f[1] - f[0]
    assert sorted(peaks) == pytest.approx([250.0, 500.0, 750.0, 1000.0], abs=df)


# --- bad input ----------------------------------------------------------------------------


def test_band_line_finds_a_sine_off_its_expected_frequency(rng):
    # a 61 Hz sine in white noise, looked for at 55.6 Hz (+-15%: 47.2-63.9 Hz)
    dt, n = 1e-4, 20000
    t = np.arange(n) * dt
    x = 0.5 * np.sin(2 * np.pi * 61.0 * t) + rng.normal(0.0, 1.0, n)
    f, p = analysis.stress_spectrum(x, dt)
    line = analysis.band_line(f, p, 55.6)
    assert line.lo_hz == pytest.approx(55.6 * 0.85) and line.hi_hz == pytest.approx(55.6 * 1.15)
    assert abs(line.peak_hz - 61.0) <= f[1] - f[0]
    # the sine's power (A^2 / 4 = 0.0625 in a few bins of the Hann lobe)
    # against the noise's per bin (~sigma^2 / (n / 2) = 1e-4): the band's
    # mean (33 bins) is ~20x its flanks'
    assert line.contrast > 5
    # white noise alone: band and flanks hold the same mean power. 20 s give
    # 334 bins of 0.05 Hz per band (chi-squared, 2 dof each, ~1.5 bins per
    # independent value under Hann): each mean within ~7%, their ratio within
    # ~10% (1 sigma), so 0.3 is a 3-sigma bound
    noise_x = rng.normal(0.0, 1.0, 200_000)
    noise = analysis.band_line(*analysis.stress_spectrum(noise_x, dt), 55.6)
    assert noise.contrast == pytest.approx(1.0, abs=0.3)
    assert 0 < noise.share < 0.05


def test_band_line_rejects_bad_arguments():
    f = np.linspace(0, 100, 101)
    with pytest.raises(ValueError, match="f_hz"):
        analysis.band_line(f, np.ones_like(f), -1.0)
    with pytest.raises(ValueError, match="rel_half_width"):
        analysis.band_line(f, np.ones_like(f), 50.0, rel_half_width=1.5)


def test_bad_arguments_name_the_argument():
    with pytest.raises(ValueError, match="dt_s"):
        analysis.psth(np.ones(10), -1e-4, 1e-3)
    with pytest.raises(ValueError, match="bin_s = 0.00015 must be a whole number of steps"):
        analysis.psth(np.ones(10), 1e-4, 1.5e-4)
    with pytest.raises(ValueError, match="non-negative integer counts"):
        analysis.receptor_rates_hz(np.array([1.0, -1.0]), 1e-4)
    with pytest.raises(ValueError, match="freq_hz"):
        analysis.vector_strength(np.ones(3), 0.0)
    with pytest.raises(ValueError, match="weights has 2 entries for 3 spike times"):
        analysis.vector_strength(np.ones(3), 10.0, weights=np.ones(2))
    with pytest.raises(ValueError, match="segment_s"):
        analysis.spike_spectrum(np.ones(100), 1e-3, segment_s=1.0)


# --- figures -----------------------------------------------------------------------------


def test_figures_draw_what_analysis_computes(rng):
    dt = 1e-3
    counts = poisson_counts(rng, 50.0, dt, (1000, 3))
    classes = np.array(["SA1", "RA", "PC"])
    ax = figures.plot_raster(counts, dt, classes)
    events = ax.collections
    assert len(events) == 3
    for coll, train in zip(events, analysis.raster(counts, dt)):
        np.testing.assert_allclose(np.sort(coll.get_positions()), train)
    ax = figures.plot_psth(counts, dt, 0.05)
    starts, rate = analysis.psth(counts, dt, 0.05)
    np.testing.assert_allclose(ax.patches[0].get_data().values, rate)
    f, p = analysis.spike_spectrum(counts, dt)
    ax = figures.plot_spectrum(f, p)
    np.testing.assert_allclose(ax.lines[0].get_ydata(), p[f > 0])
    ax = figures.plot_tuning([10, 100], [3.0, 0.5], unit="um")
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    times = (np.arange(50) + 0.25) / 100.0
    ax = figures.plot_phase_histogram(times, 100.0, nbins=4)
    assert "1.000" in ax.get_title()
    buf = io.BytesIO()
    ax.figure.savefig(buf, format="png")
    assert buf.getvalue()[:8] == b"\x89PNG\r\n\x1a\n"


def test_figures_without_matplotlib_name_the_plot_extra(monkeypatch):
    for name in [m for m in sys.modules if m == "matplotlib" or m.startswith("matplotlib.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib -> ImportError
    with pytest.raises(ImportError, match=r"mjtouch\[plot\]"):
        figures.plot_psth(np.ones(10), 1e-3, 2e-3)
