"""The cost of shear="partial" (a benchmark, not a test).

    python examples/bench_partial_slip.py [--steps 200] [--rounds 5]
    python examples/bench_partial_slip.py --ab LIB_A LIB_B [--rounds 5]

models/slide_grating.xml and slide_flat.xml (nx 128, the default skin) with
pressure winkler and elastic, each with no shear (-normal), the shear in
full slip (the default) and partial, in two cases, each started from one
state simulated without the plugin:
- slide: steady sliding (the press and a lead-in of sliding), the slide
  control held; MuJoCo's friction is at mu P, so partial slip is full slip;
- ramp: from the end of the press, the slide speed ramped from 0 to 13 mm/s
  over the steps: the tangential force rises to ~0.85 mu P (partial slip,
  the stick zone shrinking).
Prints per scene and case:
- us per mj_step (process CPU time), min and median over --rounds rounds,
  the configurations interleaved within each round, and the partial / full
  slip and partial / normal-only ratios of the min and of the median (the
  issue's goals: winkler <= 1.2x, elastic <= 1.5x the normal-only step);
- for the partial rows, what the run met: Q / (mu P) and the stuck share
  (median over the steps), and their accuracy against a tight tangential and
  normal solve (tolerance 1e-10) over the same steps: the largest stuck-share
  difference and the receptor stress's relative RMS difference (all steps
  pooled); the full-slip elastic row's own stress difference at that
  tolerance, for scale; and stage 3's split sum (the full-slip part and
  the coarse correction, stress_fold.h) against the exact sums
  (stress_method="fft"), with the full-slip stress's difference from the
  exact partial one, the effect the correction carries, for scale.
--ab runs the timing in subprocesses alternating between two plugin
libraries (MJTOUCH_PLUGIN_PATH), one round each at a time, and prints both
libraries' tables and the B / A ratios.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

import mujoco
import numpy as np

from mjtouch import bench
from mjtouch.bench.configs import LEAD_IN_S
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

SCENES = ("slide_flat", "slide_grating")
CASES = ("slide", "ramp")
RAMP_SPEED_M_S = 13e-3
CONFIGS = {
    "winkler-normal": dict(pressure="winkler", shear="false"),
    "winkler": dict(pressure="winkler"),
    "winkler+partial": dict(pressure="winkler", shear="partial"),
    "elastic-normal": dict(pressure="elastic", shear="false"),
    "elastic": dict(pressure="elastic"),
    "elastic+partial": dict(pressure="elastic", shear="partial"),
}
TIGHT_TOLERANCE = "1e-10"
_PHYSICS = int(mujoco.mjtState.mjSTATE_FULLPHYSICS) & ~int(mujoco.mjtState.mjSTATE_PLUGIN)
_FULL = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)


def settled(name: str, case: str):
    """(physics state, qacc warm start): after the press and LEAD_IN_S of
    sliding (slide), after the press alone (ramp)."""
    m = scenes.remove_skin(scenes.shipped_scene_spec(name)).compile()
    d = mujoco.MjData(m)
    for row in scenes.controls(scenes.Protocol(), LEAD_IN_S if case == "slide" else 0.0):
        d.ctrl[:] = row
        mujoco.mj_step(m, d)
    state = np.empty(mujoco.mj_stateSize(m, _PHYSICS))
    mujoco.mj_getState(m, d, state, _PHYSICS)
    return state, d.qacc_warmstart.copy()


def case_ctrl(case: str, nstep: int) -> np.ndarray:
    ctrl = bench.slide_ctrl(scenes.Protocol(), nstep)
    if case == "ramp":
        ctrl[:, 0] = RAMP_SPEED_M_S * np.arange(nstep) / nstep
    return ctrl


class Run:
    """A configuration stepped from its start state under the case's ctrl."""

    def __init__(self, name: str, case: str, start, nstep: int, **skin):
        self.model = scenes.shipped_scene_spec(name, **skin).compile()
        self.data = mujoco.MjData(self.model)
        mujoco.mj_setState(self.model, self.data, start[0], _PHYSICS)
        self.state0 = np.empty(mujoco.mj_stateSize(self.model, _FULL))
        mujoco.mj_getState(self.model, self.data, self.state0, _FULL)
        self.warm = start[1]
        self.ctrl = case_ctrl(case, nstep)

    def run(self, out: np.ndarray | None = None) -> np.ndarray:
        """Steps through the ctrl; the sensordata per step into out, if given.
        Returns the last step's sensordata."""
        m, d = self.model, self.data
        mujoco.mj_setState(m, d, self.state0, _FULL)
        d.qacc_warmstart[:] = self.warm
        for k, row in enumerate(self.ctrl):
            d.ctrl[:] = row
            mujoco.mj_step(m, d)
            if out is not None:
                out[k] = d.sensordata
        return d.sensordata.copy()


def timing(name: str, case: str, start, steps: int, rounds: int) -> dict:
    """{config: [us per step per round]} (process CPU time), interleaved."""
    runs = {k: Run(name, case, start, steps, **skin) for k, skin in CONFIGS.items()}
    times = {k: [] for k in runs}
    last = {}
    for _ in range(rounds):
        for k, run in runs.items():
            t0 = time.process_time()
            sd = run.run()
            times[k].append((time.process_time() - t0) / steps * 1e6)
            if k in last and not np.array_equal(last[k], sd):
                raise RuntimeError(f"{name} {case} {k}: repeated runs differ")
            last[k] = sd
    return times


def record(name: str, case: str, start, steps: int, **skin) -> dict:
    run = Run(name, case, start, steps, **skin)
    lay = SkinLayout.from_model(run.model)
    out = np.empty((steps, run.model.nsensordata))
    run.run(out)
    blocks = {"stress": lay.block(out, "stress"), "force": lay.block(out, "force")}
    if skin.get("shear") == "partial":
        blocks["slip"] = lay.block(out, "slip")
    return blocks


def rms_rel(a: np.ndarray, ref: np.ndarray) -> float:
    """Relative RMS difference of a from ref, all entries pooled."""
    return float(np.sqrt(((a - ref) ** 2).sum() / (ref**2).sum()))


def accuracy(name: str, case: str, start, steps: int) -> dict:
    """Per partial config: Q / mu P and stuck share (medians), largest
    stuck-share difference and stress relative RMS against the tight solve;
    for the full-slip elastic row its own stress difference at the tight
    tolerance."""
    out = {}
    for k, skin in CONFIGS.items():
        partial = skin.get("shear") == "partial"
        if skin.get("shear") == "false" or (skin["pressure"] == "winkler" and not partial):
            continue
        extra = {"outputs": "spikes stress force" + (" slip" if partial else "")}
        a = record(name, case, start, steps, **skin, **extra)
        b = record(name, case, start, steps, **skin, **extra, tolerance=TIGHT_TOLERANCE)
        row = {"stress_rms_rel": rms_rel(a["stress"], b["stress"])}
        if partial:
            # stage 3's split sum (full-slip part + coarse correction)
            # against the exact sums (FFT), and the full-slip stress for scale
            e = record(name, case, start, steps, **skin, **extra, stress_method="fft")["stress"]
            full = {**skin, "shear": "true"}
            u = record(name, case, start, steps, **full, outputs="spikes stress force")["stress"]
            row["stress_split_rms_rel"] = rms_rel(a["stress"], e)
            row["full_slip_rms_rel"] = rms_rel(u, e)
            f, slip = a["force"], a["slip"]
            touching = f[:, 0] > 0
            ratio = np.hypot(f[:, 1], f[:, 2]) / (slip[:, 1] * f[:, 0] + ~touching)
            row["q_over_mu_p"] = float(np.median(ratio[touching]))
            row["q_over_mu_p_max"] = float(ratio[touching].max())
            row["stuck_share"] = float(np.median(slip[touching, 0]))
            row["stuck_share_max_diff"] = float(np.abs(slip[:, 0] - b["slip"][:, 0]).max())
        out[k] = row
    return out


def table(times: dict) -> list[str]:
    lines = []
    for k, v in times.items():
        lines.append(f"  {k:16s} us/step min {min(v):8.1f} median {np.median(v):8.1f}")
    for base in ("winkler", "elastic"):
        b = times[base + "+partial"]
        for ref in (base, base + "-normal"):
            a = times[ref]
            lines.append(
                f"  ratio {base}+partial / {ref}: min {min(b) / min(a):.2f}x  "
                f"median {np.median(b) / np.median(a):.2f}x"
            )
    return lines


def run_ab(libs: list[str], steps: int, rounds: int) -> None:
    """One round per library at a time, alternating, in subprocesses."""
    times = {lib: {} for lib in libs}
    for r in range(rounds):
        for lib in libs if r % 2 == 0 else libs[::-1]:
            env = dict(os.environ, MJTOUCH_PLUGIN_PATH=lib)
            res = subprocess.run(
                [sys.executable, __file__, "--steps", str(steps), "--rounds", "1", "--json"],
                env=env,
                check=True,
                capture_output=True,
                text=True,
            )
            for key, t in json.loads(res.stdout.splitlines()[-1]).items():
                for k, v in t.items():
                    times[lib].setdefault(key, {}).setdefault(k, []).extend(v)
    for key in times[libs[0]]:
        print(f"{key} ({steps} steps, {rounds} alternating rounds)")
        for tag, lib in zip("AB", libs):
            print(f" {tag}: {lib}")
            print("\n".join(table(times[lib][key])))
        ta, tb = times[libs[0]][key], times[libs[1]][key]
        for k in CONFIGS:
            print(
                f"  B / A {k:16s}: min {min(tb[k]) / min(ta[k]):.2f}x  "
                f"median {np.median(tb[k]) / np.median(ta[k]):.2f}x"
            )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200, help="steps per run")
    ap.add_argument("--rounds", type=int, default=5, help="interleaved timing rounds")
    ap.add_argument("--ab", nargs=2, metavar="LIB", help="two libmjtouch.so to compare")
    ap.add_argument("--no-accuracy", action="store_true", help="timing only")
    ap.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.ab:
        run_ab([str(pathlib.Path(p).resolve()) for p in args.ab], args.steps, args.rounds)
        return
    result = {}
    for name in SCENES:
        for case in CASES:
            start = settled(name, case)
            times = timing(name, case, start, args.steps, args.rounds)
            key = f"{name} {case}"
            result[key] = times
            if args.json:
                continue
            print(f"{key} ({args.steps} steps, {args.rounds} interleaved rounds)")
            print("\n".join(table(times)))
            if args.no_accuracy:
                continue
            for k, a in accuracy(name, case, start, args.steps).items():
                line = f"  {k:16s} vs tolerance {TIGHT_TOLERANCE}: stress rms rel {a['stress_rms_rel']:.2e}"
                if "stuck_share" in a:
                    line += (
                        f"  Q/muP median {a['q_over_mu_p']:.3f} max {a['q_over_mu_p_max']:.3f}"
                        f"  stuck share median {a['stuck_share']:.3f},"
                        f" max |diff| {a['stuck_share_max_diff']:.4f}"
                        f"\n    stage 3 split vs exact sums: stress rms rel"
                        f" {a['stress_split_rms_rel']:.2e} (full slip vs exact partial:"
                        f" {a['full_slip_rms_rel']:.2e})"
                    )
                print(line)
    if args.json:
        print(json.dumps(result))


if __name__ == "__main__":
    main()
