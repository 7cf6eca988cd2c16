"""Spectral-peak rollouts in a few lines of pytest.

    from mjtouch.analysis import testing

    def test_grating_line():
        spec = testing.slide_spectrum(texture=testing.grating(period_m=1e-3), speed_m_s=0.04)
        testing.assert_peak_at(spec, 0.04 / 1e-3, bins=1)

    def test_fingerprint_filtering():
        # ridges filter only with contact that lets them carry the load:
        # the boundary-element `elastic` model (Winkler presses them flat)
        def tip(ridges):
            return scenes.Fingertip(nx=64, pitch_m=1.5e-4, ridges=ridges,
                                    skin={"pressure": "elastic"})
        ridged, smooth = (testing.slide_spectrum(texture=testing.random_texture(), ridges=r,
                                                 tip=tip(r), timestep_s=1e-3, duration_s=0.4)
                          for r in (True, False))
        testing.assert_power_ratio(ridged, smooth, ridged.speed_m_s / 0.45e-3, at_least=10)

A rollout presses the fingertip, slides it over the texture, and returns the
power spectrum of the receptor stress (averaged over the receptors of one
class or all) with its frequency resolution, so assertions are stated in FFT
bins. Defaults are sized for tests: a 64 x 64 taxel skin at 0.15 mm, dt = 2e-4 s
(5 kHz sampling), 0.5 s of sliding.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mjtouch.analysis import signals
from mjtouch.experiments import rollout
from mjtouch.scene import scenes


@dataclasses.dataclass
class Spectrum:
    freqs_hz: np.ndarray
    power: np.ndarray  # Pa^2, mean over the selected receptors
    speed_m_s: float
    site: str
    result: rollout.SlideResult

    @property
    def bin_hz(self) -> float:
        return float(self.freqs_hz[1] - self.freqs_hz[0])

    def peaks(self, n: int = 6, fmin_hz: float = 5.0) -> list[float]:
        return signals.spectral_peaks(self.freqs_hz, self.power, n=n, fmin_hz=fmin_hz)

    def power_at(self, f_hz: float, bins: int = 1) -> float:
        return signals.power_at(self.freqs_hz, self.power, f_hz, bins)


def grating(period_m: float = 1e-3, **kw) -> scenes.Texture:
    kw.setdefault("edge_m", min(0.05e-3, period_m / 8))
    kw.setdefault("resolution_m", min(2e-5, period_m / 20))
    return scenes.Texture(kind="grating", period_m=period_m, **kw)


def random_texture(
    rms_m: float = 20e-6, corr_length_m: float = 60e-6, seed: int = 0, **kw
) -> scenes.Texture:
    kw.setdefault("width_m", 0.016)  # length: sized to the slide by slide_spectrum
    return scenes.Texture(kind="random", rms_m=rms_m, corr_length_m=corr_length_m, seed=seed, **kw)


def slide_spectrum(
    texture: scenes.Texture | None = None,
    speed_m_s: float = 0.025,
    force_n: float = 0.5,
    ridges: bool = True,
    duration_s: float = 0.5,
    timestep_s: float = 2e-4,
    site: str = "all",
    settle_s: float = 0.05,
    tip: scenes.Fingertip | None = None,
) -> Spectrum:
    """Slide and return the receptor-stress spectrum of `site` (a receptor
    class, or "all")."""
    if site not in ("all", "SA1", "RA", "PC"):
        raise ValueError(f"site {site!r} is not one of 'all', 'SA1', 'RA', 'PC'")
    tip = tip or scenes.Fingertip(nx=64, pitch_m=1.5e-4, ridges=ridges)
    proto = scenes.Protocol(
        force_n=force_n, speed_m_s=speed_m_s, timestep_s=timestep_s, press_s=0.1
    )
    texture = texture or grating()
    need = 2 * speed_m_s * duration_s + 0.02  # slide + contact patch margin
    if texture.length_m < need:
        texture = dataclasses.replace(texture, length_m=need)
    res = rollout.run_slide(tip, texture, proto, duration_s=duration_s)
    w = res.window(settle_s)
    stress = res.stress[w]
    if site != "all":
        stress = stress[:, res.layout.mask(site)]
    f, p = signals.stress_spectrum(stress, res.dt)
    return Spectrum(f, p, speed_m_s, site, res)


def assert_peak_at(spec: Spectrum, f_hz: float, bins: float = 1.0, rank: int = 0) -> None:
    """The rank-th strongest peak (0: the strongest) lies within `bins` FFT
    bins of f_hz."""
    peaks = spec.peaks(n=max(6, rank + 1))
    assert len(peaks) > rank, f"fewer than {rank + 1} spectral peaks: {peaks}"
    got = peaks[rank]
    assert abs(got - f_hz) <= bins * spec.bin_hz, (
        f"peak #{rank} at {got:.2f} Hz, expected {f_hz:.2f} Hz within {bins} bin(s) of "
        f"{spec.bin_hz:.2f} Hz; peaks: {[round(p, 2) for p in peaks]}"
    )


def assert_power_ratio(
    a: Spectrum, b: Spectrum, f_hz: float, at_least: float, bins: int = 1
) -> None:
    """Power at f_hz (+-bins) of spectrum a is at least `at_least` times b's."""
    pa, pb = a.power_at(f_hz, bins), b.power_at(f_hz, bins)
    assert pa >= at_least * pb, (
        f"power at {f_hz:.2f} Hz: {pa:.3g} vs {pb:.3g} (ratio {pa / max(pb, 1e-300):.3g}, "
        f"needed >= {at_least})"
    )
