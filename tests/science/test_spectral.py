"""Rollouts: the receptor stress oscillates at V/D when a grating is scanned."""

import numpy as np
import pytest
from conftest import fast_tip

from mjtouch import analysis
from mjtouch.experiments import rollout
from mjtouch.scene import scenes


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
        res = rollout.run_slide(
            fast_tip(ridges=False), scenes.Texture(kind=kind, period_m=D), proto, 0.4
        )
        f, p = analysis.stress_spectrum(res.stress[res.window(0.1)], res.dt)
        power[kind] = analysis.power_at(f, p, proto.speed_m_s / D)
    assert power["flat"] < 1e-4 * power["grating"], power


@pytest.mark.parametrize("kind", ["flat", "grating"])
def test_no_line_at_speed_over_taxel_pitch(kind):
    # The taxel grid is fixed in the skin while the texture moves at V: a
    # renderer that sampled cells at points would add a line at V / pitch
    # (267 Hz here). Cell means are exact, so the power there must be at the
    # noise floor: within 10x the median of the bins around it (a periodogram
    # bin of noise is exponential, so noise alone exceeds 10x its median
    # (6.9x its mean) in one of the 5 bins tested with probability 5e-3).
    pitch, speed = 1.5e-4, 0.04
    tip = scenes.Fingertip(nx=48, pitch_m=pitch, ridges=False, skin={"outputs": "stress force"})
    proto = scenes.Protocol(speed_m_s=speed, timestep_s=2e-4, press_s=0.1)
    res = rollout.run_slide(tip, scenes.Texture(kind=kind, period_m=1e-3), proto, 0.4)
    f, p = analysis.stress_spectrum(res.stress[res.window(0.05)], res.dt)
    k = int(np.argmin(abs(f - speed / pitch)))
    floor = np.median(np.r_[p[k - 30 : k - 5], p[k + 5 : k + 30]])
    assert p[k - 2 : k + 3].max() <= 10 * floor, (p[k - 2 : k + 3], floor)
    if kind == "grating":  # the texture's own line stands far above it
        assert analysis.power_at(f, p, speed / 1e-3) > 1e4 * p[k - 2 : k + 3].max()


def test_displacement_controlled_press_and_slide():
    # Protocol(control="displacement"): a position servo holds the pad's pole
    # depth_m below the plate; the normal force is then MuJoCo's contact force
    # at that penetration: steady while sliding and rising with the depth,
    # and the receptors' stress and the SA1 rate with it.
    forces, stress = [], []
    for depth in (0.5e-3, 1e-3, 1.5e-3):
        tip = scenes.Fingertip(nx=48, pitch_m=1.5e-4, skin={"outputs": "spikes stress force"})
        proto = scenes.Protocol(
            control="displacement", depth_m=depth, timestep_s=2e-4, press_s=0.15
        )
        res = rollout.run_slide(tip, scenes.Texture(period_m=1e-3), proto, 0.2)
        fn = res.force[res.window(0.05)][:, 0]
        assert fn.std() < 1e-3 * fn.mean()
        forces.append(fn.mean())
        stress.append(res.stress[res.window(0.05)][:, res.layout.mask("SA1")].mean())
    assert forces[0] > 0 and np.all(np.diff(forces) > 0), forces
    assert np.all(np.diff(stress) > 0), stress
    with pytest.raises(ValueError, match="depth_m = 0.01 is out of range"):
        scenes.scene_xml(protocol=scenes.Protocol(control="displacement", depth_m=0.01))
    with pytest.raises(ValueError, match="control = 'speed' is not one of"):
        scenes.scene_xml(protocol=scenes.Protocol(control="speed"))
