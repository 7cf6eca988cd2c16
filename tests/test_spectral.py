"""Rollouts: the receptor stress oscillates at V/D when a grating is scanned."""

import numpy as np
import pytest

from mjtouch import analysis, rollout, scenes

from conftest import fast_tip


@pytest.mark.parametrize("speed", [0.02, 0.04])
def test_strongest_stress_peak_at_v_over_d(speed):
    D = 1.0e-3
    proto = scenes.Protocol(speed_m_s=speed, timestep_s=2e-4, press_s=0.1)
    res = rollout.run_slide(fast_tip(), scenes.Texture(period_m=D), proto, duration_s=0.5)
    w = res.window(settle_s=0.05)
    f, p = analysis.stress_spectrum(res.stress[w], res.dt)
    bin_hz = f[1] - f[0]
    peaks = analysis.spectral_peaks(f, p, fmin_hz=5.0)
    assert peaks, "no spectral peak"
    assert abs(peaks[0] - speed / D) <= bin_hz, (peaks[:3], speed / D, bin_hz)
    # the measured sliding speed is the commanded one (intvelocity servo)
    x = res.finger_x_m[w]
    v = np.polyfit(res.time_s[w], x, 1)[0]
    assert abs(v / speed - 1) < 2e-3


def test_flat_plate_has_no_texture_line():
    # Smooth skin on a flat plate: nothing moves relative to the skin, so the
    # stress has no line at V/D, while the grating's dominates its spectrum.
    proto = scenes.Protocol(speed_m_s=0.03, timestep_s=2e-4, press_s=0.1)
    D = 1e-3
    power = {}
    for kind in ("flat", "grating"):
        res = rollout.run_slide(fast_tip(ridges=False), scenes.Texture(kind=kind, period_m=D),
                                proto, 0.4)
        f, p = analysis.stress_spectrum(res.stress[res.window(0.1)], res.dt)
        power[kind] = analysis.power_at(f, p, proto.speed_m_s / D)
    assert power["flat"] < 1e-4 * power["grating"], power
