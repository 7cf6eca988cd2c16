"""Errors against a reference run (stress, spectral peak, spike rates), the
Pareto front and the cost fits."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from mjtouch.analysis import signals
from mjtouch.bench.configs import FMAX_HZ, FMIN_HZ, SKIP_S, SPECTRAL_MIN_S
from mjtouch.scene.sensor import CLASSES


@dataclasses.dataclass
class Trace:
    stress: np.ndarray  # (nstep, nrec), Pa
    spikes: np.ndarray  # (nstep, nrec), counts
    classes: np.ndarray  # (nrec,)
    dt_s: float


def class_means(stress: np.ndarray, classes: np.ndarray) -> tuple[np.ndarray, list[str]]:
    present = [c for c in CLASSES if (classes == c).any()]
    return np.stack([stress[:, classes == c].mean(axis=1) for c in present], axis=1), present


def errors(row: Trace, ref: Trace, basis: str = "receptor", skip_s: float = SKIP_S) -> dict:
    """Errors of row against ref over their common window after skip_s.
    The row's timestep must be a whole multiple of the reference's; stress
    is compared at the row's sample times. basis "receptor": receptor by
    receptor (same sites); "class mean": the class-mean traces."""
    m = row.dt_s / ref.dt_s
    if m < 1 - 1e-9 or abs(m - round(m)) > 1e-6 * m:
        raise ValueError(
            f"row timestep {row.dt_s} s is not a whole multiple of the reference's {ref.dt_s} s"
        )
    m = int(round(m))
    k0 = int(round(skip_s / row.dt_s))
    n = min(row.stress.shape[0], ref.stress.shape[0] // m)
    if n - k0 < 2:
        raise ValueError(f"the window after skip_s = {skip_s} s has {n - k0} steps; run longer")
    window_s = (n - k0) * row.dt_s
    idx = (np.arange(k0, n) + 1) * m - 1  # reference rows at the row's sample times
    a, b = row.stress[k0:n], ref.stress[idx]
    if basis == "class mean":
        a, ca = class_means(a, row.classes)
        b, cb = class_means(b, ref.classes)
        if ca != cb:
            raise ValueError(f"classes differ: {ca} vs {cb}")
    elif basis != "receptor" or a.shape != b.shape or not np.array_equal(row.classes, ref.classes):
        raise ValueError("basis 'receptor' needs the same receptors in row and reference")
    diff = np.sqrt(np.mean((a - b) ** 2))
    scale = np.sqrt(np.mean(b**2))
    out = {
        "stress_rms_pa": float(diff),
        "stress_rms_rel": float(diff / scale) if scale > 0 else (0.0 if diff == 0 else None),
        "peak_freq_hz": None,
        "peak_amp_rel": None,
        "ref_peak_hz": None,
    }
    ref_win = slice(k0 * m, n * m)
    if window_s >= SPECTRAL_MIN_S - 1e-12:
        fmax = min(FMAX_HZ, 0.5 / row.dt_s)
        f, p = signals.stress_spectrum(row.stress[k0:n], row.dt_s)
        fr, pr = signals.stress_spectrum(ref.stress[ref_win], ref.dt_s)
        peak_ref = signals.spectral_peaks(fr, pr, n=1, fmin_hz=FMIN_HZ, fmax_hz=fmax)
        peak_row = signals.spectral_peaks(f, p, n=1, fmin_hz=FMIN_HZ, fmax_hz=fmax)
        if peak_ref and peak_row:
            amp = math.sqrt(signals.power_at(f, p, peak_ref[0]))
            amp_ref = math.sqrt(signals.power_at(fr, pr, peak_ref[0]))
            out["ref_peak_hz"] = peak_ref[0]
            out["peak_freq_hz"] = abs(peak_row[0] - peak_ref[0])
            out["peak_amp_rel"] = abs(amp / amp_ref - 1) if amp_ref > 0 else None
    r = signals.rates_hz(row.spikes[k0:n], row.dt_s, row.classes)
    rr = signals.rates_hz(ref.spikes[ref_win], ref.dt_s, ref.classes)
    total = sum(rr.values())
    dev = sum(abs(r[c] - rr[c]) for c in CLASSES)
    out["spike_rate_rel"] = dev / total if total > 0 else (0.0 if dev == 0 else None)
    out["spike_rate_hz"] = {c: r[c] - rr[c] for c in CLASSES}
    out["ref_rate_hz"] = rr
    out["window_s"] = window_s
    return out


def pareto_front(costs, errs) -> list[bool]:
    """True where no other point is at most as costly and at most as wrong
    and better in one (None errors are never on the front)."""
    pts = list(zip(costs, errs))
    out = []
    for i, (c, e) in enumerate(pts):
        if e is None or c is None:
            out.append(False)
            continue
        dominated = any(
            j != i and e2 is not None and c2 <= c and e2 <= e and (c2 < c or e2 < e)
            for j, (c2, e2) in enumerate(pts)
        )
        out.append(not dominated)
    return out


def fit_power_law(x, y) -> dict:
    """Least squares of log y = log a + b log x: the exponent b, prefactor a
    and R^2 of the log-log fit (points with x, y <= 0 are dropped)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 2 or np.ptp(np.log(x[ok])) == 0:
        return {"exponent": None, "prefactor": None, "r2": None, "n": int(ok.sum())}
    lx, ly = np.log(x[ok]), np.log(y[ok])
    b, a = np.polyfit(lx, ly, 1)
    res = ly - (a + b * lx)
    ss = np.sum((ly - ly.mean()) ** 2)
    return {
        "exponent": float(b),
        "prefactor": float(math.exp(a)),
        "r2": float(1 - np.sum(res**2) / ss) if ss > 0 else 1.0,
        "n": int(ok.sum()),
    }


def fit_affine(x, y) -> dict:
    """Least squares of y = intercept + slope x, with R^2."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if x.size < 2 or np.ptp(x) == 0:
        return {"intercept": None, "slope": None, "r2": None, "n": int(x.size)}
    slope, intercept = np.polyfit(x, y, 1)
    ss = np.sum((y - y.mean()) ** 2)
    res = y - (intercept + slope * x)
    return {
        "intercept": float(intercept),
        "slope": float(slope),
        "r2": float(1 - np.sum(res**2) / ss) if ss > 0 else 1.0,
        "n": int(x.size),
    }
