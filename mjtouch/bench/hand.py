"""What skins cost on a whole robot hand: Gymnasium-Robotics' Shadow hand at
its own 2 ms step, five fingertip skins (one ``mjtouch.attach`` each).

    python -m mjtouch bench --hand [--time-steps N] [--repeats R] [--quick]
    python examples/bench_hand.py [--steps N] [--repeats R] [--threads T] [--quick]

Rows, timed interleaved in one process (thread CPU time per ``mj_step``,
min and median over repeats x steps):

- bare hand, fingertips free; + one acceleration-stage sensor (MuJoCo's own
  cost of any sensor that reads contact forces); + five skins idle (no
  contact): the idle cost;
- bare hand, four fingertips pressed on fixed plates; + five skins with the
  RL preset; + five skins with the RL preset but every substep evaluating
  all stages (``substep="full"``); + five default skins (elastic contact);
- the free and pressed rows again through ``mujoco.rollout``, which records
  the full state (plugin_state included) and sensordata every step: in the
  calling thread (thread CPU time), and on T threads over 2T MjData (wall
  time per step per MjData x T: noisy on a shared machine).

The RL preset is the bench's ``rl`` preset (``mjtouch.bench.configs.PRESETS``);
its accuracy against the science preset is the bench's ``presets`` knob
(``python -m mjtouch bench --knobs presets``). No Allegro hand: its model
comes only from mujoco_menagerie downloads.
"""

from __future__ import annotations

import argparse
import importlib.util
import pathlib
import time

import mujoco
import mujoco.rollout
import numpy as np

import mjtouch
from mjtouch.bench.configs import DEFAULT_DENSITY, PRESETS

FINGERS = ("ff", "mf", "rf", "lf", "th")
PRESSED = ("ff", "mf", "rf", "th")  # lf stays free
DEPTH_M = 1.5e-3  # each plate starts this far into its fingertip


def hand_xml() -> pathlib.Path:
    spec = importlib.util.find_spec("gymnasium_robotics")
    if spec is None:
        raise RuntimeError("the hand bench needs Gymnasium-Robotics: pip install -e '.[robots]'")
    root = pathlib.Path(spec.submodule_search_locations[0])
    return root / "envs" / "assets" / "hand" / "reach.xml"


def rl_attributes() -> dict:
    """The bench's `rl` preset as attach() attributes (its timestep aside:
    the hand keeps its own)."""
    p = PRESETS["rl"]
    out = {"nx": p["nx"], "pitch": p["pitch_m"], "ridges": p.get("ridges", True)}
    if "density_scale" in p:
        out["density"] = [d * p["density_scale"] for d in DEFAULT_DENSITY]
    out.update({k[5:]: v for k, v in p.items() if k.startswith("skin.")})
    return out


def pad_facing(model, data, finger: str) -> np.ndarray:
    """The side of the distal capsule that flexing the finger moves forward."""
    g = model.geom(f"robot0:C_{finger}distal").id
    x0, R0 = data.geom_xpos[g].copy(), data.geom_xmat[g].reshape(3, 3).copy()
    flexed = mujoco.MjData(model)
    joints = ["THJ0"] if finger == "th" else [f"{finger.upper()}J{k}" for k in (0, 1, 2)]
    for j in joints:
        flexed.qpos[model.joint(f"robot0:{j}").qposadr[0]] = 0.3
    mujoco.mj_forward(model, flexed)
    move = R0.T @ (flexed.geom_xpos[g] - x0)
    move[2] = 0.0
    axis = np.argmax(np.abs(move))
    f = np.zeros(3)
    f[axis] = np.sign(move[axis])
    return f


def add_pad_plates(spec, model, data, facing: dict, fingers, depth_m: float = DEPTH_M) -> None:
    """A fixed plate against each finger's distal capsule pad (normal along the
    pad's outward `facing[f]`, in the geom frame), starting depth_m into it;
    8 mm of the capsule's length lies on it. model, data: the hand before the
    plates, forward-computed."""
    for f in fingers:
        g = model.geom(f"robot0:C_{f}distal")
        R = data.geom_xmat[g.id].reshape(3, 3)
        n = R @ facing[f]
        centre = data.geom_xpos[g.id] + n * (g.size[0] - depth_m + 2e-3)
        x = R[:, 2]  # along the capsule
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.column_stack([x, np.cross(n, x), n]).ravel())
        spec.worldbody.add_geom(
            name=f"plate_{f}",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[4e-3, 8e-3, 2e-3],
            pos=centre,
            quat=quat,
        )


def hand(skin: dict | None, pressed: bool, settle_steps: int = 100, acc_sensor: bool = False):
    """(model, data) of the hand, gravity off, settled; skin: attach()
    attributes for five fingertip skins, or None (bare). acc_sensor: add one
    acceleration-stage sensor (MuJoCo then runs mj_rnePostConstraint every
    step, as it does for the skins, which need the contact forces)."""
    spec = mujoco.MjSpec.from_file(str(hand_xml()))
    spec.option.gravity = [0, 0, 0]
    if acc_sensor:
        spec.add_sensor(
            name="ff_linacc",
            type=mujoco.mjtSensor.mjSENS_FRAMELINACC,
            objtype=mujoco.mjtObj.mjOBJ_BODY,
            objname="robot0:ffdistal",
        )
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    facing = {f: pad_facing(model, data, f) for f in FINGERS}
    if pressed:
        add_pad_plates(spec, model, data, facing, PRESSED)
    if skin is not None:
        for f in FINGERS:
            mjtouch.attach(
                spec, body=f"robot0:{f}distal", name=f"skin_{f}", facing=facing[f], **skin
            )
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    for _ in range(settle_steps):
        mujoco.mj_step(model, data)
    return model, data


def step_cpu_us(model, data, steps: int) -> np.ndarray:
    out = np.empty(steps)
    for k in range(steps):
        t0 = time.thread_time_ns()
        mujoco.mj_step(model, data)
        out[k] = time.thread_time_ns() - t0
    return out / 1e3


def rollout_us(model, data, steps: int, threads: int, runner) -> float:
    """Per step of one MjData, from the settled state (rollout records the
    full state and sensordata every step): threads = 0, thread CPU time of
    the calling thread (the rollout runs in it); else wall time x threads
    (the CPU per step if each thread had a core)."""
    n = max(2 * threads, 1)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    states = np.repeat(state[None], n, axis=0)
    ctrl = np.zeros((n, steps, model.nu))
    datas = [mujoco.MjData(model) for _ in range(max(threads, 1))]
    # output buffers touched before timing: a fresh one costs the kernel's
    # page zeroing, which is not the sensor's cost
    out_state = np.ones((n, steps, state.size))
    out_sensor = np.ones((n, steps, model.nsensordata))
    clock = time.perf_counter if threads else time.thread_time
    t0 = clock()
    runner.rollout(model, datas, states, ctrl, state=out_state, sensordata=out_sensor)
    return (clock() - t0) / (n * steps) * max(threads, 1) * 1e6


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--steps", type=int, default=300, help="steps per timed repeat")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--threads", type=int, default=2, help="mujoco.rollout threads (>= 1)")
    p.add_argument("--quick", action="store_true", help="smoke run: 20 steps, 1 repeat")
    args = p.parse_args(argv)
    if args.quick:
        args.steps, args.repeats = 20, 1
    if args.steps < 1 or args.repeats < 1 or args.threads < 1:
        p.error(f"--steps {args.steps}, --repeats {args.repeats}, --threads {args.threads}: >= 1")
    rl = rl_attributes()
    rows = {
        "bare, free": hand(None, False),
        "bare + 1 acc-stage sensor, free": hand(None, False, acc_sensor=True),
        "5 skins rl, idle": hand(rl, False),
        "bare, 4 tips pressed": hand(None, True),
        "5 skins rl, 4 pressed": hand(rl, True),
        "5 skins rl substep=full, 4 pressed": hand({**rl, "substep": "full"}, True),
        "5 default skins, 4 pressed": hand({}, True),
    }
    cpu = {k: [] for k in rows}
    for _ in range(args.repeats):
        for k, (m, d) in rows.items():
            steps = args.steps if "default" not in k else max(5, args.steps // 10)
            cpu[k].append(step_cpu_us(m, d, steps))
    m0 = rows["bare, free"][0]
    print(f"Shadow hand (Gymnasium-Robotics), timestep {m0.opt.timestep * 1e3:g} ms; rl = {rl}")

    def table(times: dict) -> None:
        lo = {k: float(np.min(v)) for k, v in times.items()}
        mid = {k: float(np.median(v)) for k, v in times.items()}
        for k in times:
            ref = "bare, 4 tips pressed" if "pressed" in k else "bare, free"
            print(
                f"  {k:36s} {lo[k]:8.1f} {mid[k]:8.1f}   "
                f"{lo[k] / lo[ref]:7.2f} {mid[k] / mid[ref]:7.2f}"
            )

    print("thread CPU per mj_step, us             min   median   x bare: min  median")
    table({k: np.concatenate(v) for k, v in cpu.items()})
    for threads in (0, args.threads):
        with mujoco.rollout.Rollout(nthread=threads) as runner:
            res = {k: [] for k in rows if "substep" not in k and "default" not in k}
            for _ in range(args.repeats):
                for k in res:
                    m, d = rows[k]
                    res[k].append(rollout_us(m, d, args.steps, threads, runner))
        if threads == 0:
            print("mujoco.rollout in this thread: thread CPU per step, us")
        else:
            print(f"mujoco.rollout, {threads} threads: wall per step per MjData x threads, us")
        table(res)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
