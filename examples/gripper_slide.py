"""Skin on a robot: a two-finger gripper squeezes a textured bar and slides
along it; each fingertip has its own mjtouch.skin (mjtouch.attach), and each
face of the bar its own grating, so the two fingers' stress spectra peak at
different V/D.

    python examples/gripper_slide.py [--json] [--plot FILE]

The robot is a plain MjSpec (a carriage sliding along x with two fingers
closing along y); mjtouch.attach adds the skins, mjtouch.layouts reads them
by sensor name. The gratings are non-colliding height fields in the skins'
texture group over the bar's faces (MuJoCo collides the flat bar).
"""

from __future__ import annotations

import argparse
import json
import math
import sys

import mujoco
import mujoco.rollout
import numpy as np

import mjtouch
from mjtouch import analysis
from mjtouch.scene import scenes

PERIODS_M = {"left": 1.0e-3, "right": 1.6e-3}  # the grating on each face of the bar
BAR_HALF_M = (0.04, 0.005, 0.01)  # the bar: 80 mm long, 10 mm thick, 20 mm tall
PAD_SEMI_AXES_M = (0.008, 0.007, 0.007)
SKIN = dict(nx=48, pitch=2e-4, ridges=True, outputs="spikes stress force")
# Each pad's local -z (the skin) faces the bar: a quarter turn about x.
FACE_QUAT = {
    "left": [math.sqrt(0.5), -math.sqrt(0.5), 0, 0],  # local z -> +y
    "right": [math.sqrt(0.5), math.sqrt(0.5), 0, 0],
}  # local z -> -y
SIDE = {"left": 1.0, "right": -1.0}


def gripper_spec(protocol: scenes.Protocol | None = None, **skin) -> mujoco.MjSpec:
    """The gripper, the bar and its two gratings, with a skin on each
    fingertip (attributes ``skin`` over SKIN)."""
    protocol = protocol or scenes.Protocol()
    tip = scenes.Fingertip(semi_axes_m=PAD_SEMI_AXES_M)
    spec = mujoco.MjSpec()
    spec.modelname = "gripper_slide"
    scenes.set_options(spec, protocol)
    L, T, H = BAR_HALF_M
    spec.worldbody.add_geom(
        name="bar", type=mujoco.mjtGeom.mjGEOM_BOX, size=[L, T, H], rgba=[0.55, 0.6, 0.65, 1]
    )
    for side, period in PERIODS_M.items():
        tex = scenes.Texture(kind="grating", period_m=period, length_m=2 * L)
        scenes.add_grating_hfield(spec, f"grating_{side}", tex, H)
        spec.worldbody.add_geom(
            name=f"grating_{side}",
            type=mujoco.mjtGeom.mjGEOM_HFIELD,
            hfieldname=f"grating_{side}",
            pos=[0, SIDE[side] * T, 0],
            quat=FACE_QUAT[side],
            contype=0,
            conaffinity=0,
            group=scenes.TEXTURE_GROUP,
            rgba=[0.45, 0.5, 0.55, 1],
        )
    start_x = -L / 2
    carriage = spec.worldbody.add_body(name="carriage", pos=[start_x, 0, 0])
    carriage.add_joint(
        name="slide_x",
        type=mujoco.mjtJoint.mjJNT_SLIDE,
        axis=[1, 0, 0],
        damping=2 * math.sqrt(scenes.SLIDE_KP * 0.1),
    )
    carriage.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.005, 0.03, 0.004],
        pos=[0, 0, H + 0.02],
        mass=0.06,
        contype=0,
        conaffinity=0,
    )
    a, b, c = PAD_SEMI_AXES_M
    for side in ("left", "right"):
        y0 = SIDE[side] * (T + c + scenes.PAD_CLEARANCE_M)
        finger = carriage.add_body(name=f"finger_{side}", pos=[0, y0, 0])
        finger.add_joint(
            name=f"close_{side}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0], damping=2
        )
        finger.add_geom(
            type=mujoco.mjtGeom.mjGEOM_CAPSULE,
            size=[0.002, 0.01, 0],
            pos=[0, 0, H + 0.01],
            mass=0.01,
            contype=0,
            conaffinity=0,
        )
        finger.add_geom(
            name=f"pad_{side}",
            type=mujoco.mjtGeom.mjGEOM_ELLIPSOID,
            size=[a, b, c],
            quat=FACE_QUAT[side],
            mass=tip.mass_kg,
            friction=[tip.friction, 0.005, 0.0001],
            solref=scenes.CONTACT_SOLREF,
            solimp=scenes.CONTACT_SOLIMP,
            rgba=[0.93, 0.72, 0.62, 1],
        )
        squeeze = spec.add_actuator(
            name=f"squeeze_{side}", target=f"close_{side}", trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
        squeeze.set_to_motor()
        squeeze.ctrlrange = [-10, 10]
        mu = tip.friction
        spec.add_pair(
            geomname1=f"pad_{side}",
            geomname2="bar",
            condim=3,
            friction=[mu, mu, 0.005, 0.0001, 0.0001],
            solref=scenes.CONTACT_SOLREF,
            solimp=scenes.PAIR_SOLIMP,
            solreffriction=[scenes.friction_timeconst(tip, protocol), 1],
        )
        # each skin feels its own face's grating (the far one, seen from
        # behind the bar, would read as a deep overlap)
        mjtouch.attach(
            spec, f"pad_{side}", name=f"skin_{side}", texture=f"grating_{side}", **{**SKIN, **skin}
        )
    slide = spec.add_actuator(name="slide", target="slide_x", trntype=mujoco.mjtTrn.mjTRN_JOINT)
    slide.set_to_intvelocity(kp=scenes.SLIDE_KP)
    slide.actrange = [-L, L]
    slide.ctrlrange = [-2, 2]
    scenes.add_light(spec)
    return spec


def controls(model: mujoco.MjModel, protocol: scenes.Protocol, duration_s: float) -> np.ndarray:
    """Squeeze with protocol.force_n per finger, then slide at protocol.speed_m_s."""
    n_press = int(round(protocol.press_s / protocol.timestep_s))
    ctrl = np.zeros((n_press + int(round(duration_s / protocol.timestep_s)), model.nu))
    aid = lambda n: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, n)  # noqa: E731
    ctrl[:, aid("squeeze_left")] = -protocol.force_n  # towards -y, onto the bar
    ctrl[:, aid("squeeze_right")] = protocol.force_n
    ctrl[n_press:, aid("slide")] = protocol.speed_m_s
    return ctrl


def run(model: mujoco.MjModel, ctrl: np.ndarray, nthread: int | None = None):
    """(state, sensordata) of a rollout from the model's initial state."""
    data = mujoco.MjData(model)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state0, spec)
    if nthread:
        datas = [mujoco.MjData(model) for _ in range(nthread)]
        state, sd = mujoco.rollout.rollout(
            model, datas, np.stack([state0] * nthread), np.stack([ctrl] * nthread)
        )
        return state, sd
    state, sd = mujoco.rollout.rollout(model, data, state0[None], ctrl[None])
    return state[0], sd[0]


def readouts(model, sensordata, protocol: scenes.Protocol, settle_s: float = 0.1) -> dict:
    """Per finger: firing rates, the strongest stress peaks and V/D."""
    w = slice(int(round((protocol.press_s + settle_s) / protocol.timestep_s)), None)
    out = {}
    for name, layout in mjtouch.layouts(model).items():
        side = name.removeprefix("skin_")
        spikes = layout.block(sensordata, "spikes")[w]
        f, p = analysis.stress_spectrum(layout.block(sensordata, "stress")[w], protocol.timestep_s)
        out[side] = {
            "rates_hz": analysis.rates_hz(spikes, protocol.timestep_s, layout.classes),
            "peaks_hz": analysis.spectral_peaks(f, p, n=3, fmin_hz=5.0, fmax_hz=500.0),
            "expected_hz": protocol.speed_m_s / PERIODS_M[side],
            "normal_force_n": float(layout.block(sensordata, "force")[w, 0].mean()),
            "fft_bin_hz": float(f[1] - f[0]),
        }
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=0.8, help="sliding time (s)")
    ap.add_argument("--speed", type=float, default=0.04, help="sliding speed (m/s)")
    ap.add_argument("--force", type=float, default=0.5, help="squeeze per finger (N)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--plot", metavar="FILE", help="PNG of each finger's spectrum and raster")
    args = ap.parse_args(argv)
    protocol = scenes.Protocol(force_n=args.force, speed_m_s=args.speed, timestep_s=2e-4)
    model = gripper_spec(protocol).compile()
    _, sd = run(model, controls(model, protocol, args.duration))
    out = readouts(model, sd, protocol)
    if args.plot:
        _plot(args.plot, model, sd, protocol)
    if args.json:
        print(json.dumps(out))
        return 0
    for side, r in out.items():
        print(
            f"{side:5s} finger (D = {PERIODS_M[side] * 1e3:.1f} mm): V/D = "
            f"{r['expected_hz']:.1f} Hz, stress peaks "
            + ", ".join(f"{x:.1f}" for x in r["peaks_hz"])
            + " Hz; rates "
            + "  ".join(f"{k} {v:.1f}" for k, v in r["rates_hz"].items())
            + f" Hz; F = {r['normal_force_n']:.2f} N"
        )
    return 0


def _plot(path, model, sd, protocol):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lays = mjtouch.layouts(model)
    fig, axes = plt.subplots(2, len(lays), figsize=(5 * len(lays), 6), squeeze=False)
    dt = protocol.timestep_s
    w = slice(int(round((protocol.press_s + 0.1) / dt)), None)
    for k, (name, lay) in enumerate(lays.items()):
        f, p = analysis.stress_spectrum(lay.block(sd, "stress")[w], dt)
        side = name.removeprefix("skin_")
        axes[0, k].semilogy(f[1:], p[1:], lw=0.8)
        axes[0, k].axvline(protocol.speed_m_s / PERIODS_M[side], ls="--", c="r", label="V/D")
        axes[0, k].set(xlim=(0, 300), xlabel="frequency (Hz)", title=name)
        axes[0, k].legend()
        spikes = lay.block(sd, "spikes")[w]
        t = np.arange(spikes.shape[0]) * dt
        for r in range(spikes.shape[1]):
            axes[1, k].plot(t[spikes[:, r] > 0], np.full((spikes[:, r] > 0).sum(), r), "|", ms=2)
        axes[1, k].set(xlabel="time (s)", ylabel="receptor")
    fig.tight_layout()
    fig.savefig(path, dpi=100)


if __name__ == "__main__":
    sys.exit(main())
