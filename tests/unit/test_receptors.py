"""Stage 4: receptor membranes against analytic results."""

import numpy as np
import pytest

from mjtouch import core

SA1 = dict(C=10e-12, R=1.5e9, Vth=30e-3, k0=1.40e-16, k1=1.68e-16, I0=4.94e-12, M=8)
# The analytic LIF rate holds for Wang 2016's SA1 (no adaptation, one
# parameter set); the default `filtered` SA1 adds adaptation and variants.
WANG = {"sa1_model": "wang2016"}


def lif_rate(I, R, C, Vth, refractory):
    """Constant-current LIF rate with reset to 0 and absolute refractory."""
    if I * R <= Vth:
        return 0.0
    return 1.0 / (refractory - R * C * np.log(1 - Vth / (I * R)))


@pytest.mark.parametrize("q_pa", [20e3, 40e3, 80e3, 200e3])
@pytest.mark.parametrize("dt", [1e-4, 2.5e-5, 2e-3])
def test_sa1_constant_stress_rate_matches_analytic(q_pa, dt):
    # Constant stress: heminode 1 (8 Merkel cells) carries the largest current
    # and fires first every cycle; the others reset with it.
    q = np.full(int(round(2.0 / dt)), q_pa)
    spikes, _ = core.receptor_run("SA1", q, dt, WANG)
    T = (q.size - 1) * dt  # the first value primes the receptor at rest
    I = SA1["M"] * SA1["k0"] * q_pa + SA1["I0"]
    expect = lif_rate(I, SA1["R"], SA1["C"], SA1["Vth"], 1e-3)
    # exact integration: the count is the analytic count up to the one
    # partial interval at the end
    assert abs(spikes.sum() - expect * T) <= 1.0
    assert abs(spikes.sum() / T / expect - 1) < 0.01 or expect * T < 100


def test_sa1_silent_at_and_below_rheobase():
    # rheobase: I R = Vth, i.e. q = (Vth / R - I0) / (M k0)
    q_rheo = (SA1["Vth"] / SA1["R"] - SA1["I0"]) / (SA1["M"] * SA1["k0"])
    for q in [0.0, 0.5 * q_rheo, q_rheo]:
        spikes, v = core.receptor_run("SA1", np.full(50000, q), 1e-4, WANG)
        assert spikes.sum() == 0
        assert v.max() <= 1.0


def test_ra_silent_in_hold_fires_on_ramp():
    dt = 1e-4
    t = np.arange(int(0.6 / dt)) * dt
    q = np.clip(t / 0.1, 0, 1) * 5e3  # 0.1 s ramp to 5 kPa, then hold
    spikes, _ = core.receptor_run("RA", q, dt)
    assert spikes[t < 0.1].sum() > 0
    assert spikes[t > 0.15].sum() == 0


def test_spikes_never_exceed_refractory_limit():
    dt = 2e-3
    q = np.full(1000, 1e9)
    for cls in ("SA1", "RA", "PC"):
        spikes, _ = core.receptor_run(cls, q * (np.arange(1000) % 2), dt)
        assert spikes.max() <= dt / 1e-3 + 1


def test_bad_receptor_arguments():
    with pytest.raises(ValueError, match="class"):
        core.receptor_run("XX", np.ones(3), 1e-4)
    with pytest.raises(ValueError, match="`sa1_c`"):
        core.receptor_run("SA1", np.ones(3), 1e-4, {"sa1_c": "-1"})
