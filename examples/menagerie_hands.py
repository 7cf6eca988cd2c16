"""Skins on every fingertip of mujoco_menagerie's Shadow, LEAP and Allegro
hands, each fingertip pressed by a plate: per skin, its normal force
against MuJoCo's normal force on the fingertip geom, and the share of that
force its patch carries (coverage).

    python examples/menagerie_hands.py PATH/TO/mujoco_menagerie [--hands shadow_hand ...] [--time]

Nothing is downloaded: give a local clone of mujoco_menagerie. Fingertips
are named per hand in HANDS (a body, whose colliding geom attach picks, or
a geom by name); their pad side is where flexing the distal joint moves
them (mjtouch.scene.robot.flexion_facing). A plate on a slide joint is
pushed into each pad with PUSH_N while the hand holds its pose (gravity
off, position servos at qpos0). --time adds each hand's cost at its own
timestep: thread CPU per mj_step, pressed, bare against an RL skin on
every fingertip (interleaved repeats, min and median).
"""

from __future__ import annotations

import argparse
import functools
import pathlib

import mujoco
import numpy as np

import mjtouch
from mjtouch.bench.hand import step_cpu_us
from mjtouch.scene import robot

# Fingertips per hand: (label, {"body": name} or {"geom": name}).
HANDS = {
    "shadow_hand": (
        "right_hand.xml",
        [
            ("ff", {"body": "rh_ffdistal"}),  # mesh f_distal_pst, unnamed
            ("mf", {"body": "rh_mfdistal"}),
            ("rf", {"body": "rh_rfdistal"}),
            ("lf", {"body": "rh_lfdistal"}),
            ("th", {"body": "rh_thdistal"}),  # mesh th_distal_pst, unnamed
        ],
    ),
    "leap_hand": (
        "right_hand.xml",
        [  # the tip bodies also hold boxes: name the tip meshes
            ("if", {"geom": "if_tip"}),
            ("mf", {"geom": "mf_tip"}),
            ("rf", {"geom": "rf_tip"}),
            ("th", {"geom": "th_tip"}),
        ],
    ),
    "wonik_allegro": (
        "right_hand.xml",
        [  # unnamed capsules on their own bodies
            ("ff", {"body": "ff_tip"}),
            ("mf", {"body": "mf_tip"}),
            ("rf", {"body": "rf_tip"}),
            ("th", {"body": "th_tip"}),
        ],
    ),
}
RL = robot.RL_SKIN  # the bench's rl preset
DEPTH_M = 1.5e-3  # each plate starts this far into its fingertip
PLATE_HALF_M = (5e-3, 5e-3, 2e-3)
PLATE_MASS_KG = 0.01
PUSH_N = 0.5  # each plate's push: MuJoCo's normal force on its pad once settled


def mujoco_normal_n(model: mujoco.MjModel, data: mujoco.MjData, geom: int) -> float:
    """MuJoCo's normal contact force on `geom` (N), summed over its contacts."""
    total, f = 0.0, np.zeros(6)
    for i in range(data.ncon):
        if geom in data.contact[i].geom:
            mujoco.mj_contactForce(model, data, i, f)
            total += f[0]
    return total


def pressed_hand(
    spec: mujoco.MjSpec,
    tips,
    depth_m: float = DEPTH_M,
    push_n: float = PUSH_N,
    skin: dict | None = None,
):
    """(model, data, labels): start a plate depth_m into each fingertip pad
    of `tips` ((label, {"body"|"geom": name}) pairs), pushed into it by push_n
    along the pad's normal (a slide joint and a motor), the hand held at
    qpos0 (position servos); skin: attach() attributes for a skin on each
    pad (merged over the RL preset), or None for the bare hand."""
    spec.option.gravity = [0, 0, 0]
    model = spec.compile()
    data = mujoco.MjData(model)
    start_pose(model, data)
    mujoco.mj_kinematics(model, data)
    pads = []
    for label, where in tips:
        if "geom" in where:
            g = model.geom(where["geom"]).id
        else:  # the body's colliding geom reaching farthest along its pad side
            b = model.body(where["body"]).id
            ids = range(model.body_geomadr[b], model.body_geomadr[b] + model.body_geomnum[b])
            colliding = [i for i in ids if model.geom_contype[i] or model.geom_conaffinity[i]]
            g = colliding[0]
        facing = robot.flexion_facing(model, g)
        if "body" in where and len(colliding) > 1:  # as attach picks, along this side
            n = robot.geom_written_xmat(model, data, g) @ facing
            g = max(colliding, key=lambda i: robot.geom_reach_m(model, data, i, n))
            facing = robot.flexion_facing(model, g)
        n = robot.geom_written_xmat(model, data, g) @ facing  # world, out of the pad
        reach = robot.geom_reach_m(model, data, g, n)  # the pad's farthest point along n
        centre = data.geom_xpos[g] + n * (reach - data.geom_xpos[g] @ n - depth_m)
        centre = centre + n * PLATE_HALF_M[2]
        x = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
        x /= np.linalg.norm(x)
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.column_stack([x, np.cross(n, x), n]).ravel())
        # a plate on a slide joint along n, pushed into the pad by a motor
        plate = spec.worldbody.add_body(name=f"plate_{label}", pos=centre, quat=quat)
        plate.add_joint(
            name=f"plate_{label}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1], damping=2.0
        )
        plate.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=PLATE_HALF_M, mass=PLATE_MASS_KG)
        spec.add_actuator(
            name=f"push_{label}",
            target=f"plate_{label}",
            trntype=mujoco.mjtTrn.mjTRN_JOINT,
            gear=[-1, 0, 0, 0, 0, 0],  # the plate's -z: into the pad
        )
        if "body" in where and len(colliding) > 1:  # the picked geom itself (maybe unnamed)
            where = {"geom": spec.body(where["body"]).geoms[g - model.body_geomadr[b]]}
        pads.append((label, where, facing))
    if skin is not None:
        attrs = dict(RL, outputs="spikes force coverage")
        attrs.update(skin)
        for label, where, facing in pads:
            mjtouch.attach(spec, **where, name=f"skin_{label}", facing=facing, **attrs)
    model = spec.compile()
    data = mujoco.MjData(model)
    start_pose(model, data)
    hold_pose(model, data)
    for label, _, _ in pads:
        data.ctrl[model.actuator(f"push_{label}").id] = push_n
    return model, data, [label for label, _, _ in pads]


def press_fingertips(
    spec: mujoco.MjSpec,
    tips,
    steps: int = 300,
    depth_m: float = DEPTH_M,
    push_n: float = PUSH_N,
    **skin,
) -> list[dict]:
    """Press each fingertip of `tips` with a plate (pressed_hand, a skin on
    each pad) and step; per skin: MuJoCo's normal force on its geom, the
    skin's normal force, the coverage share and the spike count over the run
    (mean forces over the last half of the run)."""
    model, data, labels = pressed_hand(spec, tips, depth_m, push_n, skin)
    layouts = mjtouch.layouts(model)
    rows = {label: dict(tip=label, mujoco_n=0.0, skin_n=0.0, spikes=0) for label in labels}
    carried = {label: 0.0 for label in rows}
    half = steps // 2
    for k in range(steps):
        mujoco.mj_step(model, data)
        for label in rows:
            lay = layouts[f"skin_{label}"]
            rows[label]["spikes"] += int(lay.block(data.sensordata, "spikes").sum())
            if k < half:
                continue
            cov = lay.block(data.sensordata, "coverage")
            rows[label]["mujoco_n"] += cov[1] / (steps - half)
            rows[label]["skin_n"] += lay.block(data.sensordata, "force")[0] / (steps - half)
            carried[label] += cov[0] * cov[1] / (steps - half)
    for label, row in rows.items():
        g = model.sensor(f"skin_{label}").objid[0]
        row["geom"] = model.geom(g).name
        row["mujoco_now_n"] = mujoco_normal_n(model, data, g)
        row["coverage"] = carried[label] / row["mujoco_n"] if row["mujoco_n"] > 0 else 1.0
    return list(rows.values())


def start_pose(model: mujoco.MjModel, data: mujoco.MjData) -> None:
    """qpos0 clipped into each limited hinge and slide joint's range (the
    Allegro's thumb base has qpos0 0 outside its range: its servo would
    swing the thumb away from its plate)."""
    hinge_slide = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    for j in range(model.njnt):
        if model.jnt_limited[j] and int(model.jnt_type[j]) in hinge_slide:
            a = model.jnt_qposadr[j]
            data.qpos[a] = np.clip(model.qpos0[a], *model.jnt_range[j])


def hold_pose(model: mujoco.MjModel, data: mujoco.MjData) -> None:
    """Position servos hold the current pose: each joint actuator's control
    is its joint's position (tendon actuators: the tendon's length)."""
    mujoco.mj_forward(model, data)
    for a in range(model.nu):
        t = model.actuator_trnid[a, 0]
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT:
            data.ctrl[a] = data.qpos[model.jnt_qposadr[t]]
        elif model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_TENDON:
            data.ctrl[a] = data.ten_length[t]
    lo, hi = model.actuator_ctrlrange.T
    limited = model.actuator_ctrllimited.astype(bool)
    data.ctrl[limited] = np.clip(data.ctrl[limited], lo[limited], hi[limited])


def print_rows(hand: str, rows: list[dict]) -> None:
    print(f"{hand}: skin normal force vs MuJoCo's on the fingertip geom (mean, last half)")
    print(
        f"  {'tip':4s} {'geom':22s} {'MuJoCo N':>9s} {'skin N':>9s} {'coverage':>9s} {'spikes':>7s}"
    )
    for r in rows:
        print(
            f"  {r['tip']:4s} {r['geom']:22s} {r['mujoco_n']:9.4f} {r['skin_n']:9.4f} "
            f"{r['coverage']:9.3f} {r['spikes']:7d}"
        )


def time_hand(make_spec, tips, steps: int, repeats: int, settle_steps: int = 100) -> dict:
    """Thread CPU per mj_step (us) of the pressed hand, bare and with an RL
    skin on each pad, timed interleaved after settle_steps: per row, every
    step's time (repeats x steps). make_spec() returns a fresh MjSpec."""
    rows = {"bare": None, "rl skins": {}}
    hands = {}
    for k, skin in rows.items():
        model, data, _ = pressed_hand(make_spec(), tips, skin=skin)
        for _ in range(settle_steps):
            mujoco.mj_step(model, data)
        hands[k] = (model, data)
    times = {k: [] for k in rows}
    for _ in range(repeats):
        for k, (model, data) in hands.items():
            times[k].append(step_cpu_us(model, data, steps))
    out = {k: np.concatenate(v) for k, v in times.items()}
    out["timestep_s"] = hands["bare"][0].opt.timestep
    return out


def print_times(hand: str, n_tips: int, t: dict) -> None:
    lo = {k: float(np.min(t[k])) for k in ("bare", "rl skins")}
    mid = {k: float(np.median(t[k])) for k in ("bare", "rl skins")}
    print(
        f"{hand}: {n_tips} tips pressed, timestep {t['timestep_s'] * 1e3:g} ms; "
        "thread CPU per mj_step, us (min, median)"
    )
    for k in lo:
        print(f"  {k:9s} {lo[k]:8.1f} {mid[k]:8.1f}   x bare {lo[k] / lo['bare']:6.2f} "
              f"{mid[k] / mid['bare']:6.2f}")  # fmt: skip


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("menagerie", type=pathlib.Path, help="a local clone of mujoco_menagerie")
    p.add_argument("--hands", nargs="+", default=list(HANDS), choices=list(HANDS))
    p.add_argument("--steps", type=int, default=300)
    p.add_argument(
        "--time", action="store_true",
        help="also time each hand pressed, bare and with RL skins (interleaved)",
    )  # fmt: skip
    p.add_argument("--repeats", type=int, default=5, help="timed repeats of --steps (--time)")
    args = p.parse_args(argv)
    if args.steps < 1 or args.repeats < 1:
        p.error(f"--steps {args.steps}, --repeats {args.repeats}: each must be >= 1")
    for hand in args.hands:
        xml, tips = HANDS[hand]
        path = args.menagerie / hand / xml
        if not path.is_file():
            raise SystemExit(f"{path} is not a file: give the mujoco_menagerie folder")
        print_rows(hand, press_fingertips(mujoco.MjSpec.from_file(str(path)), tips, args.steps))
        if args.time:
            t = time_hand(
                functools.partial(mujoco.MjSpec.from_file, str(path)),
                tips,
                args.steps,
                args.repeats,
            )
            print_times(hand, len(tips), t)


if __name__ == "__main__":
    main()
