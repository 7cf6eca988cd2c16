"""Spectral-peak rollouts (REFERENCE section 7): texture lines at V/D."""

import numpy as np
import pytest

from mjtouch import testing


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
    f = np.array([testing.slide_spectrum(texture=testing.grating(period), speed_m_s=v).peaks()[0]
                  for v in speeds])
    slope, intercept = np.polyfit(speeds, f, 1)
    # slope 1/D; intercept 0 within a bin (2.2 Hz)
    assert slope == pytest.approx(1 / period, rel=0.01)
    assert abs(intercept) < 2.2
