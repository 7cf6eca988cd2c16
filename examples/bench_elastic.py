"""The `elastic` contact solve, old against new, in one process (a benchmark,
not a test).

    python examples/bench_elastic.py [--steps 200] [--rounds 5]

models/slide_grating.xml and slide_flat.xml with pressure="elastic", each
with contact_solver="pk" (Polonsky & Keer, warm-started from the last step:
the solver before #13) and "pcg" (preconditioned CG, extrapolated warm
start), the compliance FFTs in double (elastic_precision="double", the
reference arithmetic) and, for pcg, in float (the default). Every configuration starts from one settled sliding state (the press
and a lead-in simulated without the plugin). Prints per configuration:
- CG iterations per step (median, max) over the sliding steps, and the most
  common FFT grid of the solve (set by the solve box, pipeline/warm_start.cc);
- errors against a tight reference (pk, tolerance 1e-8) over the same steps:
  pressure relative RMS (all steps pooled), and the largest indentation-depth
  difference (the force block's depth, m; its forces are MuJoCo's by
  construction);
- us/step (process CPU time) of stages 1-2 (outputs="force") and of the full
  pipeline (default outputs), min and median over interleaved rounds, and the pk / pcg ratios;
  the winkler model in the same rounds as a yardstick of the machine's load;
- pcg float (stages 1-2, full) and the Winkler full step with `threads` 1
  and --threads (default 2): process CPU and wall time per step, min and
  median, the wall ratio, and a yardstick of the
  cores free meanwhile (two numpy loops on two threads against one after
  the other: 2.0 on an idle 2-core machine, ~1.0 when another process holds
  a core; the `threads` speedup can reach at most that).
"""

from __future__ import annotations

import argparse
import threading
import time

import mujoco
import numpy as np

from mjtouch import bench
from mjtouch.bench.configs import LEAD_IN_S
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

SCENES = ("slide_grating", "slide_flat")
# label: skin attributes
SOLVERS = {
    "pk": dict(contact_solver="pk", elastic_precision="double"),
    "pcg double": dict(contact_solver="pcg", elastic_precision="double"),
    "pcg float": dict(contact_solver="pcg", elastic_precision="float"),
}
_PHYSICS = int(mujoco.mjtState.mjSTATE_FULLPHYSICS) & ~int(mujoco.mjtState.mjSTATE_PLUGIN)
_FULL = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)


def settled(name: str):
    """(physics state, qacc warm start) after the press and LEAD_IN_S of sliding."""
    m = scenes.remove_skin(scenes.shipped_scene_spec(name)).compile()
    d = mujoco.MjData(m)
    for row in scenes.controls(scenes.Protocol(), LEAD_IN_S):
        d.ctrl[:] = row
        mujoco.mj_step(m, d)
    state = np.empty(mujoco.mj_stateSize(m, _PHYSICS))
    mujoco.mj_getState(m, d, state, _PHYSICS)
    return state, d.qacc_warmstart.copy()


def make_run(name: str, start, nstep: int, **skin) -> bench.Run:
    m = scenes.shipped_scene_spec(name, **{"pressure": "elastic", **skin}).compile()
    d = mujoco.MjData(m)
    mujoco.mj_setState(m, d, start[0], _PHYSICS)
    full = np.empty(mujoco.mj_stateSize(m, _FULL))
    mujoco.mj_getState(m, d, full, _FULL)
    return bench.Run(m, full, start[1], bench.slide_ctrl(scenes.Protocol(), nstep))


def accuracy(name: str, start, steps: int) -> dict:
    """Iterations and errors of each solver against the tight reference."""
    out = {}
    traces = {}
    for label, skin in (
        ("ref", dict(contact_solver="pk", tolerance="1e-8", elastic_precision="double")),
        *SOLVERS.items(),
    ):
        run = make_run(name, start, steps, outputs="force pressure", **skin)
        layout = SkinLayout.from_model(run.model)
        mujoco.mj_setState(run.model, run.data, run.state0, _FULL)
        run.data.qacc_warmstart[:] = run.warm
        run.data.ctrl[:] = run.ctrl[0]
        p, depth, its, grids = [], [], [], []
        for _ in range(steps):
            mujoco.mj_step(run.model, run.data)
            p.append(layout.block(run.data.sensordata, "pressure").copy())
            depth.append(layout.block(run.data.sensordata, "force")[3])
            ev = layout.last_evaluation(run.data)
            its.append(ev["elastic_iterations"])
            grids.append(ev["elastic_fft_size"])
        traces[label] = (np.array(p), np.array(depth), np.array(its))
        if label in SOLVERS:
            out[label + "_grid"] = max(set(grids), key=grids.count)
    p_ref, d_ref, _ = traces["ref"]
    for s in SOLVERS:
        p, d, its = traces[s]
        out[s] = dict(
            iterations_median=float(np.median(its)),
            iterations_max=int(its.max()),
            pressure_rms_rel=float(np.sqrt(((p - p_ref) ** 2).sum() / (p_ref**2).sum())),
            depth_max_abs_m=float(np.abs(d - d_ref).max()),
            fft_grid=out[s + "_grid"],
        )
    out["ref_iterations_median"] = float(np.median(traces["ref"][2]))
    return out


def timing(name: str, start, steps: int, rounds: int) -> dict:
    # winkler (the fast model) in the same rounds: a yardstick for the
    # machine's load, against the quiet-machine figures
    runs = {
        (s, stage): make_run(
            name,
            start,
            steps,
            **({"pressure": "winkler"} if s == "winkler" else SOLVERS[s]),
            **({"outputs": "force"} if stage == "stages 1-2" else {}),
        )
        for s in (*SOLVERS, "winkler")
        for stage in ("stages 1-2", "full")
    }
    times = {k: [] for k in runs}
    last = {}
    for _ in range(rounds):  # interleaved: a load change hits every configuration alike
        for k, run in runs.items():
            # process CPU time: on a shared, oversubscribed machine wall time
            # also counts the time the process waits for a core
            t0 = time.process_time()
            _, sd = run.step(steps)
            times[k].append((time.process_time() - t0) / steps * 1e6)
            if k in last and not np.array_equal(last[k], sd):
                raise RuntimeError(f"{name} {k}: repeated runs differ")
            last[k] = sd
    return {k: (min(v), float(np.median(v))) for k, v in times.items()}


def free_cores_yardstick(n: int = 2, size: int = 4_000_000) -> float:
    """Wall time of n numpy loops (the GIL released) one after the other over
    their time on n threads: how many cores this process gets right now."""
    a = np.random.default_rng(0).random(size)

    def work():
        for _ in range(3):
            np.cumsum(a)

    t0 = time.perf_counter()
    for _ in range(n):
        work()
    serial = time.perf_counter() - t0
    ts = [threading.Thread(target=work) for _ in range(n)]
    t0 = time.perf_counter()
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    return serial / (time.perf_counter() - t0)


def thread_timing(name: str, start, steps: int, rounds: int, threads: int) -> dict:
    """pcg float (and the Winkler full step) with threads 1 and `threads`:
    (cpu, wall) us/step lists per (threads, stage), and the free-cores
    yardstick per round."""
    runs = {
        (t, stage): make_run(
            name,
            start,
            steps,
            **SOLVERS["pcg float"],
            threads=str(t),
            **({"outputs": "force"} if stage == "stages 1-2" else {}),
        )
        for t in (1, threads)
        for stage in ("stages 1-2", "full")
    }
    runs.update(
        {
            (t, "winkler"): make_run(name, start, steps, pressure="winkler", threads=str(t))
            for t in (1, threads)
        }
    )
    out = {k: [] for k in runs}
    yard = []
    for _ in range(rounds):
        yard.append(free_cores_yardstick(threads))
        for k, run in runs.items():
            t0, c0 = time.perf_counter(), time.process_time()
            run.step(steps)
            out[k].append(
                ((time.process_time() - c0) / steps * 1e6, (time.perf_counter() - t0) / steps * 1e6)
            )
    return out, yard


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200, help="sliding steps per run")
    ap.add_argument("--rounds", type=int, default=5, help="interleaved timing rounds")
    ap.add_argument("--threads", type=int, default=2, help="the `threads` compared with 1")
    args = ap.parse_args()
    for name in SCENES:
        start = settled(name)
        acc = accuracy(name, start, args.steps)
        t = timing(name, start, args.steps, args.rounds)
        print(
            f"{name} ({args.steps} steps; reference pk at tolerance 1e-8: "
            f"{acc['ref_iterations_median']:.0f} median iterations)"
        )
        for s in SOLVERS:
            a = acc[s]
            print(
                f"  {s:10s} iterations median {a['iterations_median']:5.1f} max "
                f"{a['iterations_max']:3d}  pressure rms rel {a['pressure_rms_rel']:.2e}  "
                f"depth max |diff| {a['depth_max_abs_m']:.2e} m  FFT grid {a['fft_grid'][0]}x{a['fft_grid'][1]}"
            )
            for stage in ("stages 1-2", "full"):
                lo, med = t[s, stage]
                print(f"             {stage:10s} us/step min {lo:8.1f} median {med:8.1f}")
        for stage in ("stages 1-2", "full"):
            lo, med = t["winkler", stage]
            print(f"  winkler {stage:10s} us/step min {lo:8.1f} median {med:8.1f}")
        for base in ("pk", "pcg double"):
            for stage in ("stages 1-2", "full"):
                r_min = t[base, stage][0] / t["pcg float", stage][0]
                r_med = t[base, stage][1] / t["pcg float", stage][1]
                print(
                    f"  ratio {base} / pcg float {stage:10s}: min {r_min:.2f}x  median {r_med:.2f}x"
                )
        print(
            f"  iterations pk / pcg float: "
            f"{acc['pk']['iterations_median'] / acc['pcg float']['iterations_median']:.2f}x"
        )
        tt, yard = thread_timing(name, start, args.steps, args.rounds, args.threads)
        print(
            f"  pcg float, threads 1 / {args.threads} (free-cores yardstick min "
            f"{min(yard):.2f} median {np.median(yard):.2f} max {max(yard):.2f})"
        )
        for stage in ("stages 1-2", "full", "winkler"):
            for t in (1, args.threads):
                c = [a for a, _ in tt[t, stage]]
                w = [b for _, b in tt[t, stage]]
                print(
                    f"    threads {t} {stage:10s} us/step cpu min {min(c):7.1f} median "
                    f"{np.median(c):7.1f}  wall min {min(w):7.1f} median {np.median(w):7.1f}"
                )
            w1 = [b for _, b in tt[1, stage]]
            wn = [b for _, b in tt[args.threads, stage]]
            print(
                f"    wall threads 1 / {args.threads} {stage:10s}: min {min(w1) / min(wn):.2f}x  "
                f"median {np.median(w1) / np.median(wn):.2f}x"
            )


if __name__ == "__main__":
    main()
