"""Press force control against the plain motor, in the same run (issue 14).

    python examples/force_control.py            # table
    python examples/force_control.py --json

For each target force, the time until the pad's normal force stays within 5%
of it (landing, from 0.3 mm above the plate), and for a 50 ms ramp from a
0.05 N preload to 0.5 N, the force at the ramp's end and the worst error over
the ramp and hold: `stimuli.press_force_controls` (closed loop, replayed open
loop) against the motor driven with the target itself (what
`scenes.controls` does). Bare MuJoCo (the skin does not change the physics).
"""

from __future__ import annotations

import argparse
import json

import mujoco
import numpy as np

from mjtouch.experiments import stimuli
from mjtouch.scene import scenes


def motor_force(bare: mujoco.MjModel, target_n: np.ndarray) -> np.ndarray:
    pad = mujoco.mj_name2id(bare, mujoco.mjtObj.mjOBJ_GEOM, "pad")
    d = mujoco.MjData(bare)
    out = np.empty(target_n.size)
    for k, f in enumerate(target_n):
        d.ctrl[:] = [0.0, -f]
        mujoco.mj_step(bare, d)
        out[k] = stimuli.contact_normal_force(bare, d, pad)
    return out


def landed_s(force: np.ndarray, target: float, dt: float) -> float:
    bad = np.nonzero(np.abs(force - target) > 0.05 * target)[0]
    if bad.size == 0:
        return 0.0
    return float("inf") if bad[-1] == force.size - 1 else float((bad[-1] + 1) * dt)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--forces", type=float, nargs="+", default=[0.003, 0.01, 0.1, 1.0, 5.0])
    p.add_argument("--duration", type=float, default=0.6, help="landing run (s)")
    p.add_argument("--dt", type=float, default=1e-4)
    p.add_argument("--json", action="store_true")
    a = p.parse_args(argv)
    spec = stimuli.vibrating_plate_spec(timestep_s=a.dt)
    bare = scenes.remove_skin(spec.copy()).compile()
    landing = []
    for f in a.forces:
        target = np.full(int(round(a.duration / a.dt)), f)
        closed = stimuli.press_force_controls(spec, target).force_n
        landing.append(
            dict(
                force_n=f,
                closed_s=landed_s(closed, f, a.dt),
                motor_s=landed_s(motor_force(bare, target), f, a.dt),
            )
        )
    t = np.arange(int(round(0.3 / a.dt))) * a.dt
    target = np.interp(t, [0, 0.1, 0.15, 1], [0.05, 0.05, 0.5, 0.5])
    end = int(round(0.15 / a.dt)) - 1
    after = t >= 0.1
    ramp = {}
    for name, force in (
        ("closed", stimuli.press_force_controls(spec, target).force_n),
        ("motor", motor_force(bare, target)),
    ):
        ramp[name] = dict(
            end_fraction=float(force[end] / target[end]),
            max_error_fraction=float(np.abs(force - target)[after].max() / 0.5),
        )
    out = dict(landing=landing, ramp_50ms_0p05_to_0p5_n=ramp, dt_s=a.dt)
    if a.json:
        print(json.dumps(out))
        return 0
    print("landing within 5% (ms):  force (N)   closed loop   motor")
    for r in landing:
        print(f"  {r['force_n']:10.3g} {r['closed_s'] * 1e3:12.1f} {r['motor_s'] * 1e3:8.1f}")
    print("50 ms ramp 0.05 -> 0.5 N: force at the ramp's end / target, worst error / 0.5 N")
    for k, r in ramp.items():
        print(f"  {k:7s} {r['end_fraction']:.3f}  {r['max_error_fraction']:.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
