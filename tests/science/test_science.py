"""Spectral-peak rollouts (REFERENCE section 7): texture lines at V/D."""

import numpy as np
import pytest

from mjtouch.analysis import testing
from mjtouch.scene import scenes


@pytest.mark.parametrize("period_m", [0.2e-3, 0.6e-3, 1.8e-3])
@pytest.mark.parametrize("speed_m_s", [0.015, 0.025, 0.04])
def test_grating_peak_at_v_over_d(period_m, speed_m_s):
    # 0.5 s of sliding: even D = 1.8 mm at 15 mm/s gives 4 periods; the FFT
    # bin is 1 / 0.45 s = 2.2 Hz. The line must be the strongest peak.
    spec = testing.slide_spectrum(texture=testing.grating(period_m), speed_m_s=speed_m_s)
    testing.assert_peak_at(spec, speed_m_s / period_m, bins=1)
    # harmonics: a grating of duty cycle 1/2 has odd harmonics; 3 V/D is
    # among the peaks if it lies below the 2.5 kHz Nyquist limit
    f3 = 3 * speed_m_s / period_m
    if f3 < 1000:
        assert any(abs(p - f3) <= spec.bin_hz for p in spec.peaks(n=8)), (f3, spec.peaks(n=8))


def test_line_frequency_scales_linearly_with_speed():
    period = 0.6e-3
    speeds = np.array([0.015, 0.025, 0.04])
    f = np.array(
        [
            testing.slide_spectrum(texture=testing.grating(period), speed_m_s=v).peaks()[0]
            for v in speeds
        ]
    )
    slope, intercept = np.polyfit(speeds, f, 1)
    # slope 1/D; intercept 0 within a bin (2.2 Hz)
    assert slope == pytest.approx(1 / period, rel=0.01)
    assert abs(intercept) < 2.2


# -- Fingerprint filtering (Scheibert et al. 2009) ---------------------------

RIDGE_PITCH_M = 0.45e-3


def _ridge_filtering_spectra(speed_m_s, ridge_angle_deg=0.0):
    """Ridged and smooth skins over the same fine random texture (20 um rms,
    60 um correlation length), `elastic` contact (the ridges carry the load in
    partial contact; a Winkler foundation presses them flat) and exact
    stress (stress_method auto: the hierarchical path's block approximation
    would leak fine-scale traction into the smooth skin's spectrum)."""
    out = {}
    for ridges in (True, False):
        tip = scenes.Fingertip(
            nx=64,
            pitch_m=1.5e-4,
            ridges=ridges,
            ridge_angle_deg=ridge_angle_deg,
            skin={"pressure": "elastic", "outputs": "stress force"},
        )
        out[ridges] = testing.slide_spectrum(
            texture=testing.random_texture(),
            speed_m_s=speed_m_s,
            ridges=ridges,
            duration_s=0.4,
            timestep_s=1e-3,
            tip=tip,
        )
    return out[True], out[False]


def test_fingerprint_ridges_add_a_peak_at_v_over_lambda():
    peaks = {}
    for v in (0.025, 0.05):
        ridged, smooth = _ridge_filtering_spectra(v)
        f, fl = ridged.freqs_hz, v / RIDGE_PITCH_M
        # Power in the band V/lambda +-15% (the ridge array's line is
        # V / (contact length) ~ 4-8 Hz wide, the bins 2.8 Hz): ridged over
        # smooth at least 10, as the issue asks (measured 26).
        band = (f > 0.85 * fl) & (f < 1.15 * fl)
        ratio = ridged.power[band].sum() / smooth.power[band].sum()
        assert ratio >= 10, (v, ratio)
        testing.assert_power_ratio(ridged, smooth, fl, at_least=10)
        # The ridged spectrum peaks there: its 5-bin moving average has its
        # maximum over V/lambda +-30% within 15% of V/lambda.
        smoothed = np.convolve(ridged.power, np.ones(5) / 5, mode="same")
        win = (f > 0.7 * fl) & (f < 1.3 * fl)
        peaks[v] = f[win][np.argmax(smoothed[win])]
        assert abs(peaks[v] / fl - 1) <= 0.15, (v, peaks[v], fl)
    # ... and the peak moves with V (twice the speed, twice the frequency).
    assert peaks[0.05] / peaks[0.025] == pytest.approx(2.0, rel=0.15)


# -- Shao et al. 2010 (seed 001): the fine texture needs the ridges ----------


def test_shao2010_fine_grating_lines_need_ridges():
    # examples/shao2010.py --quick: D = 0.2 mm at 25 mm/s (V/D = 125 Hz), 0.1 N,
    # Mises stress at the Meissner (0.75 mm) and Pacinian (2 mm) depths. The
    # paper's findings our model shares are asserted; where it differs (the
    # README's comparison) nothing is.
    import pathlib
    import runpy

    ex = runpy.run_path(str(pathlib.Path(__file__).parents[2] / "examples" / "shao2010.py"))
    ridged, smooth = ex["run"](quick=True)
    assert ridged["ridges"] and not smooth["ridges"]
    fd = ridged["v_over_d_hz"]
    for site in ("Meissner", "Pacinian"):
        r, s = ridged["sites"][site], smooth["sites"][site]
        # with ridges: the texture line is the strongest peak (within a bin)
        assert abs(r["peaks_hz"][0] - fd) <= r["fft_bin_hz"], (site, r["peaks_hz"])
        # without ridges no clear line: 100x less power at V/D (the 0.75-2 mm
        # depth filters 0.2 mm relief by exp(-2 pi z / D) < 1e-10; what is
        # left comes from the contact edges)
        assert s["power_at_harmonics_pa2"][0] < 1e-2 * r["power_at_harmonics_pa2"][0], site
    # the harmonics 2V/D and 3V/D are spectral peaks at the Pacinian site
    pc = ridged["sites"]["Pacinian"]
    for k in (2, 3):
        assert any(abs(p - k * fd) <= pc["fft_bin_hz"] for p in pc["peaks_hz"]), (k, pc["peaks_hz"])


def test_ridges_along_the_sliding_direction_do_not_filter():
    # Ridges parallel to the motion (ridge_angle 90 deg) present no ridge
    # period along the path, so the texture's passage is not sampled at
    # V/lambda: the ridged/smooth band power there stays within the range of
    # two smooth-skin spectra's scatter (a factor 3), far from the >= 10 of
    # ridges across the motion.
    ridged, smooth = _ridge_filtering_spectra(0.025, ridge_angle_deg=90.0)
    f, fl = ridged.freqs_hz, 0.025 / RIDGE_PITCH_M
    band = (f > 0.85 * fl) & (f < 1.15 * fl)
    ratio = ridged.power[band].sum() / smooth.power[band].sum()
    assert ratio < 3, ratio
