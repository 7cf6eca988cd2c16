"""Per-step cost of each pressure model at 64^2, 128^2 and 256^2 taxels (a
benchmark, not a test).

    python examples/bench_pressure.py [--steps 200] [--elastic-steps 30]

The default sliding scene (ridged fingertip, 0.5 N, 25 mm/s over the 1 mm
grating), taxels at 0.1 mm, the skin's outputs reduced to `force` so that
only stages 1-2 run (surface rendering and the pressure model). Every
configuration starts from the same settled, sliding state
(mjtouch.bench.timing.States) and is timed as the minimum over rounds of
`mj_step(nstep)`; in the same run: the bare MuJoCo step (plugin removed) and
MuJoCo's native `tactile` sensor on a mesh with as many vertices as taxels.
Prints us/step and the ratios to both baselines.
"""

from __future__ import annotations

import argparse

from mjtouch import bench
from mjtouch.scene import scenes

GRIDS = (64, 128, 256)
MODELS = ("contacts", "winkler", "elastic")


def measure(steps: int = 200, elastic_steps: int = 30, rounds: int = 3) -> list[dict]:
    texture = scenes.Texture(period_m=1e-3)
    states = bench.States(texture)
    runs = {}
    for n in GRIDS:
        for model in MODELS:
            tip, proto = bench.scene_parts(
                {"nx": n, "pitch_m": 1e-4, "skin.pressure": model, "skin.outputs": "force"}
            )
            m = scenes.build_model(tip, texture, proto)
            state, warm = states.initial(m)
            nstep = elastic_steps if model == "elastic" else steps
            runs[n, model] = (bench.Run(m, state, warm, bench.slide_ctrl(proto, nstep)), nstep)
        tip, proto = bench.scene_parts({"nx": n, "pitch_m": 1e-4})
        native = bench.add_native_tactile(
            scenes.scene_spec(tip, texture, proto), n, 1e-4, tip.semi_axes_m
        ).compile()
        state, warm = states.initial(native)
        runs[n, "native tactile"] = (
            bench.Run(native, state, warm, bench.slide_ctrl(proto, steps)),
            steps,
        )
    bare = bench.bare_model(scenes.Fingertip(), texture, scenes.Protocol())
    state, warm = states.initial(bare)
    runs[0, "bare"] = (
        bench.Run(bare, state, warm, bench.slide_ctrl(scenes.Protocol(), steps)),
        steps,
    )
    best = {k: float("inf") for k in runs}
    for _ in range(rounds):  # interleaved rounds: a load change hits every row alike
        for k, (run, nstep) in runs.items():
            run.step(min(5, nstep))  # warm
            wall, _ = run.step(nstep)
            best[k] = min(best[k], wall / nstep * 1e6)
    rows = []
    for n in GRIDS:
        for model in MODELS:
            us = best[n, model]
            rows.append(
                {
                    "taxels": n * n,
                    "model": model,
                    "us_per_step": us,
                    "over_bare": us / best[0, "bare"],
                    "over_native_tactile": us / best[n, "native tactile"],
                    "native_tactile_us_per_step": best[n, "native tactile"],
                    "bare_us_per_step": best[0, "bare"],
                }
            )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200, help="timed steps (contacts, winkler)")
    ap.add_argument("--elastic-steps", type=int, default=30, help="timed steps (elastic)")
    args = ap.parse_args()
    rows = measure(args.steps, args.elastic_steps)
    print(f"bare MuJoCo step {rows[0]['bare_us_per_step']:.2f} us")
    print(
        f"{'taxels':>7s} {'model':9s} {'us/step':>9s} {'x bare':>8s} {'x native':>9s} "
        f"{'native us':>10s}"
    )
    for r in rows:
        print(
            f"{r['taxels']:7d} {r['model']:9s} {r['us_per_step']:9.1f} {r['over_bare']:8.1f} "
            f"{r['over_native_tactile']:9.2f} {r['native_tactile_us_per_step']:10.1f}"
        )


if __name__ == "__main__":
    main()
