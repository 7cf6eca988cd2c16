"""Analysis of skin outputs, and the reference solutions they are checked against.

- :mod:`mjtouch.analysis.signals`   rates, rasters, PSTHs, vector strength and
  spectra of spike trains and stress (re-exported here: ``mjtouch.analysis.rates_hz``)
- :mod:`mjtouch.analysis.reference_solutions`   analytic and numerical oracles
  (Hertz, the layered half-space)
- :mod:`mjtouch.analysis.figures`   raster and PSTH plots (matplotlib)
- :mod:`mjtouch.analysis.testing`   helpers for tests of a skin scene
"""

from mjtouch.analysis.signals import (
    CLASSES,
    BandLine,
    VectorStrength,
    band_line,
    power_at,
    psth,
    raster,
    rates_hz,
    rayleigh_p,
    receptor_rates_hz,
    smoothed_rate,
    spectral_peaks,
    spike_spectrum,
    spike_times,
    spikes_per_cycle,
    stress_spectrum,
    vector_strength,
    vector_strength_counts,
)

__all__ = [
    "CLASSES",
    "BandLine",
    "band_line",
    "power_at",
    "psth",
    "raster",
    "rates_hz",
    "rayleigh_p",
    "receptor_rates_hz",
    "smoothed_rate",
    "spectral_peaks",
    "spike_spectrum",
    "spike_times",
    "spikes_per_cycle",
    "stress_spectrum",
    "vector_strength",
    "vector_strength_counts",
    "VectorStrength",
]
