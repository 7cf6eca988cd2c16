"""Afferent responses against physiology (issue 5, "Must show").

Receptor stage alone (``core.receptor_run``) and the full plugin (MuJoCo
rollouts of a fingertip pressed on a flat plate: 48 x 48 taxels at 0.15 mm,
no ridges, default layered skin and receptor parameters). Every expected value
is computed: from the LIF formula, from a receptor run on the plugin's own
stress, or from a law stated at the assertion.
"""

import dataclasses
import math

import mujoco
import mujoco.rollout
import numpy as np
import pytest
from conftest import fast_tip

from mjtouch import _core, analysis, core
from mjtouch.experiments import rollout, stimuli
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

FULLPHYSICS = mujoco.mjtState.mjSTATE_FULLPHYSICS


def tip(skin=None) -> scenes.Fingertip:
    return scenes.Fingertip(nx=48, pitch_m=1.5e-4, ridges=False, skin=dict(skin or {}))


def flat_scene(skin=None, timestep_s=1e-4, mocap_plate=False) -> mujoco.MjModel:
    texture, protocol = scenes.Texture(kind="flat"), scenes.Protocol(timestep_s=timestep_s)
    if not mocap_plate:
        return scenes.build_model(tip(skin), texture, protocol)
    # the vibrating plate of mjtouch.stimuli (a mocap body; adds the force output)
    return stimuli.vibrating_plate_spec(tip(skin), timestep_s).compile()


def initial_state(m, d=None):
    d = d or mujoco.MjData(m)
    s = np.empty(mujoco.mj_stateSize(m, FULLPHYSICS))
    mujoco.mj_getState(m, d, s, FULLPHYSICS)
    return s


# --- rates do not depend on dt (receptor stage) -----------------------------------------


def ramp_and_hold(t, peak_pa, ramp_s, hold_s, period_s, t_on_s=0.02):
    """Trapezoids repeated every period_s: rest, ramp up, hold, ramp down."""
    knots = [0, t_on_s, t_on_s + ramp_s, t_on_s + ramp_s + hold_s, t_on_s + 2 * ramp_s + hold_s]
    return peak_pa * np.interp(np.mod(t, period_s), knots + [1e9], [0, 0, 1, 1, 0, 0])


def onset_sine(t, mean_pa, amp_pa, freq_hz):
    """A sine whose amplitude grows linearly over its first 3 cycles."""
    return mean_pa + amp_pa * np.clip(t * freq_hz / 3, 0, 1) * np.sin(2 * np.pi * freq_hz * t)


# Stimuli per class; sine amplitudes relative to the class's thresholds
# (tests/unit/test_afferent_tuning.py): above the 1:1 threshold (locked) and
# between the absolute and 1:1 thresholds (cycles skipped).
DT_STIMULI = {
    # SA1: >= 100 spikes in 2 s (noise-free, median set)
    ("SA1", "ramp"): lambda t: ramp_and_hold(t, 300e3, 0.1, 0.7, 1.0),
    ("SA1", "sine"): lambda t: onset_sine(t, 200e3, 80e3, 5.0),
    # RA, PC ramps: >= 100 spikes in 2 s (a few per ramp: the RA's gain control
    # by its sustained drive, the PC's 2.4 ms refractory period)
    ("RA", "ramp"): lambda t: ramp_and_hold(t, 60e3, 0.03, 0.02, 0.1),
    ("RA", "sine"): lambda t: onset_sine(t, 0.0, 3100.0, 40.0),
    # 7.6x RA's noise-free absolute threshold at 150 Hz (522 Pa; 1:1 is never
    # reached there), the skipping regime
    ("RA", "sine-skipping"): lambda t: onset_sine(t, 0.0, 4000.0, 150.0),
    ("PC", "ramp"): lambda t: ramp_and_hold(t, 5e3, 0.02, 0.03, 0.1),
    ("PC", "sine"): lambda t: onset_sine(t, 0.0, 10.0, 100.0),
    # PC skipping at 300 Hz (a spike every ~5 cycles): at 400 Hz the cycle
    # (2.5 ms) is within a step of the PC's 2.4 ms refractory period, a
    # near-tie the two samplings of the stimulus break differently
    ("PC", "sine-skipping"): lambda t: onset_sine(t, 0.0, 1.5, 300.0),
}


@pytest.mark.parametrize("cls, kind", list(DT_STIMULI), ids=[f"{c}-{k}" for c, k in DT_STIMULI])
def test_rates_at_two_timesteps_agree(cls, kind):
    # The same stimulus function sampled at dt = 1e-4 and 2.5e-5 s over 2 s.
    stim = DT_STIMULI[(cls, kind)]
    trains = []
    for dt in (1e-4, 2.5e-5):
        t = np.arange(int(round(2.0 / dt)) + 1) * dt
        # noise off: the integrator's exactness (noise draws one value per step)
        spikes, _ = core.receptor_run(cls, stim(t), dt, {"noise": "0 0 0"})
        trains.append(analysis.spike_times(spikes, dt))
    n1, n2 = trains[0].size, trains[1].size
    assert n1 >= 100  # enough spikes that 2% is a resolved difference
    assert abs(n1 - n2) <= 0.02 * n1
    # Stronger: with equal counts, spike by spike the times agree to the two
    # steps' quantisation (dt1 + dt2) / 2, plus 1 us for the piecewise-linear
    # sampling of the stimulus differing between the two steps.
    assert n1 == n2
    assert np.max(np.abs(trains[0] - trains[1])) <= (1e-4 + 2.5e-5) / 2 + 1e-6


# --- ramp-and-hold presses in the full plugin -------------------------------------------


def _default(name):
    """An attribute's documented default (the attribute table, attributes.cc)."""
    for line in _core.attribute_table_markdown().splitlines():
        cells = [c.strip() for c in line.split("|")]
        if len(cells) > 2 and cells[1] == f"`{name}`":
            return float(cells[2])
    raise KeyError(name)


RA_GAIN_S_PER_PA = _default("ra_gain")
RA_MIN_VARIANT_GAIN = 0.75  # receptors.cc kVariants: the least sensitive RA set
RAMP_DT = 2e-4
T_ON, RAMP, HOLD, REST = 0.1, 0.1, 0.3, 0.15  # s
PRELOAD_N = 0.05  # keeps the pad on the plate between presses
FORCES_N = (0.5, 1.0, 2.0)
SETTLE_S = 0.05  # the contact settles within 50 ms after a ramp (MuJoCo contact, 10 ms)


@dataclasses.dataclass
class RampRuns:
    t: np.ndarray  # (nstep,) evaluation time of each row, s
    spikes: np.ndarray  # (nforce, nstep, nrec)
    stress: np.ndarray  # (nforce, nstep, nrec), Pa
    layout: SkinLayout

    def window(self, a, b):
        return (self.t > a) & (self.t <= b)

    @property
    def hold(self):
        return self.window(T_ON + RAMP + SETTLE_S, T_ON + RAMP + HOLD)

    @property
    def before(self):  # after the touch-down transient of the preload
        return self.window(0.06, T_ON)

    @property
    def rest_after(self):
        return self.window(T_ON + 2 * RAMP + HOLD + 0.1, self.t[-1])


@pytest.fixture(scope="module")
def ramp_runs():
    """Press with a force ramp (0.1 s) to each of FORCES_N, hold 0.3 s, ramp
    back to the preload; one batch, two threads."""
    # noise off: per-receptor monotonicity and the receptor_run identity are
    # properties of the deterministic model (with noise an idle receptor's
    # catch-up draws other noise than receptor_run's steps; the noisy
    # identity is test_noisy_plugin_spikes_equal_receptor_run_with_its_stream)
    m = flat_scene({"outputs": "spikes stress", "noise": "0 0 0"}, timestep_s=RAMP_DT)
    layout = SkinLayout.from_model(m)
    n = int(round((T_ON + 2 * RAMP + HOLD + REST) / RAMP_DT))
    t = np.arange(n) * RAMP_DT  # row k is evaluated at k dt, before step k
    knots = [0, T_ON, T_ON + RAMP, T_ON + RAMP + HOLD, T_ON + 2 * RAMP + HOLD, 1e9]
    ctrl = np.zeros((len(FORCES_N), n, 2))
    for i, f in enumerate(FORCES_N):
        ctrl[i, :, 1] = -np.interp(t, knots, [PRELOAD_N, PRELOAD_N, f, f, PRELOAD_N, PRELOAD_N])
    s0 = np.repeat(initial_state(m)[None], len(FORCES_N), axis=0)
    _, sd = mujoco.rollout.rollout(m, [mujoco.MjData(m) for _ in range(2)], s0, ctrl)
    return RampRuns(t, layout.block(sd, "spikes"), layout.block(sd, "stress"), layout)


def test_sa1_fires_through_hold_rate_rising_with_force(ramp_runs):
    r = ramp_runs
    sa1 = r.layout.mask("SA1")
    hold = r.hold
    duration = hold.sum() * RAMP_DT
    counts = r.spikes[:, hold][:, :, sa1].sum(axis=1)  # (nforce, nSA1)
    # The plugin's SA1 spikes are its receptor stage on the stress each
    # receptor reports (receptor_run with the receptor's stream: its
    # population variant), over the whole run.
    idx = np.nonzero(sa1)[0]
    for i in range(len(FORCES_N)):
        for r_ in idx[::3]:
            got, _ = core.receptor_run(
                "SA1", r.stress[i][:, r_], RAMP_DT, {"noise": "0 0 0"}, stream=int(r_)
            )
            # the plugin integrates over exactly the timestep (not time -
            # last time, which differs by round-off), as receptor_run does
            assert np.array_equal(got, r.spikes[i][:, r_]), (i, r_)
    # SA1 fires through the hold (the receptors under the contact's centre)
    assert np.all(counts.max(axis=1) / duration > 10.0)
    # Human SA I static rates at mm indentations: tens of impulses/s, rarely
    # above ~100-150 (Knibestoel 1975, J Physiol 245:63); this press
    # indents 1-2.5 mm (force block)
    assert np.all(counts.max(axis=1) / duration < 150.0), counts.max(axis=1) / duration
    # monotone in force: the population rate rises strictly and no receptor
    # slows when the force rises
    pop = counts.sum(axis=1)
    assert np.all(np.diff(pop) > 0), pop
    assert np.all(np.diff(counts, axis=0) >= 0)
    # and faster during the ramp than in the hold (the dynamic term k1 r)
    ramp = r.window(T_ON, T_ON + RAMP)
    assert np.all(r.spikes[:, ramp][:, :, sa1].sum(axis=(1, 2)) > pop / duration * RAMP)


def test_ra_fires_on_ramps_not_in_hold(ramp_runs):
    r = ramp_runs
    ra = r.layout.mask("RA")
    up = r.window(T_ON, T_ON + RAMP)
    down = r.window(T_ON + RAMP + HOLD, T_ON + 2 * RAMP + HOLD)
    for i in range(len(FORCES_N)):
        sp = r.spikes[i][:, ra]
        q = r.stress[i][:, ra]
        # A steady stress rate v drives the RA membrane to gain v (threshold
        # 1): it fires on ramps faster than 1 / gain. Every RA whose stress
        # rises on average at twice that during the ramp fires on both ramps.
        v_min = 1 / RA_GAIN_S_PER_PA
        loaded = (q[r.hold].mean(axis=0) - q[r.before].mean(axis=0)) > 2 * v_min * RAMP
        assert loaded.sum() >= 10
        assert np.all(sp[up][:, loaded].sum(axis=0) > 0)
        assert np.all(sp[down][:, loaded].sum(axis=0) > 0)
        # silent in the steady hold and at rest, every receptor
        assert sp[r.hold].sum() == 0
        assert sp[r.before].sum() == 0 and sp[r.rest_after].sum() == 0


def test_pc_fires_on_on_and_off_transients_only(ramp_runs):
    r = ramp_runs
    pc = r.layout.mask("PC")
    onset = r.window(T_ON - 0.005, T_ON + RAMP + SETTLE_S)
    offset = r.window(T_ON + RAMP + HOLD - 0.005, T_ON + 2 * RAMP + HOLD + 0.1)
    for i in range(len(FORCES_N)):
        sp = r.spikes[i][:, pc]
        assert sp[onset].sum() > 0 and sp[offset].sum() > 0
        assert sp[r.hold].sum() == 0
        assert sp[r.before].sum() == 0 and sp[r.rest_after].sum() == 0
        # after the preload's touch-down, all its spikes fall in the on and
        # off windows
        later = sp[r.t > 0.06]
        assert sp[onset].sum() + sp[offset].sum() == later.sum()


# --- vibration: tuning curves from the plugin -------------------------------------------

VIB_DT = 1e-4
VIB_FREQS_HZ = np.array([10.0, 20, 40, 80, 150, 250, 400, 600, 800])
PRESS_N = 0.5
# 0.6 s: the pad lands (0.02 s) and settles, and the adaptation current of
# the landing's spikes (20 ms) decays to < 1e-12, so receptor_run from rest
# reproduces the plugin's receptors
SETTLE_STEPS = 6000
# Reference amplitudes: plate displacement (m) and fingertip force (N).
VIB_DRIVES = {"plate": 1e-6, "finger": 2e-3}
# noise off as ramp_runs; elastic solved to 1e-7 of the load (linearity at
# 1 um needs it: stimuli.STIMULUS_TOLERANCE)
# One contact grid, as the stimuli's probes: a flat contact driven along
# its normal moves no edge across the grid, and the cycle would stop each
# grid's solve at N x the 1e-7 tolerance.
VIB_SKIN = {
    "outputs": "spikes stress",
    "classes": "RA PC",
    "noise": "0 0 0",
    "tolerance": "1e-7",
    "grid_cycle": "1",
}


def vib_rows(f):
    """Rows of a vibration run at f and its analysis window: the last m whole
    cycles (each a whole number of steps) within the run's second half."""
    n = int(round(max(0.1, 4 / f) / VIB_DT))
    period_steps = 1 / (f * VIB_DT)
    step = next(k for k in range(1, 100) if abs(k * period_steps - round(k * period_steps)) < 1e-9)
    m = step * int((n // 2) // round(step * period_steps))
    return n, slice(n - int(round(m * period_steps)), n), m


def vib_controls(kind, f, amp, n):
    t = np.arange(n) * VIB_DT
    wave = amp * np.sin(2 * np.pi * f * t)
    if kind == "plate":  # ctrl (slide, press) then mocap_pos (x, y, z)
        c = np.zeros((n, 5))
        c[:, 4] = wave
    else:  # the press force oscillates about PRESS_N
        c = np.zeros((n, 2))
        c[:, 1] = -wave
    c[:, 1] -= PRESS_N
    return c


def vib_spec(kind):
    spec = mujoco.mjtState.mjSTATE_CTRL
    return spec | mujoco.mjtState.mjSTATE_MOCAP_POS if kind == "plate" else spec


@dataclasses.dataclass
class Sweep:
    kind: str
    amp_ref: float
    model: mujoco.MjModel
    state: np.ndarray  # settled, pressed state
    layout: SkinLayout
    base: dict  # f -> (n, nrec) stress without vibration
    delta: dict  # f -> (n, nrec) stress change at amp_ref
    delta2: dict  # f -> at 2 amp_ref
    spikes: dict  # f -> (n, nrec) plugin spikes at amp_ref
    thresholds: dict  # class -> (nfreq, nunit) 1:1 (entrainment) threshold per unit
    absolute: dict  # class -> (nfreq, nunit) absolute threshold (any spike) per unit
    units: dict  # class -> receptor indices evaluated


def locked_scale(cls, base, delta, f, stream, lo=1e-4, hi=1e5, iters=30, per_cycle=True):
    """Smallest s with >= 1 spike per cycle (per_cycle; else >= 1 spike) in
    the window when the receptor sees base + s delta (core.receptor_run, the
    plugin's receptor stage, with the receptor's stream: its variant)."""
    n, win, m = vib_rows(f)

    def locked(s):
        spikes, _ = core.receptor_run(cls, base + s * delta, VIB_DT, VIB_SKIN, stream=stream)
        return spikes[win].sum() >= (m if per_cycle else 1)

    if not locked(hi):
        return math.inf
    assert not locked(lo)
    for _ in range(iters):  # (1e9)^(2^-30): 2e-8 relative
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if locked(mid) else (mid, hi)
    return hi


@pytest.fixture(scope="module", params=list(VIB_DRIVES))
def sweep(request):
    """Vibration about a 0.5 N press, 10-800 Hz, of the plate (a mocap body,
    displacement in m) or of the fingertip (its press force, N).

    Method: one rollout per frequency at the reference amplitude a and one at
    2a, from the same settled state, and one without vibration. The receptor
    stress is linear in the amplitude (checked:
    test_vibration_stress_is_linear_in_amplitude), so at amplitude s a the
    plugin's receptors see base + s delta, delta = q(a) - q(0). The 1:1
    entrainment threshold (>= 1 spike per cycle over the window's whole
    cycles) is found by bisection on s,
    driving core.receptor_run with the plugin's receptor parameters. The
    plugin's own spikes at a check that receptor_run is its receptor stage
    (test_receptor_run_reproduces_plugin_spikes), and rollouts at 0.9x and
    1.25x the threshold check the threshold itself
    (test_pc_phase_locks_one_to_one_at_best_frequency)."""
    kind, amp = request.param, VIB_DRIVES[request.param]
    m = flat_scene(VIB_SKIN, timestep_s=VIB_DT, mocap_plate=kind == "plate")
    layout = SkinLayout.from_model(m)
    d = mujoco.MjData(m)
    d.ctrl[:] = [0.0, -PRESS_N]
    for _ in range(SETTLE_STEPS):
        mujoco.mj_step(m, d)
    s0 = initial_state(m, d)
    datas = [mujoco.MjData(m) for _ in range(2)]
    spec = vib_spec(kind)
    nmax = max(vib_rows(f)[0] for f in VIB_FREQS_HZ)
    _, sd0 = mujoco.rollout.rollout(
        m, datas, s0[None], vib_controls(kind, 1.0, 0.0, nmax)[None], control_spec=spec
    )
    q0 = layout.block(sd0[0], "stress")
    base, delta, delta2, spikes = {}, {}, {}, {}
    for f in VIB_FREQS_HZ:
        n = vib_rows(f)[0]
        ctrl = np.stack([vib_controls(kind, f, amp, n), vib_controls(kind, f, 2 * amp, n)])
        _, sd = mujoco.rollout.rollout(
            m, datas, np.repeat(s0[None], 2, axis=0), ctrl, control_spec=spec
        )
        q = layout.block(sd, "stress")
        base[f], delta[f], delta2[f] = q0[:n], q[0] - q0[:n], q[1] - q0[:n]
        spikes[f] = layout.block(sd[0], "spikes")
    thresholds, absolute, units = {}, {}, {}
    for cls in ("RA", "PC"):
        idx = np.nonzero(layout.mask(cls))[0]
        # the 4 units most strongly driven at 250 Hz (the drive's spatial
        # pattern does not change with f): the class's most sensitive ones
        resp = np.abs(delta[250.0][:, idx]).max(axis=0)
        units[cls] = idx[np.argsort(resp)[::-1][:4]]
        for out, per_cycle in ((thresholds, True), (absolute, False)):
            out[cls] = np.array(
                [
                    [
                        locked_scale(
                            cls, base[f][:, r], delta[f][:, r], f, int(r), per_cycle=per_cycle
                        )
                        * amp
                        for r in units[cls]
                    ]
                    for f in VIB_FREQS_HZ
                ]
            )
    return Sweep(kind, amp, m, s0, layout, base, delta, delta2, spikes, thresholds, absolute, units)


def test_vibration_stress_is_linear_in_amplitude(sweep):
    for f in VIB_FREQS_HZ:
        d1, d2 = sweep.delta[f], sweep.delta2[f]
        r = np.abs(d2).max(axis=0) > 0
        # q(2a) - q(0) = 2 (q(a) - q(0)): the amplitude (1 um, 2 mN) is < 1e-3
        # of the static indentation / load, so the quadratic term is < 1e-3 of
        # the linear one; 1% adds margin for float32 pressure round-off
        err = np.abs(d2[:, r] - 2 * d1[:, r]).max(axis=0) / np.abs(d2[:, r]).max(axis=0)
        assert err.max() < 0.01, (f, err.max())


def test_receptor_run_reproduces_plugin_spikes(sweep):
    # receptor_run on a receptor's stress column (stream = its index) gives
    # the plugin's spike counts in the analysis window, wherever it fires.
    fired = 0
    for f in VIB_FREQS_HZ:
        _, win, _ = vib_rows(f)
        for cls in ("RA", "PC"):
            for r in sweep.units[cls]:
                q = sweep.base[f][:, r] + sweep.delta[f][:, r]
                spikes, _ = core.receptor_run(cls, q, VIB_DT, VIB_SKIN, stream=int(r))
                assert spikes[win].sum() == sweep.spikes[f][win, r].sum(), (f, cls, r)
                fired += spikes[win].sum() > 0
    assert fired >= 10  # the comparison covered firing receptors


def test_pc_threshold_curve_is_u_shaped(sweep):
    # Absolute thresholds (any spike), as tuning curves are published
    # (Johansson et al. 1982): every unit U-shaped with its minimum at
    # 150-400 Hz, the 40 Hz threshold >= 10x the 250 Hz one.
    i40, i250 = list(VIB_FREQS_HZ).index(40.0), list(VIB_FREQS_HZ).index(250.0)
    for u in range(sweep.absolute["PC"].shape[1]):
        curve = sweep.absolute["PC"][:, u]
        best = int(np.argmin(curve))
        assert 150 <= VIB_FREQS_HZ[best] <= 400, (VIB_FREQS_HZ[best], curve)
        assert np.all(np.diff(curve[: best + 1]) < 0), curve
        assert np.all(np.diff(curve[best:]) > 0), curve
        assert curve[i40] >= 10 * curve[i250], (curve[i40], curve[i250])


def test_ra_best_frequency_is_below_pcs(sweep):
    ra = sweep.absolute["RA"].min(axis=1)
    pc = sweep.absolute["PC"].min(axis=1)
    assert np.all(np.isfinite(ra[:5]))
    f_ra, f_pc = VIB_FREQS_HZ[np.argmin(ra)], VIB_FREQS_HZ[np.argmin(pc)]
    # RA: best frequency 20-80 Hz (Johansson et al. 1982)
    assert 20 <= f_ra <= 80 and f_ra < f_pc, (f_ra, f_pc)


def test_entrainment_needs_over_1_5x_absolute_threshold(sweep):
    # Freeman & Johnson 1982, Muniak et al. 2007: 1:1 entrainment needs
    # well above the absolute threshold (RA at 40 Hz, PC at 250 Hz)
    for cls, f in (("RA", 40.0), ("PC", 250.0)):
        i = list(VIB_FREQS_HZ).index(f)
        ratio = sweep.thresholds[cls][i] / sweep.absolute[cls][i]
        assert np.all(ratio > 1.5), (cls, ratio)


def test_pc_phase_locks_one_to_one_at_best_frequency(sweep):
    # Full plugin rollouts at the PC's best frequency, at 0.9x and 1.25x the
    # most sensitive unit's threshold from the bisection.
    # best frequency: the minimum of the absolute thresholds (the tuning
    # curve); there, the unit with the lowest entrainment threshold
    fi = int(np.argmin(sweep.absolute["PC"].min(axis=1)))
    ui = int(np.argmin(sweep.thresholds["PC"][fi]))
    f, unit, thr = VIB_FREQS_HZ[fi], sweep.units["PC"][ui], sweep.thresholds["PC"][fi, ui]
    n, win, m = vib_rows(f)
    ctrl = np.stack([vib_controls(sweep.kind, f, s * thr, n) for s in (0.9, 1.25)])
    _, sd = mujoco.rollout.rollout(
        sweep.model,
        mujoco.MjData(sweep.model),
        np.repeat(sweep.state[None], 2, axis=0),
        ctrl,
        control_spec=vib_spec(sweep.kind),
    )
    below, above = sweep.layout.block(sd, "spikes")[:, :, unit]
    assert below[win].sum() < m  # under threshold: fewer spikes than cycles
    vs = analysis.vector_strength_counts(above[win], VIB_DT, f)
    # Locked to one phase, spike times are known to +-dt/2: vs >= cos(pi f dt)
    assert vs.vs >= math.cos(math.pi * f * VIB_DT), vs
    assert vs.p_value < 1e-6
    # exactly one spike in every cycle, cycles cut half a period from the
    # spikes' mean phase
    t0 = (win.start) * VIB_DT
    origin = t0 + (vs.phase_rad / (2 * np.pi) + 0.5) / f
    per_cycle = analysis.spikes_per_cycle(above[win], VIB_DT, f, t0_s=t0, origin_s=origin)
    assert per_cycle.size >= m - 1 and np.all(per_cycle == 1), per_cycle


# --- noise and determinism ---------------------------------------------------------------

NOISE_SKIN = {"outputs": "spikes stress", "noise": "0.3 0.3 0.3", "noise_tau": "2e-3"}


def noise_model(**extra):
    skin = dict(NOISE_SKIN, **extra)
    return flat_scene(skin, timestep_s=2e-4), skin


def press_controls(n, dt):
    t = np.arange(n) * dt
    c = np.zeros((n, 2))
    c[:, 1] = -np.interp(t, [0, 0.05, 0.1, 1e9], [0.05, 0.05, 1.0, 1.0])
    return c


def run_serial(m, d, ctrl):
    out = np.empty((len(ctrl), m.nsensordata))
    for k, c in enumerate(ctrl):
        d.ctrl[:] = c
        mujoco.mj_step(m, d)
        out[k] = d.sensordata
    return out


def test_noise_same_seed_is_bit_identical_across_copy_reset_and_threads():
    m, _ = noise_model(seed="7")
    layout = SkinLayout.from_model(m)
    ctrl = press_controls(1000, 2e-4)
    a = run_serial(m, mujoco.MjData(m), ctrl)
    b = run_serial(m, mujoco.MjData(m), ctrl)
    assert np.array_equal(a, b)
    spikes = layout.block(a, "spikes")
    assert spikes.sum() > 100  # noise drives spiking to compare
    # mj_copyData halfway continues identically
    d = mujoco.MjData(m)
    first = run_serial(m, d, ctrl[:500])
    d2 = mujoco.MjData(m)
    mujoco.mj_copyData(d2, m, d)
    assert np.array_equal(run_serial(m, d, ctrl[500:]), run_serial(m, d2, ctrl[500:]))
    assert np.array_equal(first, a[:500])
    # mj_resetData repeats the run from the start
    mujoco.mj_resetData(m, d)
    assert np.array_equal(run_serial(m, d, ctrl), a)
    # 1 and 2 threads of mujoco.rollout, 3 copies of the run
    s0 = np.repeat(initial_state(m)[None], 3, axis=0)
    _, one = mujoco.rollout.rollout(m, mujoco.MjData(m), s0, ctrl[None])
    _, two = mujoco.rollout.rollout(m, [mujoco.MjData(m), mujoco.MjData(m)], s0, ctrl[None])
    assert np.array_equal(one, two)
    for k in range(3):
        assert np.array_equal(two[k], a)


def test_noise_seeds_differ_and_zero_noise_is_no_noise():
    ctrl = press_controls(1000, 2e-4)
    runs = {}
    for name, extra in {
        "seed7": {"seed": "7"},
        "seed8": {"seed": "8"},
        "sd0": {"noise": "0 0 0", "seed": "7"},
    }.items():
        m, _ = noise_model(**extra)
        runs[name] = run_serial(m, mujoco.MjData(m), ctrl)
    # the seed also picks each receptor's population variant: compare at seed 7
    plain_skin = {
        "outputs": NOISE_SKIN["outputs"],
        "seed": "7",
        "noise": "0 0 0",
        "noise_tau": "5e-3",
    }  # no noise at all, whatever its time constant
    m = flat_scene(plain_skin, timestep_s=2e-4)
    layout = SkinLayout.from_model(m)
    plain = run_serial(m, mujoco.MjData(m), ctrl)
    s7, s8 = (layout.block(runs[k], "spikes") for k in ("seed7", "seed8"))
    assert not np.array_equal(s7, s8)
    # the stress (upstream of the receptors) is the same whatever the noise
    assert np.array_equal(layout.block(runs["seed7"], "stress"), layout.block(plain, "stress"))
    assert np.array_equal(runs["sd0"], plain)
    assert not np.array_equal(s7, layout.block(plain, "spikes"))


def test_noisy_plugin_spikes_equal_receptor_run_with_its_stream():
    # Receptor r draws its noise from stream r: receptor_run with the same
    # attributes and stream reproduces every receptor's spikes bit for bit.
    m, skin = noise_model(seed="11")
    layout = SkinLayout.from_model(m)
    sd = run_serial(m, mujoco.MjData(m), press_controls(1000, 2e-4))
    spikes, stress = layout.block(sd, "spikes"), layout.block(sd, "stress")
    for r in range(0, len(layout.classes), 5):
        got, _ = core.receptor_run(str(layout.classes[r]), stress[:, r], 2e-4, skin, stream=r)
        assert np.array_equal(got, spikes[:, r]), r


# --- explicit sites and the rate output --------------------------------------------------


def test_sites_place_receptors_where_asked():
    pitch, nx = 1.5e-4, 48
    asked = [
        ("SA1", 0.0, 0.0),
        ("SA1", 1.03e-3, -0.52e-3),
        ("RA", -2.01e-3, 0.4e-3),
        ("PC", 0.61e-3, 1.9e-3),
        ("RA", 0.3e-3, 0.3e-3),
    ]
    depth = {"SA1": 5e-4, "RA": 9e-4, "PC": 2.2e-3}
    sites = "; ".join(f"{c} {x} {y} {depth[c]}" for c, x, y in asked)
    # exact stress summation (as core's), no shear traction, q = -s_zz
    skin = {
        "outputs": "spikes stress pressure",
        "sites": sites,
        "shear": "false",
        "quantity": "szz szz szz",
        "stress_method": "direct",
    }
    m = flat_scene(skin, timestep_s=2e-4)
    layout = SkinLayout.from_model(m)
    # classes in SA1, RA, PC order, each in the order given
    order = sorted(range(len(asked)), key=lambda k: ("SA1", "RA", "PC").index(asked[k][0]))
    assert list(layout.classes) == [asked[k][0] for k in order]
    for r, k in enumerate(order):
        c, x, y = asked[k]
        # snapped to the nearest taxel centre: within half a pitch
        assert np.all(np.abs(layout.positions_m[r, :2] - (x, y)) <= pitch / 2 + 1e-12)
        assert layout.positions_m[r, 2] == depth[c]
    # the stress each site reports is the layered skin's stress there, from
    # the plugin's own pressure field (mjtouch.core, same kernel)
    d = mujoco.MjData(m)
    for _ in range(750):  # 0.15 s pressed with 1 N
        d.ctrl[:] = [0.0, -1.0]
        mujoco.mj_step(m, d)
    mujoco.mj_forward(m, d)
    p = layout.block(d.sensordata, "pressure").reshape(nx, nx)
    skin_model = core.LayeredSkin()
    stress = layout.block(d.sensordata, "stress")
    assert stress.min() > 0
    for r in range(len(layout.classes)):
        ij = np.round(layout.positions_m[r, :2] / pitch + (nx - 1) / 2).astype(int)
        s = skin_model.field_stress(p, pitch, layout.positions_m[r, 2], [ij])
        # float32 pressures in sensordata vs the plugin's own: 1e-6 relative
        assert -s[0, 2] == pytest.approx(stress[r], rel=1e-6)


def test_rate_output_is_the_smoothed_spike_count():
    tau, dt = 0.02, 2e-4
    m = flat_scene({"outputs": "spikes rate", "rate_tau": str(tau)}, timestep_s=dt)
    layout = SkinLayout.from_model(m)
    sd = run_serial(m, mujoco.MjData(m), press_controls(1500, dt))
    spikes, rate = layout.block(sd, "spikes"), layout.block(sd, "rate")
    assert spikes.sum() > 100
    est = analysis.smoothed_rate(spikes, dt, tau)
    # The plugin weights each spike at its exact time in the step, the
    # estimate at the step's middle: per spike within a factor exp(+-dt/2tau)
    slack = math.exp(dt / (2 * tau)) - 1
    assert np.all(np.abs(rate - est) <= slack * est + 1e-9)
    # and the smoothed rate integrates to the spike count (kernel area 1),
    # up to the tail still inside the kernel at the end
    tail = rate[-1] * tau
    np.testing.assert_allclose(
        rate.sum(axis=0) * dt + tail, spikes.sum(axis=0), rtol=0.01, atol=0.5
    )


# --- RA on scanned gratings (full plugin) -----------------------------------------------


def test_ra_follows_a_scanned_mm_grating_and_not_a_flat_plate():
    # RA (FA I) afferents respond to gratings of mm period scanned across the
    # fingerpad at tens of mm/s with tens of impulses per second, locked to
    # the passage of the grooves (Darian-Smith & Oke 1980, J Physiol 309:117;
    # Phillips & Johnson 1981, J Neurophysiol 46:1192). The RA's gain control
    # acts on the sustained stress rate only, so a grating (zero-mean rate at
    # V/D) keeps its drive. 1 mm at 40 mm/s (V/D = 40 Hz), 0.5 N: the most
    # driven tenth of the RA units at >= V/D / 2 and at most 2 V/D; on a flat
    # plate, steady sliding leaves them silent (< 5 Hz).
    speed, period = 0.04, 1e-3
    proto = scenes.Protocol(speed_m_s=speed, timestep_s=2e-4, press_s=0.1)
    top = {}
    for kind in ("grating", "flat"):
        res = rollout.run_slide(
            fast_tip(), scenes.Texture(kind=kind, period_m=period), proto, duration_s=0.5
        )
        w = res.window(settle_s=0.05)
        ra = np.asarray(res.layout.classes) == "RA"
        rates = res.spikes[w][:, ra].sum(axis=0) / (res.spikes[w].shape[0] * res.dt)
        top[kind] = np.percentile(rates, 90)
    print("RA 90th-percentile rate (Hz)", top, "V/D", speed / period)
    assert speed / period / 2 <= top["grating"] <= 2 * speed / period, top
    assert top["flat"] < 5.0, top
