"""Afferent tuning and dynamic range against published physiology, on the
receptor stage alone (core.receptor_run driven by stress waveforms).

Published facts checked (human and macaque microneurography):
- SA1 most sensitive at low frequencies, thresholds rising above ~100 Hz
  (Johansson, Landstroem & Lundstroem 1982, Brain Res 244:17; Freeman &
  Johnson 1982, J Physiol 323:21).
- RA (FA I) best frequency 20-80 Hz (Johansson et al. 1982: FA I most
  sensitive at 8-64 Hz; TouchSim's RA fits ~40-80 Hz, Saal et al. 2017).
- PC (FA II) U-shaped, minimum at 150-400 Hz, steep low-frequency flank:
  the 40 Hz threshold >= 10x the 250 Hz one (Johansson et al. 1982;
  Muniak et al. 2007, J Neurosci 27:11687).
- Entrainment (1 spike per cycle) needs well above the absolute threshold:
  > 1.5x for RA and PC (Freeman & Johnson 1982; Muniak et al. 2007; ~5x for
  PC at 250 Hz in TouchSim's models). At 5-20 Hz the cycle (50-200 ms) is
  longer than every time constant of the model (and than TouchSim's
  post-spike current, 38 ms): a noise-free unit then does the same every
  cycle and entrains at its absolute threshold; the membrane noise (on by
  default, TouchSim's level) makes the response probabilistic near threshold.
Thresholds: a sine of stress on q = 0 with a 50 ms onset ramp, counted over
20 cycles after 0.2 s; absolute = at least one spike, entrainment = at least
one spike per cycle; bisection in log amplitude.
"""

import math

import numpy as np
import pytest

from mjtouch import core

DT = 5e-5
UNIFORM = {"population": "uniform"}
# a few receptors of the varied population (streams pick parameter sets)
VARIED_STREAMS = (0, 1, 2, 3, 5, 8)


def sine_spikes(cls, f, amp, cfg, stream=0):
    n = int(round((0.2 + 20 / f) / DT)) + 1
    t = np.arange(n) * DT
    q = amp * np.clip(t / 0.05, 0, 1) * np.sin(2 * np.pi * f * t)
    spikes, _ = core.receptor_run(cls, q, DT, cfg, stream=stream)
    return spikes[t > 0.2].sum()


def threshold(cls, f, cfg, per_cycle, stream=0, lo=1e-3, hi=1e7, iters=22):
    """Smallest amplitude (Pa) with >= per_cycle x 20 spikes (per_cycle 1/20:
    any spike)."""

    def ok(a):
        return sine_spikes(cls, f, a, cfg, stream) >= max(1, round(per_cycle * 20))

    if not ok(hi):
        return math.inf
    for _ in range(iters):  # (1e10)^(2^-22): 0.5% relative
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    return hi


def absolute(cls, f, cfg=UNIFORM, stream=0):
    return threshold(cls, f, cfg, 1 / 20, stream)


def entrainment(cls, f, cfg=UNIFORM, stream=0):
    return threshold(cls, f, cfg, 1, stream)


@pytest.mark.parametrize("stream", [None, *VARIED_STREAMS])
def test_sa1_most_sensitive_below_100hz_thresholds_rise_above(stream):
    cfg = UNIFORM if stream is None else {}
    freqs = [5, 20, 40, 100, 250, 600]
    thr = np.array([absolute("SA1", f, cfg, stream or 0) for f in freqs])
    best = freqs[int(np.argmin(thr))]
    assert best < 100, thr
    # rising from 100 Hz on, and at 250 Hz well above the best (> 2x)
    assert np.all(np.diff(thr[3:]) > 0), thr
    assert thr[4] > 2 * thr.min(), thr


def test_wang2016_sa1_kept_as_published():
    # The named variant keeps Wang's unfiltered |dq/dt| term: its threshold
    # falls with frequency (the behaviour issue 14 measured, 387 Pa at 5 Hz
    # to 4.6 Pa at 600 Hz).
    cfg = {"sa1_model": "wang2016"}
    t5, t600 = absolute("SA1", 5, cfg), absolute("SA1", 600, cfg)
    assert t5 == pytest.approx(387, rel=0.05) and t600 < 6, (t5, t600)


@pytest.mark.parametrize("stream", [None, *VARIED_STREAMS])
def test_ra_best_frequency_20_to_80_hz(stream):
    cfg = UNIFORM if stream is None else {}
    freqs = [5, 10, 20, 40, 80, 150, 300]
    thr = [absolute("RA", f, cfg, stream or 0) for f in freqs]
    assert 20 <= freqs[int(np.argmin(thr))] <= 80, thr


@pytest.mark.parametrize("stream", [None, *VARIED_STREAMS])
def test_pc_u_shaped_minimum_150_to_400_hz(stream):
    cfg = UNIFORM if stream is None else {}
    freqs = [40, 80, 150, 250, 400, 800]
    thr = np.array([absolute("PC", f, cfg, stream or 0) for f in freqs])
    best = int(np.argmin(thr))
    assert 150 <= freqs[best] <= 400, thr
    assert np.all(np.diff(thr[: best + 1]) < 0) and np.all(np.diff(thr[best:]) > 0), thr
    assert thr[0] >= 10 * thr[freqs.index(250)], thr


@pytest.mark.parametrize("cls, f", [("RA", 40), ("PC", 250)])
@pytest.mark.parametrize("stream", [None, *VARIED_STREAMS])
def test_entrainment_needs_over_1_5x_absolute_threshold(cls, f, stream):
    cfg = UNIFORM if stream is None else {}
    a, e = absolute(cls, f, cfg, stream or 0), entrainment(cls, f, cfg, stream or 0)
    assert e > 1.5 * a, (a, e)
    # and between the two the unit skips cycles (spikes but fewer than cycles)
    mid = sine_spikes(cls, f, math.sqrt(a * e), cfg, stream or 0)
    assert 1 <= mid < 20, mid


@pytest.mark.parametrize("f", [5, 10, 20])
def test_ra_entrainment_over_1_5x_absolute_at_5_to_20_hz(f):
    # The median unit, and the median over the varied units, need > 1.5x
    # the absolute threshold to fire every cycle; with noise the ratio of a
    # single unit is itself a random draw (one noise path per amplitude), so
    # each varied unit is held to > 1.2x.
    a, e = absolute("RA", f), entrainment("RA", f)
    assert e > 1.5 * a, (a, e)
    ratios = np.array(
        [entrainment("RA", f, {}, s) / absolute("RA", f, {}, s) for s in VARIED_STREAMS]
    )
    assert np.median(ratios) > 1.5 and ratios.min() > 1.2, ratios


def test_calibration_absolute_thresholds():
    # receptors.h: RA gain calibrated to an absolute threshold of 100 Pa at
    # 40 Hz, PC to 0.7 Pa at 250 Hz (median unit, default noise, stream 0);
    # 3% for the bisection and the calibration's quoted precision.
    assert absolute("RA", 40) == pytest.approx(100.0, rel=0.03)
    assert absolute("PC", 250) == pytest.approx(0.7, rel=0.03)


# --- ramp-and-hold stress ------------------------------------------------------------------


def trapezoid(t, peak, t_on=0.1, ramp=0.1, hold=0.5):
    return peak * np.interp(
        t,
        [0, t_on, t_on + ramp, t_on + ramp + hold, t_on + 2 * ramp + hold, 1e9],
        [0, 0, 1, 1, 0, 0],
    )


def windows(t, t_on=0.1, ramp=0.1, hold=0.5):
    return {
        "up": (t > t_on) & (t <= t_on + ramp),
        "hold": (t > t_on + ramp + 0.1) & (t <= t_on + ramp + hold),
        "down": (t > t_on + ramp + hold) & (t <= t_on + 2 * ramp + hold),
        "after": t > t_on + 2 * ramp + hold + 0.1,
    }


def test_sa1_sustained_and_roughly_linear_in_stress():
    # Human SA I static discharge grows about linearly with indentation
    # (Knibestoel 1975, J Physiol 245:63: power exponents near 1) and lasts
    # the whole hold; rates stay in the tens of impulses/s, under ~150 Hz.
    dt = 1e-4
    t = np.arange(int(0.9 / dt)) * dt
    w = windows(t)
    peaks = np.array([20e3, 30e3, 40e3, 50e3, 60e3])  # 1-2.5 mm of flat press (README)
    rates, early, late = [], [], []
    for p in peaks:
        sp, _ = core.receptor_run("SA1", trapezoid(t, p), dt, UNIFORM)
        h = sp[w["hold"]]
        rates.append(h.sum() / (w["hold"].sum() * dt))
        early.append(h[: h.size // 2].sum())
        late.append(h[h.size // 2 :].sum())
        assert sp[w["after"]].sum() == 0
    rates = np.array(rates)
    assert np.all(np.diff(rates) > 0) and 5 < rates[0] and rates[-1] < 150, rates
    # sustained: the second half of the hold keeps >= 80% of the first's spikes
    assert np.all(np.array(late) >= 0.8 * np.array(early)), (early, late)
    # roughly linear above threshold: a straight line explains >= 97% of the
    # variance of the rates over this range
    r = np.corrcoef(peaks, rates)[0, 1]
    assert r**2 >= 0.97, (rates, r)


def test_sa1_pauses_on_release():
    # unloading inhibits (TouchSim's SA1 fits: negative gain on falling
    # velocity; Knibestoel 1975: SA I silent or slowed on release)
    dt = 1e-4
    t = np.arange(int(0.9 / dt)) * dt
    w = windows(t)
    sp, _ = core.receptor_run("SA1", trapezoid(t, 40e3), dt, UNIFORM)
    hold_rate = sp[w["hold"]].sum() / (w["hold"].sum() * dt)
    down_rate = sp[w["down"]].sum() / (w["down"].sum() * dt)
    assert down_rate < 0.5 * hold_rate, (down_rate, hold_rate)


@pytest.mark.parametrize("peak", [3e3, 20e3, 50e3])
def test_ra_only_on_ramps_pc_only_on_transients(peak):
    dt = 1e-4
    t = np.arange(int(0.9 / dt)) * dt
    w = windows(t)
    for cls in ("RA", "PC"):
        sp, _ = core.receptor_run(cls, trapezoid(t, peak), dt, UNIFORM)
        assert sp[w["hold"]].sum() == 0 and sp[w["after"]].sum() == 0, cls
        assert sp[w["up"]].sum() > 0 and sp[w["down"]].sum() > 0, cls
    # RA ramp rates stay physiological, below ~200 impulses/s even for
    # 0.5 MPa/s (Knibestoel 1973, J Physiol 232:427: FA I dynamic responses;
    # TouchSim saturates its input current, Saal et al. 2017)
    sp, _ = core.receptor_run("RA", trapezoid(t, peak), dt, UNIFORM)
    assert sp[w["up"]].sum() / 0.1 < 200


def test_population_variants_differ_and_are_deterministic():
    dt = 1e-4
    t = np.arange(int(0.9 / dt)) * dt
    q = trapezoid(t, 40e3)
    counts = {
        s: core.receptor_run("SA1", q, dt, {"seed": "3"}, stream=s)[0].sum() for s in range(12)
    }
    assert len(set(counts.values())) >= 3  # several parameter sets in use
    for s in range(12):  # a pure function of (seed, stream)
        assert core.receptor_run("SA1", q, dt, {"seed": "3"}, stream=s)[0].sum() == counts[s]
    # `uniform`: every receptor is the median unit (noise off: each stream
    # draws its own noise)
    uni = {
        core.receptor_run(
            "SA1", q, dt, {"seed": "3", "population": "uniform", "noise": "0 0 0"}, stream=s
        )[0].sum()
        for s in range(12)
    }
    assert len(uni) == 1


def test_noise_free_ra_entrains_at_its_absolute_threshold_at_5_hz():
    # Why the default has noise: without it a 5 Hz cycle (200 ms) outlasts
    # every time constant, each cycle repeats the last, and the first spike
    # per cycle comes at the absolute threshold (1.0x, issue 14's measurement).
    cfg = {"population": "uniform", "noise": "0 0 0"}
    a, e = absolute("RA", 5, cfg), entrainment("RA", 5, cfg)
    assert e == pytest.approx(a, rel=0.02), (a, e)


# --- SA1 under a 1 mm flat pin (full plugin) -----------------------------------------------

# Published SA1 static responses under a flat probe (hold, finger still):
# - threshold: human SA I units respond to indentations of tens of um
#   (Johansson & Vallbo 1979, J Physiol 286:283: SA I thresholds; Knibestoel
#   1975, J Physiol 245:63): the model must fire by 0.1 mm;
# - rate roughly linear in indentation (Knibestoel 1975: power exponents near
#   1 for the static phase; Mountcastle et al. 1966): R^2 >= 0.97 of a line
#   over 0.1-1.5 mm;
# - rates: TouchSim's four SA1 fits (Saal et al. 2017, hsaal/touchsim
#   constants.affparamsSA, its pin mechanics, noise-free; reproduced by
#   plugin/README.md's script) give 35-61 Hz at 1.0 mm and 50-89 Hz at 1.5 mm
#   under a 1 mm diameter pin; 0.8x-1.2x of those bounds for our skin.
PIN_DEPTHS_MM = (0.02, 0.1, 0.4, 0.7, 1.0, 1.5)
SA1_RATE_1MM_HZ = (0.8 * 35, 1.2 * 61)
SA1_RATE_1P5MM_HZ = (0.8 * 50, 1.2 * 89)


@pytest.fixture(scope="module")
def pin_sa1_rates():
    from mjtouch.experiments import stimuli

    scene = stimuli.ProbeScene(
        stimuli.Probe("pin", radius_m=0.5e-3), preindent_m=0.0, settle_s=0.0, timestep_s=1e-4
    )
    hold_s, ramp_s = 0.3, 0.05
    res = scene.run(
        [
            stimuli.ramp_and_hold(d * 1e-3, ramp_s=ramp_s, hold_s=hold_s, rest_s=0.0)
            for d in PIN_DEPTHS_MM
        ],
        threads=2,
    )
    out = []
    for r in res:
        u = r.centred_units()["SA1"]
        hold = slice(int(round((ramp_s + 0.1) / r.dt_s)), int(round((ramp_s + hold_s) / r.dt_s)))
        out.append(r.spikes[hold, u].sum() / ((hold.stop - hold.start) * r.dt_s))
    return np.array(out)


def test_sa1_pin_threshold_and_linear_rate_intensity(pin_sa1_rates):
    d, rate = np.array(PIN_DEPTHS_MM), pin_sa1_rates
    assert rate[d == 0.1][0] >= 5.0, rate  # fires by 0.1 mm (>= 1 spike per 0.2 s)
    assert rate[d == 0.02][0] < rate[d == 0.1][0], rate
    m = d >= 0.1
    assert np.all(np.diff(rate[m]) > 0), rate
    r2 = np.corrcoef(d[m], rate[m])[0, 1] ** 2
    assert r2 >= 0.97, (rate, r2)
    assert SA1_RATE_1MM_HZ[0] <= rate[d == 1.0][0] <= SA1_RATE_1MM_HZ[1], rate
    assert SA1_RATE_1P5MM_HZ[0] <= rate[d == 1.5][0] <= SA1_RATE_1P5MM_HZ[1], rate


@pytest.mark.parametrize("cls", ["SA1", "RA", "PC"])
def test_noisy_membranes_stay_below_threshold(cls):
    # With the default noise and adaptation, 2e5 steps of 1 ms of a
    # modulated load: a membrane reaching threshold fires, so the voltage
    # output (membrane over threshold at each step's end) stays below 1
    # (SA1 ended a step 3% over threshold once before membrane.cc's
    # fallback).
    dt, n = 1e-3, 200_000
    t = np.arange(n) * dt
    q = 5e3 * (1 + 0.3 * np.sin(2 * np.pi * 10 * t))
    spikes, volt = core.receptor_run(cls, q, dt)
    assert volt.max() < 1.0 and spikes.sum() > 0, (volt.max(), spikes.sum())
