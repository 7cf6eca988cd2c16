"""What skins cost on a whole robot hand: Gymnasium-Robotics' Shadow hand at
its own 2 ms step, five fingertip skins (one ``mjtouch.attach`` each).

    python examples/bench_hand.py [--steps N] [--repeats R] [--threads T] [--quick]

Rows, timed interleaved in one process (thread CPU time per ``mj_step``,
min and median over repeats x steps):

- bare hand, fingertips free; + five skins idle (no contact): the idle cost;
- bare hand, four fingertips pressed on fixed plates; + five skins with the
  RL preset; + five skins with the RL preset but every substep evaluating
  all stages (``substep="full"``); + five default skins (elastic contact);
- the free and pressed rows again through ``mujoco.rollout`` (T threads,
  2T MjData; wall time per step per MjData x threads).

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
        raise SystemExit("Gymnasium-Robotics is missing: pip install -e '.[robots]'")
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


def hand(skin: dict | None, pressed: bool, settle_steps: int = 100):
    """(model, data) of the hand, gravity off, settled; skin: attach()
    attributes for five fingertip skins, or None (bare)."""
    spec = mujoco.MjSpec.from_file(str(hand_xml()))
    spec.option.gravity = [0, 0, 0]
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    facing = {f: pad_facing(model, data, f) for f in FINGERS}
    if pressed:
        for f in PRESSED:
            g = model.geom(f"robot0:C_{f}distal")
            R = data.geom_xmat[g.id].reshape(3, 3)
            n = R @ facing[f]
            centre = data.geom_xpos[g.id] + n * (g.size[0] - DEPTH_M + 2e-3)
            x = R[:, 2]
            quat = np.zeros(4)
            mujoco.mju_mat2Quat(quat, np.column_stack([x, np.cross(n, x), n]).ravel())
            spec.worldbody.add_geom(
                name=f"plate_{f}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[4e-3, 8e-3, 2e-3],
                pos=centre,
                quat=quat,
            )
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
    """Wall time per step per MjData x threads (CPU per step if the threads
    each had a core), from the settled state."""
    n = 2 * threads
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    states = np.repeat(state[None], n, axis=0)
    ctrl = np.zeros((n, steps, model.nu))
    datas = [mujoco.MjData(model) for _ in range(threads)]
    t0 = time.perf_counter()
    runner.rollout(model, datas, states, ctrl)
    return (time.perf_counter() - t0) / (n * steps) * threads * 1e6


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--steps", type=int, default=300, help="steps per timed repeat")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--threads", type=int, default=2, help="mujoco.rollout threads")
    p.add_argument("--quick", action="store_true", help="smoke run: 20 steps, 1 repeat")
    args = p.parse_args(argv)
    if args.quick:
        args.steps, args.repeats = 20, 1
    rl = rl_attributes()
    rows = {
        "bare, free": hand(None, False),
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
    print("thread CPU per mj_step, us        min    median   median / bare")
    bare = {}
    for k, v in cpu.items():
        v = np.concatenate(v)
        ref = "bare, free" if ("free" in k or "idle" in k) else "bare, 4 tips pressed"
        bare.setdefault(k, np.median(v))
        ratio = np.median(v) / bare[ref]
        print(f"  {k:36s} {v.min():8.1f} {np.median(v):8.1f}   {ratio:8.2f}")
    with mujoco.rollout.Rollout(nthread=args.threads) as runner:
        print(f"mujoco.rollout, {args.threads} threads: wall per step per MjData x threads, us")
        res = {k: [] for k in list(rows)[:4]}
        for _ in range(args.repeats):
            for k in res:
                m, d = rows[k]
                res[k].append(rollout_us(m, d, args.steps, args.threads, runner))
        for k, v in res.items():
            ref = "bare, free" if ("free" in k or "idle" in k) else "bare, 4 tips pressed"
            ratio = np.median(v) / np.median(res[ref])
            print(f"  {k:36s} {min(v):8.1f} {np.median(v):8.1f}   {ratio:8.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
