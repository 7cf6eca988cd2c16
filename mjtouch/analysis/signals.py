"""Rates, spike-train statistics and spectra of receptor responses.

Spike arrays are what the plugin's ``spikes`` block holds: counts per step,
time along axis 0 (``nstep`` or ``nstep x nrec``). Row k counts the spikes of
the step that ends at the row's evaluation time ``t0_s + k * dt_s`` (the
plugin primes its receptors on the first evaluation, so row 0 is 0 when
``t0_s`` is the start of a run); a spike's time is estimated by the middle
of its step, ``t0_s + (k - 0.5) * dt_s``, so it is known to +-dt/2.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.signal

from mjtouch._validate import positive_number

CLASSES = ("SA1", "RA", "PC")


def _counts(spikes, ndim_max: int = 2) -> np.ndarray:
    a = np.asarray(spikes)
    if a.ndim == 0 or a.ndim > ndim_max:
        raise ValueError(
            f"spikes must be counts per step with time along axis 0 "
            f"(1 to {ndim_max} dimensions); got shape {a.shape}"
        )
    a = a.astype(np.float64, copy=False)
    if a.size and (not np.all(np.isfinite(a)) or a.min() < 0 or np.any(a != np.round(a))):
        raise ValueError("spikes must be non-negative integer counts per step")
    return a


def rates_hz(spikes: np.ndarray, dt_s: float, classes: np.ndarray) -> dict[str, float]:
    """Mean firing rate per class over the given steps (spikes: nstep x nrec)."""
    duration = spikes.shape[0] * dt_s
    out = {}
    for c in CLASSES:
        m = classes == c
        out[c] = float(spikes[:, m].sum() / (m.sum() * duration)) if m.any() else 0.0
    return out


def receptor_rates_hz(spikes: np.ndarray, dt_s: float) -> np.ndarray:
    """Mean firing rate (Hz) of each receptor over the given steps: spike
    count / (nstep * dt). spikes: nstep (one receptor) or nstep x nrec."""
    dt_s = positive_number("dt_s", dt_s, "seconds")
    a = _counts(spikes)
    if a.shape[0] == 0:
        raise ValueError("spikes has no steps: a rate needs at least one")
    return a.sum(axis=0) / (a.shape[0] * dt_s)


def spike_times(counts: np.ndarray, dt_s: float, t0_s: float = 0.0) -> np.ndarray:
    """Spike times (s) of one receptor from its counts per step: each spike
    at the middle of its step, t0_s + (k - 0.5) dt, repeated by the count."""
    dt_s = positive_number("dt_s", dt_s, "seconds")
    c = _counts(counts, ndim_max=1).astype(np.int64)
    k = np.repeat(np.arange(c.size), c)
    return t0_s + (k - 0.5) * dt_s


def raster(spikes: np.ndarray, dt_s: float, t0_s: float = 0.0) -> list[np.ndarray]:
    """Spike times (s) per receptor (one array per column of spikes)."""
    a = _counts(spikes)
    if a.ndim == 1:
        a = a[:, None]
    return [spike_times(a[:, r], dt_s, t0_s) for r in range(a.shape[1])]


def psth(
    spikes: np.ndarray, dt_s: float, bin_s: float, t0_s: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Peri-stimulus time histogram: the mean rate (Hz) per receptor in bins of
    bin_s (a whole number of steps), pooled over receptors (and over trials
    if spikes is ntrial x nstep x nrec: time is axis 0 otherwise, axis 1 here).
    Returns (bin start times in s, rate in Hz); a trailing partial bin is
    dropped. Bin start k * bin_s + t0_s - dt_s: row 0's step starts dt before
    t0_s (see the module docstring)."""
    dt_s = positive_number("dt_s", dt_s, "seconds")
    bin_s = positive_number("bin_s", bin_s, "seconds")
    a = np.asarray(spikes)
    if a.ndim == 3:  # trials x steps x receptors -> steps x (trials * receptors)
        a = np.moveaxis(a, 0, 1).reshape(a.shape[1], -1)
    a = _counts(a)
    if a.ndim == 1:
        a = a[:, None]
    steps = bin_s / dt_s
    per_bin = int(round(steps))
    if per_bin < 1 or abs(steps - per_bin) > 1e-9 * steps:
        raise ValueError(f"bin_s = {bin_s} must be a whole number of steps (dt_s = {dt_s})")
    nbin = a.shape[0] // per_bin
    if nbin == 0:
        raise ValueError(
            f"bin_s = {bin_s} s is longer than the spike train ({a.shape[0]} steps of {dt_s} s)"
        )
    counts = a[: nbin * per_bin].reshape(nbin, per_bin, -1).sum(axis=(1, 2))
    rate = counts / (a.shape[1] * bin_s)
    starts = t0_s - dt_s + np.arange(nbin) * bin_s
    return starts, rate


def smoothed_rate(spikes: np.ndarray, dt_s: float, tau_s: float) -> np.ndarray:
    """Firing rate (Hz) smoothed by a causal exponential kernel
    exp(-t / tau) / tau, evaluated at the end of every step, each spike taken
    at the middle of its step: the estimate of the plugin's ``rate`` output
    (attribute ``rate_tau``) from the counts alone. The plugin weights each
    spike at its exact time in the step, so the two differ per spike by a
    factor within exp(+-dt / (2 tau))."""
    dt_s = positive_number("dt_s", dt_s, "seconds")
    tau_s = positive_number("tau_s", tau_s, "seconds")
    a = _counts(spikes)
    decay = math.exp(-dt_s / tau_s)
    gain = math.exp(-0.5 * dt_s / tau_s) / tau_s
    # r_k = decay r_{k-1} + gain n_k, r_{-1} = 0
    return scipy.signal.lfilter([gain], [1.0, -decay], a, axis=0)


@dataclasses.dataclass(frozen=True)
class VectorStrength:
    """Phase locking of spikes to a period (Goldberg & Brown 1969)."""

    vs: float  # |mean of exp(i 2 pi f t)| over spikes, 0 (none) to 1 (all at one phase)
    phase_rad: float  # mean phase, (-pi, pi]
    n: int  # spikes
    rayleigh_z: float  # n vs^2
    p_value: float  # Rayleigh test of uniform phases (Zar 1999, eq. 27.4)


def rayleigh_p(n: int, vs: float) -> float:
    """P(vector strength >= vs) for n spikes at independent uniform phases
    (Rayleigh test; Zar 1999, Biostatistical Analysis, eq. 27.4:
    p = exp(sqrt(1 + 4n + 4(n^2 - R^2)) - (1 + 2n)), R = n vs)."""
    if n <= 0:
        return 1.0
    r = n * vs
    return float(min(1.0, math.exp(math.sqrt(1 + 4 * n + 4 * (n * n - r * r)) - (1 + 2 * n))))


def vector_strength(
    times_s: np.ndarray, freq_hz: float, weights: np.ndarray | None = None
) -> VectorStrength:
    """Vector strength of spike times at freq_hz (Goldberg & Brown 1969):
    vs = |sum w_j exp(i 2 pi f t_j)| / sum w_j, with the Rayleigh statistic
    Z = n vs^2 and its p-value. weights (spike counts at each time) default
    to 1; n is their sum."""
    freq_hz = positive_number("freq_hz", freq_hz, "Hz")
    t = np.asarray(times_s, dtype=np.float64).ravel()
    w = np.ones_like(t) if weights is None else np.asarray(weights, dtype=np.float64).ravel()
    if w.shape != t.shape:
        raise ValueError(f"weights has {w.size} entries for {t.size} spike times")
    if w.size and (w.min() < 0 or not np.all(np.isfinite(w))):
        raise ValueError("weights must be non-negative finite spike counts")
    n = float(w.sum())
    if n == 0:
        return VectorStrength(0.0, 0.0, 0, 0.0, 1.0)
    # phase of t mod the period first: keeps exp() exact for long trains
    phase = 2 * np.pi * np.mod(t * freq_hz, 1.0)
    z = np.sum(w * np.exp(1j * phase)) / n
    vs = float(min(1.0, abs(z)))
    n_int = int(round(n))
    return VectorStrength(vs, float(np.angle(z)), n_int, n * vs * vs, rayleigh_p(n_int, vs))


def vector_strength_counts(
    counts: np.ndarray, dt_s: float, freq_hz: float, t0_s: float = 0.0
) -> VectorStrength:
    """Vector strength of one receptor's counts per step (spikes at step
    middles, see spike_times). Timing is known to +-dt/2, so a train locked
    to one phase reads vs >= cos(pi f dt) at worst."""
    c = _counts(counts, ndim_max=1)
    k = np.nonzero(c)[0]
    return vector_strength(
        t0_s + (k - 0.5) * positive_number("dt_s", dt_s, "seconds"), freq_hz, c[k]
    )


def spike_spectrum(
    spikes: np.ndarray, dt_s: float, segment_s: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Power spectral density of spike trains, averaged over receptors.
    Each train is the rate signal counts / dt (Hz); Welch's method with Hann
    windows of segment_s (default: the whole train, one segment), the mean
    removed per segment, one-sided. Units Hz^2 / Hz = Hz: a Poisson train of
    rate lam reads 2 lam at every f > 0; a train locked to f0 shows lines at
    f0 and its harmonics."""
    dt_s = positive_number("dt_s", dt_s, "seconds")
    a = _counts(spikes)
    if a.ndim == 1:
        a = a[:, None]
    n = a.shape[0]
    nper = (
        n
        if segment_s is None
        else int(round(positive_number("segment_s", segment_s, "seconds") / dt_s))
    )
    if not 8 <= nper <= n:
        raise ValueError(
            f"segment_s must span 8 to {n} steps (the train's length); got {nper} steps"
        )
    f, p = scipy.signal.welch(
        a / dt_s,
        fs=1.0 / dt_s,
        window="hann",
        nperseg=nper,
        detrend="constant",
        scaling="density",
        axis=0,
    )
    return f, p.mean(axis=1)


def stress_spectrum(stress: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Power spectrum of receptor stress traces (nstep x nrec), averaged over
    receptors (incoherently: receptors see the texture at different phases).
    Each trace is linearly detrended and Hann-windowed; the bin width is
    1 / (nstep * dt)."""
    if stress.ndim == 1:
        stress = stress[:, None]
    f, p = scipy.signal.periodogram(
        stress, fs=1.0 / dt_s, window="hann", detrend="linear", axis=0, scaling="spectrum"
    )
    return f, p.mean(axis=1)


def spectral_peaks(
    freqs: np.ndarray,
    power: np.ndarray,
    n: int = 5,
    fmin_hz: float = 2.0,
    fmax_hz: float | None = None,
    rel_height: float = 1e-6,
) -> list[float]:
    """Up to n peak frequencies, strongest first (local maxima above
    rel_height x the strongest, within [fmin_hz, fmax_hz]), each refined by
    parabolic interpolation of log power over the three bins around it."""
    sel = freqs >= fmin_hz
    if fmax_hz is not None:
        sel &= freqs <= fmax_hz
    idx = np.nonzero(sel)[0]
    if idx.size < 3:
        return []
    p = power[idx]
    peaks, _ = scipy.signal.find_peaks(p, height=rel_height * p.max())
    order = peaks[np.argsort(p[peaks])[::-1]][:n]
    df = freqs[1] - freqs[0]
    out = []
    for k in order:
        i = idx[k]
        if 0 < i < len(power) - 1 and min(power[i - 1 : i + 2]) > 0:
            a, b, c = np.log(power[i - 1 : i + 2])
            denom = a - 2 * b + c
            shift = 0.5 * (a - c) / denom if denom != 0 else 0.0
            out.append(float(freqs[i] + np.clip(shift, -0.5, 0.5) * df))
        else:
            out.append(float(freqs[i]))
    return out


@dataclasses.dataclass(frozen=True)
class BandLine:
    """A spectral line looked for in a band around an expected frequency.

    peak_hz: the strongest bin inside [lo_hz, hi_hz], refined by parabolic
    interpolation of log power (None if the band holds no bin); power_pa2:
    the power summed over the band; share: that power over the power of the
    whole spectrum from fmin_hz up; contrast: the band's mean power per bin
    over the mean of its two flanks (bands of the same width either side):
    well above 1 where a line stands out of the background."""

    expected_hz: float
    lo_hz: float
    hi_hz: float
    peak_hz: float | None
    power_pa2: float
    share: float
    contrast: float


def band_line(
    freqs: np.ndarray,
    power: np.ndarray,
    f_hz: float,
    rel_half_width: float = 0.15,
    fmin_hz: float = 5.0,
) -> BandLine:
    """The line near f_hz: power, peak and contrast in f_hz x (1 +- rel_half_width)."""
    if not (f_hz > 0 and 0 < rel_half_width < 1):
        raise ValueError(
            f"f_hz = {f_hz} must be > 0 and rel_half_width = {rel_half_width} in (0, 1)"
        )
    lo, hi = f_hz * (1 - rel_half_width), f_hz * (1 + rel_half_width)
    width = hi - lo

    def mean_in(a, b):
        sel = (freqs >= a) & (freqs <= b)
        return float(power[sel].mean()) if sel.any() else 0.0

    sel = (freqs >= lo) & (freqs <= hi)
    band_power = float(power[sel].sum())
    total = float(power[freqs >= fmin_hz].sum())
    peak = None
    if sel.any():
        idx = np.nonzero(sel)[0]
        i = int(idx[np.argmax(power[idx])])
        peak = float(freqs[i])
        if 0 < i < len(power) - 1 and min(power[i - 1 : i + 2]) > 0:
            a, b, c = np.log(power[i - 1 : i + 2])
            denom = a - 2 * b + c
            shift = 0.5 * (a - c) / denom if denom != 0 else 0.0
            peak += float(np.clip(shift, -0.5, 0.5) * (freqs[1] - freqs[0]))
    flanks = [m for m in (mean_in(max(lo - width, fmin_hz), lo), mean_in(hi, hi + width)) if m > 0]
    flank = float(np.mean(flanks)) if flanks else 0.0
    band_mean = mean_in(lo, hi)
    return BandLine(
        expected_hz=float(f_hz),
        lo_hz=lo,
        hi_hz=hi,
        peak_hz=peak,
        power_pa2=band_power,
        share=band_power / total if total > 0 else 0.0,
        contrast=band_mean / flank if flank > 0 else float("inf") if band_mean > 0 else 0.0,
    )


def power_at(freqs: np.ndarray, power: np.ndarray, f_hz: float, half_width_bins: int = 1) -> float:
    """Spectral power summed over the bins within half_width_bins of f_hz."""
    i = int(np.argmin(np.abs(freqs - f_hz)))
    lo, hi = max(0, i - half_width_bins), min(len(power), i + half_width_bins + 1)
    return float(power[lo:hi].sum())


def spikes_per_cycle(
    counts: np.ndarray,
    dt_s: float,
    freq_hz: float,
    t0_s: float = 0.0,
    origin_s: float | None = None,
) -> np.ndarray:
    """Spike count of one receptor in each whole stimulus cycle of period
    1/freq_hz inside the train: cycle m spans [origin + m / f,
    origin + (m + 1) / f), origin_s defaulting to t0_s (row 0's time), each
    spike at its step middle. Entrainment 1:1 means every entry is 1; put
    the origin half a period from the spikes' mean phase (vector_strength)
    so that +-dt/2 timing never moves a spike across a cycle boundary."""
    dt_s = positive_number("dt_s", dt_s, "seconds")
    freq_hz = positive_number("freq_hz", freq_hz, "Hz")
    c = _counts(counts, ndim_max=1)
    origin = t0_s if origin_s is None else float(origin_s)
    t = t0_s + (np.arange(c.size) - 0.5) * dt_s
    end = t0_s + (c.size - 1) * dt_s  # the last step's end
    first = math.ceil((t0_s - dt_s - origin) * freq_hz - 1e-9)  # first cycle inside the train
    last = math.floor((end - origin) * freq_hz + 1e-9)  # one past the last whole cycle
    if last <= first:
        return np.zeros(0)
    cyc = np.floor((t - origin) * freq_hz).astype(np.int64)
    ok = (cyc >= first) & (cyc < last)
    return np.bincount(cyc[ok] - first, weights=c[ok], minlength=last - first)
