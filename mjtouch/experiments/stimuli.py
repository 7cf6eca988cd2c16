"""Stimuli a touch neuroscientist uses, as MuJoCo scenes and runners.

- A displacement-controlled **probe** (flat cylindrical pin, sphere, or any
  geom) pressed up into a fingertip held still by a stiff servo: the probe is
  a mocap body, so its displacement is exactly the commanded one; the finger
  sits on a 1e6 N/m critically damped servo, so it moves ~1 um per N
  (reported, and tested). Not welded: MuJoCo gives no contact force between
  a mocap body and a body fixed to the world (neither has a degree of
  freedom), and the skin needs that force.
- A **vibrating plate** (a mocap body) under a fingertip pressed with a set
  force.
- **Waveforms** (displacement in m as functions of time): ramp-and-hold, sine
  with ramps, sum of sines, band-limited noise (seeded) and an arbitrary trace.
- **Force control** that tracks a force trace (:func:`press_force_controls`):
  closed loop on MuJoCo's contact force, computed on the bare scene (the skin
  sensor does not change the physics) and replayed open loop, so batches
  still run through ``mujoco.rollout`` threads.

Every runner returns spike trains, receptor stress, the normal force and the
achieved displacement (:class:`StimulusResult`).
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import Literal

import mujoco
import mujoco.rollout
import numpy as np

from mjtouch._validate import in_range
from mjtouch.analysis import signals
from mjtouch.experiments.rollout import chunked_rollout
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

# --- waveforms -----------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Waveform:
    """A displacement (m) as a function of time (s) over [0, duration_s].
    ``kind`` and ``params`` describe it (for JSON); ``steady_s`` is the
    interval of the steady part (the hold, or a sine between its ramps)."""

    kind: str
    duration_s: float
    fn: Callable[[np.ndarray], np.ndarray]
    params: dict
    steady_s: tuple[float, float]

    def sample(self, dt_s: float) -> np.ndarray:
        """Values at t = k dt, k = 0 .. round(duration / dt) - 1 (one per step)."""
        in_range("dt_s", dt_s, 0, 5e-3, "s", lo_open=True)
        n = int(round(self.duration_s / dt_s))
        return np.asarray(self.fn(np.arange(n) * dt_s), dtype=float)


def _envelope(t: np.ndarray, duration_s: float, ramp_s: float) -> np.ndarray:
    """0 -> 1 over ramp_s (raised cosine, no step in slope), 1, then back to 0
    over the last ramp_s: the ramps physiologists put on sines so the onset
    transient does not dominate (e.g. 50 ms in issue 14's protocol)."""
    if ramp_s <= 0:
        return ((t >= 0) & (t <= duration_s)).astype(float)
    up = np.clip(t / ramp_s, 0, 1)
    down = np.clip((duration_s - t) / ramp_s, 0, 1)
    return 0.5 - 0.5 * np.cos(np.pi * np.minimum(up, down))


def ramp_and_hold(
    depth_m: float,
    ramp_s: float = 0.05,
    hold_s: float = 0.5,
    release: bool = True,
    rest_s: float = 0.05,
) -> Waveform:
    """Linear ramp to depth_m over ramp_s, hold, then (release) ramp back to 0
    and rest_s at 0."""
    depth = in_range("depth_m", depth_m, 0, 5e-3, "m", lo_open=True)
    ramp = in_range("ramp_s", ramp_s, 1e-4, 10, "s")
    hold = in_range("hold_s", hold_s, 0, 60, "s")
    rest = in_range("rest_s", rest_s, 0, 60, "s")
    knots = [0, ramp, ramp + hold] + ([2 * ramp + hold] if release else [])
    values = [0, depth, depth] + ([0] if release else [])
    dur = knots[-1] + (rest if release else 0.0)
    return Waveform(
        "ramp_and_hold",
        dur,
        lambda t: np.interp(t, knots, values),
        dict(depth_m=depth, ramp_s=ramp, hold_s=hold, release=release, rest_s=rest),
        (ramp, ramp + hold),
    )


def sine(
    amplitude_m: float, freq_hz: float, duration_s: float = 1.0, ramp_s: float = 0.05
) -> Waveform:
    """amplitude sin(2 pi f t) under raised-cosine ramps of ramp_s at both ends
    (about the probe's pre-indentation or the plate's rest position)."""
    return sum_of_sines([amplitude_m], [freq_hz], duration_s, ramp_s, kind="sine")


def sum_of_sines(
    amplitudes_m: Sequence[float],
    freqs_hz: Sequence[float],
    duration_s: float = 1.0,
    ramp_s: float = 0.05,
    phases_rad: Sequence[float] | None = None,
    kind: str = "sum_of_sines",
) -> Waveform:
    """sum_i a_i sin(2 pi f_i t + phi_i) under the ramps of :func:`sine`."""
    amps = np.atleast_1d(np.asarray(amplitudes_m, dtype=float))
    freqs = np.atleast_1d(np.asarray(freqs_hz, dtype=float))
    if amps.ndim != 1 or amps.shape != freqs.shape or amps.size == 0:
        raise ValueError(
            f"amplitudes_m (shape {amps.shape}) and freqs_hz (shape "
            f"{freqs.shape}) must be 1-D of the same non-zero length"
        )
    phases = (
        np.zeros_like(freqs)
        if phases_rad is None
        else np.atleast_1d(np.asarray(phases_rad, dtype=float))
    )
    if phases.shape != freqs.shape:
        raise ValueError(f"phases_rad has shape {phases.shape}; expected {freqs.shape}")
    for a in amps:
        in_range("amplitude_m", a, 0, 2e-3, "m")
    for f in freqs:
        in_range("freq_hz", f, 0, 2000, "Hz", lo_open=True)
    dur = in_range("duration_s", duration_s, 1e-3, 60, "s")
    ramp = in_range("ramp_s", ramp_s, 0, dur / 2, "s")
    w = 2 * np.pi * freqs

    def fn(t):
        s = np.zeros_like(t)
        for a, wi, p in zip(amps, w, phases):
            s += a * np.sin(wi * t + p)
        return _envelope(t, dur, ramp) * s

    params = dict(
        amplitudes_m=amps.tolist(),
        freqs_hz=freqs.tolist(),
        phases_rad=phases.tolist(),
        duration_s=dur,
        ramp_s=ramp,
    )
    if kind == "sine":
        params = dict(
            amplitude_m=float(amps[0]), freq_hz=float(freqs[0]), duration_s=dur, ramp_s=ramp
        )
    return Waveform(kind, dur, fn, params, (ramp, dur - ramp))


def noise(
    rms_m: float,
    band_hz: tuple[float, float] = (10.0, 500.0),
    duration_s: float = 1.0,
    seed: int = 0,
    ramp_s: float = 0.05,
) -> Waveform:
    """Band-limited Gaussian-like noise: every multiple of 1/duration_s inside
    band_hz with equal amplitude and a seeded random phase (a flat spectrum;
    the sum of many random-phase sines is close to Gaussian), scaled to
    rms_m over the steady part. A function of continuous time, so it does not
    depend on the timestep."""
    rms = in_range("rms_m", rms_m, 0, 1e-3, "m", lo_open=True)
    dur = in_range("duration_s", duration_s, 1e-2, 60, "s")
    if len(band_hz) != 2:
        raise ValueError(f"band_hz = {band_hz!r} must be (low, high) in Hz")
    lo = in_range("band_hz[0]", band_hz[0], 0, 2000, "Hz")
    hi = in_range("band_hz[1]", band_hz[1], lo, 2000, "Hz", lo_open=True)
    if not (isinstance(seed, (int, np.integer)) and seed >= 0):
        raise ValueError(f"seed = {seed!r} must be a non-negative integer")
    freqs = np.arange(math.ceil(lo * dur), math.floor(hi * dur) + 1) / dur
    freqs = freqs[freqs > 0]
    if freqs.size == 0:
        raise ValueError(
            f"band_hz = {tuple(band_hz)} holds no multiple of 1/duration_s = "
            f"{1 / dur:g} Hz; widen the band or lengthen the stimulus"
        )
    phases = np.random.default_rng(seed).uniform(0, 2 * np.pi, freqs.size)
    a = rms * math.sqrt(2.0 / freqs.size)  # each sine carries a^2/2 of the power
    w = sum_of_sines(
        np.full(freqs.size, a),
        freqs,
        dur,
        in_range("ramp_s", ramp_s, 0, dur / 2, "s"),
        phases,
        kind="noise",
    )
    return dataclasses.replace(
        w,
        params=dict(
            rms_m=rms,
            band_hz=[lo, hi],
            duration_s=dur,
            seed=int(seed),
            ramp_s=ramp_s,
            components=int(freqs.size),
        ),
    )


def trace(values_m: Sequence[float], dt_s: float) -> Waveform:
    """An arbitrary displacement trace sampled every dt_s, linearly
    interpolated (held at its last value past its end)."""
    v = np.asarray(values_m, dtype=float)
    if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)):
        raise ValueError(
            f"values_m must be a 1-D finite array of >= 2 samples, got shape {v.shape}"
        )
    if np.abs(v).max() > 5e-3:
        raise ValueError(f"values_m reaches {np.abs(v).max():g} m; valid range [-5e-3, 5e-3] m")
    dt = in_range("dt_s", dt_s, 0, 1, "s", lo_open=True)
    tk = np.arange(v.size) * dt
    return Waveform(
        "trace",
        float(tk[-1]),
        lambda t: np.interp(t, tk, v),
        dict(samples=int(v.size), dt_s=dt),
        (0.0, float(tk[-1])),
    )


# --- force control -------------------------------------------------------------------------

# Approach: the pad is driven down under velocity control (a motor loop of
# 2 ms) at up to APPROACH_SPEED, slowing to LANDING_SPEED over the last
# LANDING_ZONE of the gap, so a light press lands in ~20 ms instead of
# coasting at F / joint damping (5 mm/s at 10 mN: 60 ms for 0.3 mm, then
# ringing on MuJoCo's soft contact). Then force control: feedforward of the
# target, cancellation of the joint's damping with the measured velocity
# (the lag of a motor press on a ramp is mostly the damper), and PI on the
# contact force error.
APPROACH_SPEED_M_S = 0.05
LANDING_SPEED_M_S = 0.002
LANDING_ZONE_M = 2e-4
VELOCITY_LOOP_S = 2e-3
# Gains from a sweep over 3 mN - 5 N landings and a 50 ms ramp to 0.5 N
# (dt 1e-4): proportional gain above ~2 or integral gain 3000/s goes
# unstable (MuJoCo's soft contact force answers the motor within the step).
FORCE_KP = 1.0  # N/N
FORCE_KI_PER_S = 1000.0  # N/(N s)


def contact_normal_force(model: mujoco.MjModel, data: mujoco.MjData, geom_id: int) -> float:
    """Sum of MuJoCo's normal contact forces (N) on geom geom_id."""
    total = 0.0
    f6 = np.zeros(6)
    for i in range(data.ncon):
        c = data.contact[i]
        if geom_id in (c.geom1, c.geom2) and c.efc_address >= 0:
            mujoco.mj_contactForce(model, data, i, f6)
            total += f6[0]
    return total


@dataclasses.dataclass
class PressTrace:
    """The press controls that track a force trace, and what they achieved."""

    ctrl: np.ndarray  # (n,) press motor control per step (N along +z: negative presses)
    target_n: np.ndarray  # (n,) target normal force per step
    force_n: np.ndarray  # (n,) normal force on the pad in step k (what sensordata row k reports)
    landed_s: float  # first time the contact force stays within 5% of target (inf if never)


def press_force_controls(
    spec: mujoco.MjSpec,
    target_n: np.ndarray,
    pad: str = "pad",
    counter: str = "plate",
    actuator: str = "press",
    joint: str = "press_z",
    other_ctrl: np.ndarray | None = None,
    mocap_pos: np.ndarray | None = None,
) -> PressTrace:
    """Controls of the motor ``actuator`` (ctrl = force along the joint's +z,
    so pressing down is negative) that make MuJoCo's normal force on ``pad``
    follow ``target_n`` (N, one value per step). Computed closed loop on the
    spec without its skin sensors (the sensor does not change the physics:
    replaying the controls in the skinned model gives the same motion, bit for
    bit) and returned for open-loop replay. ``other_ctrl`` (n, nu) sets the
    other actuators; ``mocap_pos`` (n, nmocap*3) moves mocap bodies."""
    target = np.asarray(target_n, dtype=float)
    if target.ndim != 1 or target.size == 0 or not np.all(np.isfinite(target)):
        raise ValueError("target_n must be a 1-D finite array (N per step)")
    if target.min() < 0 or target.max() > 100:
        raise ValueError(
            f"target_n spans [{target.min():g}, {target.max():g}] N; valid range [0, 100] N"
        )
    bare = scenes.remove_skin(spec.copy()).compile()
    d = mujoco.MjData(bare)
    aid = mujoco.mj_name2id(bare, mujoco.mjtObj.mjOBJ_ACTUATOR, actuator)
    jid = mujoco.mj_name2id(bare, mujoco.mjtObj.mjOBJ_JOINT, joint)
    pid = mujoco.mj_name2id(bare, mujoco.mjtObj.mjOBJ_GEOM, pad)
    cid = mujoco.mj_name2id(bare, mujoco.mjtObj.mjOBJ_GEOM, counter)
    for name, i in (
        (f"actuator {actuator!r}", aid),
        (f"joint {joint!r}", jid),
        (f"geom {pad!r}", pid),
        (f"geom {counter!r}", cid),
    ):
        if i < 0:
            raise ValueError(f"the scene has no {name}")
    dof = bare.jnt_dofadr[jid]
    damping = float(bare.dof_damping[dof])
    mass = 1.0 / max(float(bare.dof_invweight0[dof]), 1e-12)  # the joint's effective mass
    dt = float(bare.opt.timestep)
    n = target.size
    ctrl = np.zeros(n)
    force = np.zeros(n)
    integral = 0.0
    in_contact = False
    for k in range(n):
        if other_ctrl is not None:
            d.ctrl[:] = other_ctrl[k]
        if mocap_pos is not None:
            d.mocap_pos[:] = np.reshape(mocap_pos[k], d.mocap_pos.shape)
        mujoco.mj_forward(bare, d)
        fc = contact_normal_force(bare, d, pid)
        v = float(d.qvel[dof])
        if not in_contact and fc > 0:
            in_contact = True
        if not in_contact:
            gap = mujoco.mj_geomDistance(bare, d, pid, cid, 0.05, None)
            v_des = -min(
                APPROACH_SPEED_M_S,
                LANDING_SPEED_M_S
                + (APPROACH_SPEED_M_S - LANDING_SPEED_M_S) * max(gap, 0) / LANDING_ZONE_M,
            )
            u = damping * v + mass * (v_des - v) / VELOCITY_LOOP_S
        else:
            err = target[k] - fc
            integral += err * dt
            u = -(target[k] + FORCE_KP * err + FORCE_KI_PER_S * integral) + damping * v
        ctrl[k] = u
        d.ctrl[aid] = u
        mujoco.mj_step(bare, d)
        force[k] = contact_normal_force(bare, d, pid)
    ok = np.abs(force - target) <= 0.05 * np.maximum(target, 1e-9)
    bad = np.nonzero(~ok)[0]
    landed = 0.0 if bad.size == 0 else (math.inf if bad[-1] == n - 1 else (bad[-1] + 1) * dt)
    return PressTrace(ctrl, target, force, landed)


# --- scenes ----------------------------------------------------------------------------------

HOLD_KP = 1e6  # N/m: the held finger's servo; ~1 um per N of probe force
# 7.35 mm of smooth skin; odd nx: a taxel centre on the pad's axis, under the default probe
PROBE_TIP = scenes.Fingertip(nx=49, pitch_m=1.5e-4, ridges=False)
# `sites` replaces the density population; these attributes then go
_POPULATION_KEYS = ("classes", "density", "depth", "radius")
OUTPUTS = "spikes stress force"  # the blocks every runner needs
ProbeShape = Literal["pin", "sphere", "geom"]
_GEOM_TYPES = {
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE,
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE,
    "ellipsoid": mujoco.mjtGeom.mjGEOM_ELLIPSOID,
    "box": mujoco.mjtGeom.mjGEOM_BOX,
    "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
}


@dataclasses.dataclass
class Probe:
    """The indenter, moving along +z into the pad from below, its top at the
    body origin. ``pin``: a flat-ended cylinder of ``radius_m`` (the usual
    physiology probe, e.g. 0.5 mm); ``sphere``: a sphere of ``radius_m``;
    ``geom``: any geom, ``geom_type`` (sphere, capsule, ellipsoid, box,
    cylinder) with MuJoCo ``geom_size`` (m), placed so its top is at the
    origin. ``x_m``, ``y_m``: where under the pad it presses."""

    shape: ProbeShape = "pin"
    radius_m: float = 0.5e-3
    geom_type: str = "box"
    geom_size: tuple[float, ...] = (1e-3, 1e-3, 1e-3)
    x_m: float = 0.0
    y_m: float = 0.0

    def validate(self, tip: scenes.Fingertip) -> None:
        if self.shape not in ("pin", "sphere", "geom"):
            raise ValueError(f"probe shape = {self.shape!r} is not one of 'pin', 'sphere', 'geom'")
        in_range("radius_m", self.radius_m, 0, 5e-3, "m", lo_open=True)
        if self.shape == "geom":
            if self.geom_type not in _GEOM_TYPES:
                raise ValueError(
                    f"geom_type = {self.geom_type!r} is not one of {sorted(_GEOM_TYPES)}"
                )
            for s in self.geom_size:
                in_range("geom_size", s, 0, 0.02, "m", lo_open=True)
        a, b, _ = tip.semi_axes_m
        if (self.x_m / a) ** 2 + (self.y_m / b) ** 2 > 0.25:
            raise ValueError(
                f"probe at (x_m, y_m) = ({self.x_m:g}, {self.y_m:g}) m is outside "
                f"the pad's central half (semi-axes {a:g}, {b:g} m)"
            )

    def geom(self) -> dict:
        """add_geom arguments with the top of the geom at the body origin."""
        if self.shape == "pin":  # half-length 2 mm: the face is flat, the side never touches
            return dict(
                type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                size=[self.radius_m, 2e-3, 0],
                pos=[0, 0, -2e-3],
            )
        if self.shape == "sphere":
            return dict(
                type=mujoco.mjtGeom.mjGEOM_SPHERE,
                size=[self.radius_m, 0, 0],
                pos=[0, 0, -self.radius_m],
            )
        t = _GEOM_TYPES[self.geom_type]
        size = list(self.geom_size) + [0.0] * (3 - len(self.geom_size))
        top = {
            mujoco.mjtGeom.mjGEOM_SPHERE: size[0],
            mujoco.mjtGeom.mjGEOM_CAPSULE: size[0] + size[1],
        }.get(t, size[2] if t != mujoco.mjtGeom.mjGEOM_CYLINDER else size[1])
        return dict(type=t, size=size, pos=[0, 0, -top])


# `elastic` contact solved to 1e-7 of the load, not the plugin's 1e-4: a
# vibration of nm-um moves the load by 1e-6-1e-3 of the static one, which
# the default tolerance would blur (measured: q(2a) - 2 q(a) at 6% of the
# response for 1 um at 250 Hz; 1e-7 brings it under 1%,
# tests/science/test_afferents.py).
STIMULUS_TOLERANCE = "1e-7"


def _skin(tip: scenes.Fingertip, skin: dict | None) -> scenes.Fingertip:
    cfg = dict(tip.skin)
    cfg.update(skin or {})
    if cfg.get("pressure", "elastic") == "elastic":
        cfg.setdefault("tolerance", STIMULUS_TOLERANCE)
        # One contact grid: a probe moves along the skin's normal, so no
        # edge crosses the grid and no grid line forms for the cycle to
        # cancel; the cycle would also stop each grid at N x the tolerance.
        cfg.setdefault("grid_cycle", "1")
    have = cfg.get("outputs", "spikes stress").split()
    cfg["outputs"] = " ".join(dict.fromkeys(have + OUTPUTS.split()))
    return dataclasses.replace(tip, skin=cfg)


def _actuator(spec: mujoco.MjSpec, name: str):
    return next(a for a in spec.actuators if a.name == name)


def probe_spec(
    probe: Probe | None = None,
    tip: scenes.Fingertip | None = None,
    timestep_s: float = 1e-4,
    skin: dict | None = None,
) -> mujoco.MjSpec:
    """The fingertip held still by a stiff servo (press target 0) and a mocap
    probe under it, its top touching the pad's surface at mocap z =
    :func:`probe_contact_z` (the probe body's initial z). Controls: (slide, press) = (0, 0); mocap_pos =
    the probe's (x, y, z)."""
    probe = probe or Probe()
    tip = _skin(tip or PROBE_TIP, skin)
    probe.validate(tip)
    protocol = scenes.Protocol(timestep_s=in_range("timestep_s", timestep_s, 1e-6, 1e-3, "s"))
    spec = mujoco.MjSpec()
    spec.modelname = "mjtouch_probe"
    scenes.set_options(spec, protocol)
    scenes.add_fingertip(spec, tip, start_x_m=0.0, travel_m=0.01, control="displacement")
    # stiff and critically damped: the finger stays put under the probe
    press = _actuator(spec, "press")
    press.set_to_position(kp=HOLD_KP, kv=2 * math.sqrt(HOLD_KP * tip.mass_kg))
    # placed by probe_contact_z once the scene is whole
    body = spec.worldbody.add_body(
        name="probe", mocap=True, pos=[probe.x_m, probe.y_m, scenes.PAD_CLEARANCE_M]
    )
    body.add_geom(name="probe", rgba=[0.7, 0.7, 0.75, 1], **probe.geom())
    mu = tip.friction
    spec.add_pair(
        geomname1="pad",
        geomname2="probe",
        condim=3,
        friction=[mu, mu, 0.005, 0.0001, 0.0001],
        solref=scenes.CONTACT_SOLREF,
        solimp=scenes.PAIR_SOLIMP,
    )
    scenes.add_light(spec)
    body.pos = [probe.x_m, probe.y_m, probe_contact_z(spec)]
    return spec


def probe_contact_z(spec: mujoco.MjSpec) -> float:
    """The probe body's z at which the probe just touches the pad (finger at
    rest), from MuJoCo's own distance between the two geoms: exact for any
    geom and any place under the pad (a flat face meets the pad's lowest
    point under the face, not under its centre)."""
    bare = scenes.remove_skin(spec.copy()).compile()
    d = mujoco.MjData(bare)
    pad = mujoco.mj_name2id(bare, mujoco.mjtObj.mjOBJ_GEOM, "pad")
    probe = mujoco.mj_name2id(bare, mujoco.mjtObj.mjOBJ_GEOM, "probe")
    z = float(d.mocap_pos[0, 2]) - 1e-3  # 1 mm clear of the pad
    for _ in range(2):  # the second pass refines the convex solver's estimate
        d.mocap_pos[0, 2] = z
        mujoco.mj_forward(bare, d)
        z += mujoco.mj_geomDistance(bare, d, pad, probe, 0.05, None)
    return z


def vibrating_plate_spec(
    tip: scenes.Fingertip | None = None, timestep_s: float = 1e-4, skin: dict | None = None
) -> mujoco.MjSpec:
    """A fingertip pressed by its `press` motor (ctrl = -force, N) onto a flat
    plate on a mocap body (mocap_pos = the plate's offset, m), which vibrates."""
    tip = _skin(tip or PROBE_TIP, skin)
    texture = scenes.Texture(kind="flat")
    protocol = scenes.Protocol(timestep_s=in_range("timestep_s", timestep_s, 1e-6, 1e-3, "s"))
    spec = mujoco.MjSpec()
    spec.modelname = "mjtouch_vibrating_plate"
    scenes.set_options(spec, protocol)
    # the plate proxy and the rendered texture ride on one mocap body
    scenes.add_plate(spec, texture, parent=spec.worldbody.add_body(name="plate_body", mocap=True))
    scenes.add_fingertip(spec, tip, scenes.start_x(texture.length_m), texture.length_m)
    scenes.add_pad_plate_contact(spec, tip, protocol)
    return spec


# --- runners ---------------------------------------------------------------------------------


@dataclasses.dataclass
class StimulusResult:
    """One stimulus: rows are steps from the stimulus onset, row k evaluated
    at time k dt (sensordata of that step's forward pass)."""

    waveform: Waveform
    dt_s: float
    commanded_m: np.ndarray  # (n,) probe: total indentation asked (pre-indent + waveform);
    #                          plate: the plate's displacement (waveform)
    achieved_m: np.ndarray  # (n,) the same, relative to the finger: commanded minus the
    #                         finger's z displacement since settling
    finger_m: np.ndarray  # (n, 2) finger x, z displacement since settling
    force_n: np.ndarray  # (n,) normal force on the pad (the skin's force block)
    spikes: np.ndarray  # (n, nrec) spike counts per step
    stress: np.ndarray  # (n, nrec) receptor quantity, Pa
    layout: SkinLayout
    centre_m: tuple[float, float]  # where the stimulus is centred in the pad frame

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.spikes.shape[0]) * self.dt_s

    def window(self, part: str = "steady") -> slice:
        """Rows of the waveform's steady part ("steady") or all ("all")."""
        if part == "all":
            return slice(0, self.spikes.shape[0])
        if part != "steady":
            raise ValueError(f"part = {part!r} is not one of 'steady', 'all'")
        a, b = self.waveform.steady_s
        return slice(
            int(round(a / self.dt_s)), max(int(round(b / self.dt_s)), int(round(a / self.dt_s)) + 1)
        )

    def centred_units(self) -> dict[str, int]:
        """Per class, the receptor nearest the stimulus centre (the afferent
        a physiologist would record: receptive field centred on the probe;
        on the probe's axis in a :class:`ProbeScene` with ``axis_units``)."""
        return centred_units(self.layout, self.centre_m)

    def centred_offaxis_m(self) -> dict[str, float]:
        """Per class, the centred unit's distance (m) from the stimulus centre."""
        return {
            c: float(np.hypot(*(self.layout.positions_m[u, :2] - self.centre_m)))
            for c, u in self.centred_units().items()
        }

    def rates_hz(self, part: str = "steady") -> dict[str, dict[str, float]]:
        """Per class: ``mean`` over all its receptors, ``max`` over receptors,
        ``centre`` of the receptor nearest the stimulus centre (Hz)."""
        w = self.window(part)
        sp = self.spikes[w]
        dur = max(sp.shape[0], 1) * self.dt_s
        per = sp.sum(axis=0) / dur
        mean = signals.rates_hz(sp, self.dt_s, self.layout.classes)
        cen = self.centred_units()
        out = {}
        for c in cen:
            m = self.layout.classes == c
            out[c] = dict(mean=mean[c], max=float(per[m].max()), centre=float(per[cen[c]]))
        return out

    def summary(self) -> dict:
        """JSON-ready description: waveform, rates, displacement and force."""
        w = self.window("steady")
        err = np.abs(self.achieved_m - self.commanded_m)
        return dict(
            waveform=dict(kind=self.waveform.kind, **self.waveform.params),
            dt_s=self.dt_s,
            rates_hz=self.rates_hz(),
            peak_commanded_m=float(np.abs(self.commanded_m).max()),
            max_displacement_error_m=float(err.max()),
            finger_motion_max_m=float(np.abs(self.finger_m).max()),
            force_steady_mean_n=float(self.force_n[w].mean()),
            centred_offaxis_m=self.centred_offaxis_m(),
            receptors={c: int((self.layout.classes == c).sum()) for c in ("SA1", "RA", "PC")},
        )


def centred_units(layout: SkinLayout, centre_m) -> dict[str, int]:
    """Per class, the index of the receptor nearest centre_m (pad frame, m)."""
    out = {}
    for c in ("SA1", "RA", "PC"):
        idx = np.nonzero(layout.classes == c)[0]
        if idx.size:
            d = np.hypot(*(layout.positions_m[idx, :2] - np.asarray(centre_m)).T)
            out[c] = int(idx[np.argmin(d)])
    return out


def axis_sites(layout: SkinLayout, centre_m) -> str:
    """The `sites` attribute of layout's receptors with the unit of each
    class nearest centre_m moved onto it (the plugin snaps a site to the
    nearest taxel centre: on centre_m when it is one, else within pitch /
    sqrt 2). Receptor count and order are unchanged, so each keeps its
    noise stream and population variant."""
    pos = layout.positions_m.copy()
    for u in centred_units(layout, centre_m).values():
        pos[u, :2] = centre_m
    return "; ".join(f"{c} {x:.17g} {y:.17g} {z:.17g}" for c, (x, y, z) in zip(layout.classes, pos))


_FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS
_CTRL_MOCAP = mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_MOCAP_POS


class _Scene:
    """A compiled stimulus scene, settled once; each run starts from the
    settled state (same model and inputs: bit-identical outputs)."""

    spec: mujoco.MjSpec
    model: mujoco.MjModel
    centre_m: tuple[float, float]

    def _finish(self, settle_ctrl: np.ndarray, settle_mocap: np.ndarray) -> None:
        self.model = self.spec.compile()
        self.layout = SkinLayout.from_model(self.model)
        self.dt_s = float(self.model.opt.timestep)
        d = mujoco.MjData(self.model)
        for c, p in zip(settle_ctrl, settle_mocap):
            d.ctrl[:] = c
            d.mocap_pos[:] = p.reshape(d.mocap_pos.shape)
            mujoco.mj_step(self.model, d)
        self.hold_ctrl = np.array(settle_ctrl[-1]) if len(settle_ctrl) else np.array(d.ctrl)
        self.rest_mocap = np.array(d.mocap_pos).ravel()
        self.state = np.empty(mujoco.mj_stateSize(self.model, _FULL))
        mujoco.mj_getState(self.model, d, self.state, _FULL)
        self._qadr = [
            int(self.model.jnt_qposadr[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, j)])
            for j in ("slide_x", "press_z")
        ]

    def _mocap_rows(self, w: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _commanded(self, w: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def run(
        self, waveforms: Waveform | Sequence[Waveform], threads: int = 1
    ) -> StimulusResult | list[StimulusResult]:
        """Run each waveform from the settled state (one mujoco.rollout batch,
        ``threads`` threads). One waveform in, one result out."""
        single = isinstance(waveforms, Waveform)
        ws = [waveforms] if single else list(waveforms)
        if not ws or not all(isinstance(w, Waveform) for w in ws):
            raise ValueError("waveforms must be a Waveform or a non-empty list of them")
        nthread = int(in_range("threads", threads, 1, 64, "threads"))
        samples = [w.sample(self.dt_s) for w in ws]
        ctrls = []
        for s in samples:
            c = np.zeros((s.size, self.model.nu + 3 * self.model.nmocap))
            c[:, : self.model.nu] = self.hold_ctrl
            c[:, self.model.nu :] = self._mocap_rows(s)
            ctrls.append(c)

        # Each waveform in bounded chunks (rollout.chunked_rollout: the full
        # state, with the elastic warm start, is too large to keep for every
        # step), waveforms on `threads` Python threads (mujoco.rollout
        # releases the GIL), each with its own MjData and its own length (a
        # batch padded to its longest waveform simulated every short one that
        # long: 4 s for each 0.26 s sine of a tuning round).
        def one(i):
            return chunked_rollout(
                self.model,
                mujoco.MjData(self.model),
                self.state,
                ctrls[i],
                control_spec=_CTRL_MOCAP,
            )

        nworker = min(nthread, len(ws))
        if nworker > 1:
            with concurrent.futures.ThreadPoolExecutor(nworker) as pool:
                runs = list(pool.map(one, range(len(ws))))
        else:
            runs = [one(i) for i in range(len(ws))]
        # qpos before each step (the state row k is after step k)
        q0 = self.state[1 + np.array(self._qadr)]
        out = []
        for i, s in enumerate(samples):
            m = s.size
            state, sd = runs[i]
            q = np.vstack([q0[None], state[: m - 1][:, 1 + np.array(self._qadr)]])
            finger = q - q0
            commanded = self._commanded(s)
            out.append(
                StimulusResult(
                    waveform=ws[i],
                    dt_s=self.dt_s,
                    commanded_m=commanded,
                    achieved_m=commanded - finger[:, 1],
                    finger_m=finger,
                    force_n=self.layout.block(sd[:m], "force")[:, 0].copy(),
                    spikes=self.layout.block(sd[:m], "spikes").astype(np.int32),
                    stress=self.layout.block(sd[:m], "stress").copy(),
                    layout=self.layout,
                    centre_m=self.centre_m,
                )
            )
        return out[0] if single else out


class ProbeScene(_Scene):
    """The probe scene (:func:`probe_spec`) compiled and settled: the probe
    ramps to ``preindent_m`` over ``settle_s`` / 2 and holds for the rest, so
    sines and noise start in contact. ``run(waveform)`` then moves the probe
    by the waveform (m, positive into the skin) about the pre-indentation.
    ``axis_units``: the unit of each class nearest the probe's axis is moved
    onto it (:func:`axis_sites`; unless the skin sets ``sites``), so the
    centred unit is the one a recording centres the probe on; its distance
    from the axis is ``centred_offaxis_m()`` (0 at a taxel centre, e.g. the
    default probe on :data:`PROBE_TIP`)."""

    def __init__(
        self,
        probe: Probe | None = None,
        tip: scenes.Fingertip | None = None,
        preindent_m: float = 0.0,
        settle_s: float = 0.1,
        timestep_s: float = 1e-4,
        skin: dict | None = None,
        axis_units: bool = True,
    ):
        self.probe = probe or Probe()
        self.tip = tip or PROBE_TIP
        self.preindent_m = in_range("preindent_m", preindent_m, 0, 3e-3, "m")
        settle = in_range("settle_s", settle_s, 0, 10, "s")
        self.centre_m = (self.probe.x_m, self.probe.y_m)
        self.spec = probe_spec(self.probe, self.tip, timestep_s, skin)
        if axis_units and "sites" not in {**self.tip.skin, **(skin or {})}:
            sites = axis_sites(SkinLayout.from_model(self.spec.compile()), self.centre_m)
            keep = {k: v for k, v in self.tip.skin.items() if k not in _POPULATION_KEYS}
            skin = {k: v for k, v in (skin or {}).items() if k not in _POPULATION_KEYS}
            self.spec = probe_spec(
                self.probe,
                dataclasses.replace(self.tip, skin=keep),
                timestep_s,
                dict(skin, sites=sites),
            )
        self.z_contact = float(next(b for b in self.spec.bodies if b.name == "probe").pos[2])
        n = int(round(settle / timestep_s))
        depth = self.preindent_m * np.clip(np.arange(n) * timestep_s / max(settle / 2, 1e-9), 0, 1)
        self.dt_s = timestep_s
        self._finish(np.zeros((n, 2)), self._rows(depth))

    def _rows(self, depth_m):
        """mocap rows of the probe at total indentation depth_m (m)."""
        rows = np.empty((depth_m.size, 3))
        rows[:, 0], rows[:, 1] = self.probe.x_m, self.probe.y_m
        rows[:, 2] = self.z_contact + depth_m
        return rows

    def _mocap_rows(self, w):
        return self._rows(self.preindent_m + w)

    def _commanded(self, w):
        return self.preindent_m + w


class PlateScene(_Scene):
    """The vibrating plate (:func:`vibrating_plate_spec`): the finger lands and is held
    at ``press_n`` by :func:`press_force_controls` over ``settle_s``, then
    keeps its last press control (a constant force) while ``run(waveform)``
    moves the plate up (+) and down by the waveform (m)."""

    def __init__(
        self,
        press_n: float = 0.5,
        tip: scenes.Fingertip | None = None,
        settle_s: float = 0.1,
        timestep_s: float = 1e-4,
        skin: dict | None = None,
    ):
        self.press_n = in_range("press_n", press_n, 0, 20, "N", lo_open=True)
        settle = in_range("settle_s", settle_s, 0.02, 10, "s")
        self.tip = tip or PROBE_TIP
        self.spec = vibrating_plate_spec(self.tip, timestep_s, skin)
        self.centre_m = (0.0, 0.0)
        n = int(round(settle / timestep_s))
        self.press = press_force_controls(self.spec, np.full(n, self.press_n))
        ctrl = np.zeros((n, 2))
        ctrl[:, 1] = self.press.ctrl
        self.dt_s = timestep_s
        self._finish(ctrl, np.zeros((n, 3)))

    def _mocap_rows(self, w):
        rows = np.zeros((w.size, 3))
        rows[:, 2] = w
        return rows

    def _commanded(self, w):
        return w.copy()


def run_probe(
    waveform: Waveform, probe: Probe | None = None, preindent_m: float = 0.0, **kwargs
) -> StimulusResult:
    """One probe stimulus (builds a :class:`ProbeScene`; reuse the scene for many)."""
    return ProbeScene(probe, preindent_m=preindent_m, **kwargs).run(waveform)


def run_plate(waveform: Waveform, press_n: float = 0.5, **kwargs) -> StimulusResult:
    """One vibrating-plate stimulus (builds a :class:`PlateScene`)."""
    return PlateScene(press_n, **kwargs).run(waveform)
