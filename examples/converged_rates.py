"""Population rates of the default slide against a converged reference, on
textures, periods and speeds the tests do not use.

    python examples/converged_rates.py                 # ~15-30 min on 2 cores
    python examples/converged_rates.py --cases grating --duration 0.5
    python examples/converged_rates.py --json
    python examples/converged_rates.py --cost          # ~1 min: step cost only

Per case, the slide (`python -m mjtouch slide --json` with the case's
options) runs with the default skin (128 x 0.1 mm, `elastic` with
`grid_cycle` 4), with the taxel grid alone (`grid_cycle` 1), and with the
reference `--nx 256 --pitch 5e-5 --grid-shift`; `--finer` adds `--nx 341 --pitch
3.75e-5 --grid-shift` to show that the reference itself has converged (the
goal: the two references within 5%). Printed: SA1 / RA / PC population rates
and each one's relative error against the reference (goal: 10% SA1 and RA,
15% PC).

--cost: the step cost of the default (`grid_cycle` 4) against the taxel
grid alone (`grid_cycle` 1) on the default slide (`python -m mjtouch
slide`, the goal: at most 1.2x the one grid's), both started from
their own settled sliding state and stepped in interleaved rounds (process
CPU time, so a shared machine's waits do not count): us per step (min and
median over the rounds), their ratios, and the mean CG iterations per step."""

import argparse
import json
import sys
import time

import mujoco
import numpy as np

from mjtouch.experiments import rollout, slide
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

CASES = {
    "grating": {"texture": "grating", "period_m": 0.7e-3, "speed_m_s": 0.035},
    "random": {
        "texture": "random",
        "rms_m": 2.5e-5,
        "corr_length_m": 8e-5,
        "seed": 5,
        "speed_m_s": 0.04,
    },
    "dots": {
        "texture": "dots",
        "dot_spacing_m": 1.8e-3,
        "dot_radius_m": 0.45e-3,
        "speed_m_s": 0.03,
    },
}
SETTINGS = {
    "default": {},
    "one grid": {"grid_cycle": 1},
    "ref 50 um": {"nx": 256, "pitch_m": 5e-5, "grid_shift": True},
    "ref 37.5 um": {"nx": 341, "pitch_m": 3.75e-5, "grid_shift": True},
}
CLASSES = ("SA1", "RA", "PC")
BOUND = {"SA1": 0.10, "RA": 0.10, "PC": 0.15}


def rates(case: str, setting: str, duration_s: float) -> dict:
    p = slide.from_mapping({**CASES[case], **SETTINGS[setting], "duration_s": duration_s})
    out = slide.run(p)
    return {"rates_hz": out.summary["rates_hz"], "wall_s": out.summary["wall_s"]}


def step_cost(settings=("default", "one grid"), steps: int = 300, rounds: int = 7) -> dict:
    """Per setting: us/step (min, median over rounds after the first) and
    mean CG iterations per step (the first round), on the default slide."""
    full = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)
    runs = {}
    for s in settings:
        p = slide.from_mapping(SETTINGS[s])
        texture, _, _ = p.texture_spec()
        model = scenes.build_model(p.fingertip(), texture, p.protocol())
        data = mujoco.MjData(model)
        ctrl = scenes.controls(p.protocol(), p.duration_s)
        settle = round(p.protocol().press_s / p.dt_s) + round(rollout.SETTLE_S / p.dt_s)
        for c in ctrl[:settle]:
            data.ctrl[:] = c
            mujoco.mj_step(model, data)
        state = np.empty(mujoco.mj_stateSize(model, full))
        mujoco.mj_getState(model, data, state, full)
        runs[s] = (model, data, state, data.qacc_warmstart.copy(), ctrl[settle : settle + steps])
    times = {s: [] for s in settings}
    iterations = {}
    for r in range(rounds + 1):  # interleaved: a load change hits every setting alike
        for s, (model, data, state, warm, ctrl) in runs.items():
            mujoco.mj_setState(model, data, state, full)
            data.qacc_warmstart[:] = warm
            if r == 0:  # (the diagnostics' calls are not timed)
                layout, its = SkinLayout.from_model(model), []
                for c in ctrl:
                    data.ctrl[:] = c
                    mujoco.mj_step(model, data)
                    its.append(layout.last_evaluation(data)["elastic_iterations"])
                iterations[s] = float(np.mean(its))
                continue
            t0 = time.process_time()
            for c in ctrl:
                data.ctrl[:] = c
                mujoco.mj_step(model, data)
            times[s].append((time.process_time() - t0) / len(ctrl) * 1e6)
    return {
        s: {"us_min": min(t), "us_median": float(np.median(t)), "iterations": iterations[s]}
        for s, t in times.items()
    }


def print_cost(cost: dict) -> None:
    base = cost["one grid"]  # the ratios: against the taxel grid alone
    for s, c in cost.items():
        print(
            f"{s:10s} {c['us_min']:7.0f} us/step min ({c['us_min'] / base['us_min']:.2f}x)  "
            f"{c['us_median']:7.0f} median ({c['us_median'] / base['us_median']:.2f}x)  "
            f"CG iterations {c['iterations']:.2f}"
        )


def rel(a: float, b: float) -> float:
    return abs(a - b) / b if b > 0 else float("inf")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default=",".join(CASES), help="comma-separated: " + " ".join(CASES))
    ap.add_argument("--duration", type=float, default=0.5, help="sliding time per run (s)")
    ap.add_argument("--finer", action="store_true", help="also the 37.5 um reference")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--cost", action="store_true", help="only the step cost (see above)")
    ap.add_argument("--rounds", type=int, default=7, help="--cost: timed rounds")
    a = ap.parse_args(argv)
    if a.cost:
        cost = step_cost(rounds=a.rounds)
        if a.json:
            print(json.dumps(cost))
        else:
            print_cost(cost)
        return 0
    settings = ["default", "one grid", "ref 50 um"] + (["ref 37.5 um"] if a.finer else [])
    rows = {}
    for case in a.cases.split(","):
        if case not in CASES:
            ap.error(f"unknown case {case!r}; valid: {' '.join(CASES)}")
        rows[case] = {s: rates(case, s, a.duration) for s in settings}
    if a.json:
        print(json.dumps(rows))
        return 0
    for case, runs in rows.items():
        ref = runs["ref 50 um"]["rates_hz"]
        print(f"{case}: {CASES[case]}")
        for s, r in runs.items():
            cells = "  ".join(
                f"{c} {r['rates_hz'][c]:6.1f} ({100 * rel(r['rates_hz'][c], ref[c]):4.1f}%)"
                for c in CLASSES
            )
            ok = all(rel(r["rates_hz"][c], ref[c]) <= BOUND[c] for c in CLASSES)
            print(f"  {s:12s} {cells}  {'within' if ok else 'OUTSIDE'}  [{r['wall_s']:.0f} s]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
