"""Figures of receptor responses (matplotlib, the optional ``plot`` extra).

Each function draws into ``ax`` if given, else into a new
``matplotlib.figure.Figure`` (no pyplot, no GUI backend: save it with
``ax.figure.savefig(path)``), and returns the axes. matplotlib is imported
only when a figure is drawn; without it the call raises ImportError naming
the extra to install.
"""

from __future__ import annotations

import numpy as np

from mjtouch.analysis import signals

CLASS_COLOURS = {"SA1": "tab:blue", "RA": "tab:green", "PC": "tab:purple"}


def _matplotlib_figure():
    try:
        import matplotlib.figure
    except ImportError as e:
        raise ImportError(
            "mjtouch.analysis.figures needs matplotlib, the optional `plot` extra: "
            "pip install 'mjtouch[plot]'"
        ) from e
    return matplotlib.figure


def _axes(ax):
    if ax is not None:
        return ax
    return _matplotlib_figure().Figure(figsize=(6.4, 4.0)).add_subplot()


def plot_raster(spikes: np.ndarray, dt_s: float, classes=None, t0_s: float = 0.0, ax=None):
    """Raster: one row per receptor (column of spikes), a tick per spike at
    its step middle; rows coloured by class if classes is given."""
    _matplotlib_figure()
    ax = _axes(ax)
    trains = signals.raster(spikes, dt_s, t0_s)
    if classes is not None and len(classes) != len(trains):
        raise ValueError(f"classes has {len(classes)} entries for {len(trains)} receptors")
    colours = [CLASS_COLOURS.get(str(c), "k") for c in classes] if classes is not None else "k"
    ax.eventplot(trains, colors=colours, lineoffsets=np.arange(len(trains)), linelengths=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("receptor")
    return ax


def plot_psth(
    spikes: np.ndarray,
    dt_s: float,
    bin_s: float,
    t0_s: float = 0.0,
    ax=None,
    label: str | None = None,
):
    """PSTH (mean rate per receptor, Hz) as a step plot over bins of bin_s."""
    _matplotlib_figure()
    ax = _axes(ax)
    starts, rate = signals.psth(spikes, dt_s, bin_s, t0_s)
    edges = np.append(starts, starts[-1] + bin_s)
    ax.stairs(rate, edges, label=label)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("rate (Hz)")
    return ax


def plot_spectrum(freqs_hz: np.ndarray, power: np.ndarray, ax=None, label: str | None = None):
    """A spectrum (spike or stress) on log power axes, the f = 0 bin left out."""
    _matplotlib_figure()
    ax = _axes(ax)
    f, p = np.asarray(freqs_hz), np.asarray(power)
    keep = f > 0
    ax.semilogy(f[keep], p[keep], label=label)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("power")
    return ax


def plot_tuning(
    freqs_hz: np.ndarray, thresholds: np.ndarray, ax=None, label: str | None = None, unit: str = ""
):
    """Threshold vs vibration frequency on log-log axes (a tuning curve)."""
    _matplotlib_figure()
    ax = _axes(ax)
    ax.loglog(freqs_hz, thresholds, "o-", label=label)
    ax.set_xlabel("vibration frequency (Hz)")
    ax.set_ylabel(f"threshold{f' ({unit})' if unit else ''}")
    return ax


def plot_phase_histogram(times_s: np.ndarray, freq_hz: float, nbins: int = 24, ax=None):
    """Histogram of spike phases at freq_hz (cycles, 0 to 1), titled with the
    vector strength."""
    _matplotlib_figure()
    if nbins < 2:
        raise ValueError(f"nbins = {nbins} must be >= 2")
    ax = _axes(ax)
    phase = np.mod(np.asarray(times_s, dtype=np.float64) * freq_hz, 1.0)
    ax.hist(phase, bins=nbins, range=(0.0, 1.0))
    vs = signals.vector_strength(times_s, freq_hz)
    ax.set_title(f"vector strength {vs.vs:.3f} (n = {vs.n})")
    ax.set_xlabel("phase (cycles)")
    ax.set_ylabel("spikes")
    return ax
