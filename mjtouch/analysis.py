"""Rates and spectra of receptor responses."""

from __future__ import annotations

import numpy as np
import scipy.signal

CLASSES = ("SA1", "RA", "PC")


def rates_hz(spikes: np.ndarray, dt_s: float, classes: np.ndarray) -> dict[str, float]:
    """Mean firing rate per class over the given steps (spikes: nstep x nrec)."""
    duration = spikes.shape[0] * dt_s
    out = {}
    for c in CLASSES:
        m = classes == c
        out[c] = float(spikes[:, m].sum() / (m.sum() * duration)) if m.any() else 0.0
    return out


def stress_spectrum(stress: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Power spectrum of receptor stress traces (nstep x nrec), averaged over
    receptors (incoherently: receptors see the texture at different phases).
    Each trace is linearly detrended and Hann-windowed; the bin width is
    1 / (nstep * dt)."""
    if stress.ndim == 1:
        stress = stress[:, None]
    f, p = scipy.signal.periodogram(stress, fs=1.0 / dt_s, window="hann", detrend="linear",
                                    axis=0, scaling="spectrum")
    return f, p.mean(axis=1)


def spectral_peaks(freqs: np.ndarray, power: np.ndarray, n: int = 5, fmin_hz: float = 2.0,
                   fmax_hz: float | None = None, rel_height: float = 1e-6) -> list[float]:
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
        if 0 < i < len(power) - 1 and min(power[i - 1:i + 2]) > 0:
            a, b, c = np.log(power[i - 1:i + 2])
            denom = a - 2 * b + c
            shift = 0.5 * (a - c) / denom if denom != 0 else 0.0
            out.append(float(freqs[i] + np.clip(shift, -0.5, 0.5) * df))
        else:
            out.append(float(freqs[i]))
    return out


def power_at(freqs: np.ndarray, power: np.ndarray, f_hz: float, half_width_bins: int = 1) -> float:
    """Spectral power summed over the bins within half_width_bins of f_hz."""
    i = int(np.argmin(np.abs(freqs - f_hz)))
    lo, hi = max(0, i - half_width_bins), min(len(power), i + half_width_bins + 1)
    return float(power[lo:hi].sum())
